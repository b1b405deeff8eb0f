//! A load cell's lag hidden in a measured stand log (issue 29 item 6): the shared vanderploeg
//! staircase (rpm, thrust, torque, current, voltage; `../shared/data` or
//! `$PROPID_SHARED_DATA`, skipped with a message when absent) read as `propid diagnose` reads
//! it, its thrust alone delayed and filtered (seeded draws, the first of
//! `examples/stand_lag_table.rs`): found as `sensor_lag` on the thrust, on the stand baseline,
//! its delay within a row and τ within 25 % of the injected ones on top of the clean log's own.

use propid_diagnose::file::{signals, Signals, DEFAULT_OUTPUT, OPTIONAL};
use propid_diagnose::stand::BaselineKind;
use propid_diagnose::{Diagnosis, Options};
use propid_ingest::load::{load_bytes, Request};
use propid_numerics::EffectName;
use propid_testkit::inject::{lag_column, tolerance, Injection, Samples};
use rand::rngs::StdRng;
use rand::SeedableRng;
use std::path::PathBuf;

fn vanderploeg() -> Option<Signals> {
    let root = std::env::var_os("PROPID_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"));
    let path = root.join("vanderploeg-rcbenchmark-steps/90PERCENT_2024-08-13_185523.csv");
    let Ok(bytes) = std::fs::read(&path) else {
        eprintln!(
            "skipped: {} is absent (shared dataset; set PROPID_SHARED_DATA)",
            path.display()
        );
        return None;
    };
    let outputs = [DEFAULT_OUTPUT.to_string()];
    let req = Request {
        outputs: &outputs,
        optional: &OPTIONAL,
        ..Request::default()
    };
    let file = load_bytes(path.display().to_string(), &bytes, &req).unwrap();
    Some(signals(&file, None).unwrap())
}

/// The thrust's sensor (delay, τ) of the final stand model.
fn thrust_sensor(d: &Diagnosis) -> (f64, f64) {
    let s = &d.stand.as_ref().expect("a stand diagnosis").model.sensors["thrust"];
    (s.delay_s.value.unwrap(), s.tau_s.value.unwrap())
}

#[test]
fn a_load_cells_lag_hidden_in_a_measured_stands_thrust_is_found_as_a_sensor_lag() {
    let Some(s) = vanderploeg() else {
        return;
    };
    // What the clean log shows of its thrust sensor (the stand model's figures, also where the
    // data choose the generic baseline).
    let own = s
        .diagnose(&Options {
            prefer_stand: true,
            ..Options::default()
        })
        .unwrap();
    let (d0, t0) = thrust_sensor(&own);
    let samples = Samples {
        dt_s: s.dt_s,
        t0_s: 0.0,
        u: s.u.clone(),
        y: s.y.clone(),
        voltage: None,
    };
    for seed in [1000, 1003] {
        let inj = Injection::draw(
            EffectName::SensorLag,
            &samples,
            &mut StdRng::seed_from_u64(seed),
        )
        .unwrap();
        let Injection::SensorLag { delay_s, tau_s, .. } = inj else {
            unreachable!()
        };
        let d = s
            .map_channel("thrust", |y| lag_column(y, s.dt_s, delay_s, tau_s))
            .diagnose(&Options::default())
            .unwrap();
        assert_eq!(
            d.baseline.choice.kind,
            BaselineKind::Stand,
            "#{seed}: {}",
            d.baseline.choice.why
        );
        let f = d
            .findings
            .iter()
            .find(|f| f.effect == EffectName::SensorLag && f.params["channel"] == "thrust")
            .unwrap_or_else(|| panic!("#{seed} {inj:?}: {:?}", d.findings));
        let (got_d, got_t) = (
            f.params["delay_s"].as_f64().unwrap() - d0,
            f.params["tau_s"].as_f64().unwrap() - t0,
        );
        assert!(
            (got_d - delay_s).abs() <= s.dt_s,
            "#{seed} delay {got_d} vs {delay_s}"
        );
        assert!(
            (got_t / tau_s - 1.0).abs() <= tolerance(&inj),
            "#{seed} τ {got_t} vs {tau_s}"
        );
        let names: Vec<EffectName> = d.findings.iter().map(|f| f.effect).collect();
        assert!(
            !names.contains(&EffectName::StiffnessNonlinearity),
            "{names:?}"
        );
    }
}
