//! A model file written by propid 0.1.0 (schema `propid-model/1`) still loads, simulates and
//! converts: the stored files of `tests/data/` (`diagnose --save` of a simulated multisine
//! record with a dead time, `identify --save` of `propid sim --record`'s motor stand) read by this version.

use propid_model::params::{self, Options, Record, Target};
use propid_model::simulate::{free_run, Which};
use propid_model::{ModelError, ModelFile};

const DIAGNOSE_V1: &str = include_str!("data/diagnose-v1.json");
const IDENTIFY_V1: &str = include_str!("data/identify-v1.json");

#[test]
fn a_stored_diagnose_model_loads_and_simulates() {
    let m = ModelFile::from_text(DIAGNOSE_V1).expect("the stored file loads");
    assert_eq!(m.provenance.command, "diagnose");
    let u: Vec<f64> = (0..500)
        .map(|k| 0.5 + 0.1 * (k as f64 * 0.05).sin())
        .collect();
    for which in [Which::Extended, Which::Linear] {
        let y = free_run(&m, which, &u, None, &[], 0).unwrap();
        assert!(y[0].iter().all(|v| v.is_finite()), "{which:?}");
    }
}

#[test]
fn a_stored_identify_model_loads_and_converts() {
    let m = ModelFile::from_text(IDENTIFY_V1).expect("the stored file loads");
    assert_eq!(m.provenance.command, "identify");
    assert!(m.linear.is_some() && m.stand.is_some());
    let rec = Record {
        stand: m.stand.as_ref(),
        static_map: &m.static_map,
        supply: m.supply.as_ref(),
    };
    let p = params::params(Target::Gazebo, &rec, &Options::default());
    // The simulated stand's torque is 0.012 m times its thrust.
    let k = p.iter().find(|p| p.name == "momentConstant").unwrap();
    assert!((k.value.unwrap() - 0.012).abs() < 1e-3, "{k:?}");
}

#[test]
fn the_stored_file_with_one_byte_changed_is_refused() {
    let edited = DIAGNOSE_V1.replacen("\"rows\": ", "\"rows\": 1", 1);
    assert!(matches!(
        ModelFile::from_text(&edited),
        Err(ModelError::Tampered { .. })
    ));
}
