//! `diagnose_record` on `Record`s: missing samples, a clipping sensor, and bad input (typed
//! errors, no panic).

use propid_diagnose::{self as diagnose, DiagnoseError, Options};
use propid_numerics::EffectName;
use propid_sim::effects::{Saturation, SaturationSignal};
use propid_sim::synth;
use propid_wire::record::{names, Channel, Record};

fn record(u: Vec<f64>, y: Vec<f64>, missing: Vec<bool>) -> Record {
    let ch = |name: &str, unit: &str, data| Channel::read(name, unit, data);
    Record {
        dt_s: synth::DT_S,
        t0_s: 0.0,
        channels: vec![ch(names::THROTTLE, "1", u), ch(names::THRUST, "N", y)],
        missing,
        events: Vec::new(),
    }
}

#[test]
fn missing_samples_are_skipped_and_a_clean_plant_stays_clean() {
    let (_, m) = synth::case(None, 3).unwrap();
    let n = m.u.len();
    let mut missing = vec![false; n];
    let (mut u, mut y) = (m.u.clone(), m.y.clone());
    for k in (1000..1040).chain(6000..6010) {
        missing[k] = true;
        u[k] = f64::NAN;
        y[k] = f64::NAN;
    }
    let d = diagnose::diagnose_record(&record(u, y, missing), names::THRUST, &Options::default())
        .unwrap();
    assert!(d.findings.is_empty(), "{:?}", d.findings);
    assert!(d.baseline.fit_percent > 90.0);
    assert_eq!(d.split.validation[1], n);
}

#[test]
fn unmarked_nan_and_absent_channels_are_typed_errors() {
    let (_, m) = synth::case(None, 1).unwrap();
    let mut y = m.y.clone();
    y[77] = f64::NAN;
    let n = y.len();
    let err = diagnose::diagnose_record(
        &record(m.u.clone(), y, vec![false; n]),
        names::THRUST,
        &Options::default(),
    );
    assert_eq!(
        err.unwrap_err(),
        DiagnoseError::NonFinite {
            channel: names::THRUST.into(),
            index: 77
        }
    );
    let err = diagnose::diagnose_record(
        &record(m.u.clone(), m.y.clone(), vec![false; n]),
        "rpm",
        &Options::default(),
    );
    assert!(matches!(err, Err(DiagnoseError::MissingChannel(_))));
}

#[test]
fn short_constant_and_non_finite_inputs_are_refused() {
    let o = Options::default();
    let u = vec![0.5; 1000];
    let y: Vec<f64> = (0..1000).map(|k| (k as f64).sin()).collect();
    assert_eq!(
        diagnose::diagnose(0.01, &u, &y, &[], None, &o).unwrap_err(),
        DiagnoseError::Constant("input")
    );
    let u2: Vec<f64> = (0..1000)
        .map(|k| 0.5 + 0.1 * ((k / 50) % 2) as f64)
        .collect();
    assert_eq!(
        diagnose::diagnose(0.01, &u2, &vec![1.0; 1000], &[], None, &o).unwrap_err(),
        DiagnoseError::Constant("output")
    );
    assert!(matches!(
        diagnose::diagnose(0.01, &u2[..50], &y[..50], &[], None, &o),
        Err(DiagnoseError::TooShort { .. })
    ));
    assert!(matches!(
        diagnose::diagnose(0.0, &u2, &y, &[], None, &o),
        Err(DiagnoseError::BadSamplePeriod(_))
    ));
    let mut u3 = u2.clone();
    u3[5] = f64::INFINITY;
    assert!(matches!(
        diagnose::diagnose(0.01, &u3, &y, &[], None, &o),
        Err(DiagnoseError::NonFinite { index: 5, .. })
    ));
}

#[test]
fn a_clipping_sensor_is_named_with_its_level() {
    for i in 0..4 {
        let (mut cfg, _) = synth::case(None, i).unwrap();
        // Clip between the thrust at throttle 0.58 and at 0.65: the top operating point reads flat.
        let level = cfg.gain_n_per_throttle * 0.62;
        cfg.effects.saturation = Some(Saturation {
            level,
            signal: SaturationSignal::Sensor,
        });
        let m = synth::run(&cfg, &synth::throttle_plan(), 100 + i).unwrap();
        let d = diagnose::diagnose(
            synth::DT_S,
            &m.u,
            &m.y,
            &[],
            Some(&m.voltage),
            &Options::default(),
        )
        .unwrap();
        let f = d
            .findings
            .iter()
            .find(|f| f.effect == EffectName::Saturation)
            .expect("saturation named");
        assert_eq!(f.params["signal"], "sensor");
        let est = f.params["level"].as_f64().unwrap();
        assert!((est - level).abs() <= 1e-3, "level {est} vs {level}");
        let ext = d.extended.as_ref().unwrap();
        assert!(ext.fit_percent > d.baseline.fit_percent);
    }
}
