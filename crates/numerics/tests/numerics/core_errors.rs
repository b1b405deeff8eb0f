//! Bad input gives a typed error, never a panic (issue 2, item 6); the JSON report is valid.

use propid_testkit as core_support;

use core_support::{throttle, Plant};
use propid_numerics::{IdentError, IdentOptions, Limits, MarkovSeq, PulseInput, Workspace};

fn ws() -> Workspace {
    Workspace::new(&Limits::default()).unwrap()
}

fn pulse_record() -> (Plant, Vec<f64>, Vec<f64>) {
    let plant = Plant::new(10.0, 0.3, 4.0, 0.005);
    let u = throttle(
        1300,
        &[(0, 0.4)],
        &[(100, 1, 0.1), (500, 1, -0.1), (900, 1, 0.1)],
    );
    let y = plant.simulate(&u, 1.0).remove(0);
    (plant, u, y)
}

fn input<'a>(u: &'a [f64], y: &'a [&'a [f64]], missing: &'a [bool]) -> PulseInput<'a> {
    PulseInput {
        dt_s: 0.005,
        u,
        y,
        missing,
        pulse_starts: None,
    }
}

#[test]
fn no_pulse_constant_output_and_non_finite() {
    let (_, u, y) = pulse_record();
    let opts = IdentOptions::default();
    let flat = vec![0.4; u.len()];
    let chans = [&y[..]];
    assert_eq!(
        ws().identify(&input(&flat, &chans, &[]), &opts).err(),
        Some(IdentError::NoPulse)
    );
    let zeros = vec![0.0; u.len()];
    let zc = [&zeros[..]];
    assert_eq!(
        ws().identify(&input(&u, &zc, &[]), &opts).err(),
        Some(IdentError::ConstantOutput { channel: 0 })
    );
    let mut bad = y.clone();
    bad[321] = f64::INFINITY;
    let bc = [&bad[..]];
    assert!(matches!(
        ws().identify(&input(&u, &bc, &[]), &opts).err(),
        Some(IdentError::NonFinite {
            signal: "output",
            sample: 321,
            ..
        })
    ));
    // NaN is fine where marked missing; that pulse still counts at its other lags (issue 12).
    let mut miss = vec![false; u.len()];
    miss[321] = true;
    bad[321] = f64::NAN;
    let bc = [&bad[..]];
    let m = ws()
        .identify(&input(&u, &bc, &miss), &opts)
        .unwrap()
        .to_report();
    assert_eq!((m.pulses, m.pulses_skipped, m.missing_samples), (3, 0, 1));
}

#[test]
fn too_short_rank_deficient_order_too_high_and_limits() {
    let opts = IdentOptions::default();
    let mut w = ws();
    let short = MarkovSeq::from_data(1, 1, vec![0.0, 1.0, 0.5, 0.25]).unwrap();
    assert!(matches!(
        w.identify_markov(
            &short,
            0.01,
            &IdentOptions {
                order: Some(2),
                ..opts
            }
        ),
        Err(IdentError::RecordTooShort { .. })
    ));
    // A first-order sequence asked for order 3: rank 1 < 3.
    let first: Vec<f64> = (0..100)
        .map(|k| if k == 0 { 0.0 } else { 0.9f64.powi(k - 1) })
        .collect();
    let first = MarkovSeq::from_data(1, 1, first).unwrap();
    assert!(matches!(
        w.identify_markov(
            &first,
            0.01,
            &IdentOptions {
                order: Some(3),
                ..opts
            }
        ),
        Err(IdentError::RankDeficient { rank: 1, order: 3 })
    ));
    assert!(matches!(
        w.identify_markov(
            &first,
            0.01,
            &IdentOptions {
                order: Some(5),
                hankel_blocks: Some((3, 3)),
                ..opts
            }
        ),
        Err(IdentError::OrderTooHigh { order: 5, max: 3 })
    ));
    assert!(matches!(
        w.identify_markov(
            &first,
            0.01,
            &IdentOptions {
                order: Some(50),
                ..opts
            }
        ),
        Err(IdentError::LimitsExceeded { what: "order", .. })
    ));
    let auto = w.identify_markov(&first, 0.01, &opts).unwrap();
    assert_eq!(auto.order(), 1);
    let zero = MarkovSeq::from_data(1, 1, vec![0.0; 50]).unwrap();
    assert!(w.identify_markov(&zero, 0.01, &opts).is_err());
    let mut nan = vec![0.5; 50];
    nan[7] = f64::NAN;
    let nan = MarkovSeq::from_data(1, 1, nan).unwrap();
    assert!(matches!(
        w.identify_markov(&nan, 0.01, &opts),
        Err(IdentError::NonFinite { sample: 7, .. })
    ));
    let small = Limits {
        max_samples: 100,
        ..Limits::default()
    };
    let (_, u, y) = pulse_record();
    let chans = [&y[..]];
    assert!(matches!(
        Workspace::new(&small)
            .unwrap()
            .identify(&input(&u, &chans, &[]), &opts),
        Err(IdentError::LimitsExceeded {
            what: "samples",
            ..
        })
    ));
    assert!(Workspace::new(&Limits {
        max_order: 0,
        ..Limits::default()
    })
    .is_err());
    // Mismatched lengths and a bad sample period.
    let chans = [&y[..10]];
    assert!(matches!(
        ws().identify(&input(&u, &chans, &[]), &opts),
        Err(IdentError::InvalidInput(_))
    ));
    let chans = [&y[..]];
    let bad_dt = PulseInput {
        dt_s: 0.0,
        ..input(&u, &chans, &[])
    };
    assert!(matches!(
        ws().identify(&bad_dt, &opts),
        Err(IdentError::InvalidInput(_))
    ));
}

#[test]
fn device_pulse_starts_are_used() {
    let (plant, u, y) = pulse_record();
    let chans = [&y[..]];
    let starts = [100, 500, 900];
    let inp = PulseInput {
        pulse_starts: Some(&starts),
        ..input(&u, &chans, &[])
    };
    let m = ws()
        .identify(&inp, &IdentOptions::default())
        .unwrap()
        .to_report();
    assert_eq!(m.pulses, 3);
    assert!(((m.fn_hz - plant.fn_hz) / plant.fn_hz).abs() < 1e-8);
}

#[test]
fn report_is_valid_json_with_the_public_field_names() {
    let (_, u, y) = pulse_record();
    let chans = [&y[..]];
    let mut w = ws();
    // Order 1 on 2nd-order data: fn and zeta are NaN and must serialise as null.
    let m = w.identify(
        &input(&u, &chans, &[]),
        &IdentOptions {
            order: Some(1),
            ..IdentOptions::default()
        },
    );
    let r = m.unwrap().to_report();
    let text = serde_json::to_string(&r).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "order",
        "dt_s",
        "fn_hz",
        "zeta",
        "dc_gain",
        "time_constants_s",
        "poles_s",
        "poles_z",
        "a",
        "b",
        "c",
        "d",
        "singular_values",
        "indicators",
        "uncertainty",
        "pulses",
        "pulses_skipped",
        "noise_rms",
        "mass_spring_damper",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert!(v["fn_hz"].is_null() && v["zeta"].is_null());
    for key in ["msv", "mac", "emac", "mpc", "cmi"] {
        assert!(v["indicators"][0].get(key).is_some());
    }
    for key in ["fn_hz", "zeta", "dc_gain"] {
        assert!(v["uncertainty"].get(key).is_some());
    }
    for key in ["m", "d", "k"] {
        assert!(v["mass_spring_damper"].get(key).is_some());
    }
    assert!(v["dc_gain"].is_number());
    let back: propid_numerics::ModelReport = serde_json::from_str(&text).unwrap();
    assert_eq!(back.order, 1);
    assert!(back.fn_hz.is_nan());
}

mod never_panics {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

        /// Random throttle levels, pulses of random width, random outputs with NaN/inf, random
        /// missing masks and device starts: `identify` returns, it never panics.
        #[test]
        fn identify_returns_on_arbitrary_input(
            levels in proptest::collection::vec((0usize..300, 0.0f64..1.0), 1..4),
            pulses in proptest::collection::vec((1usize..290, 1usize..8, -0.3f64..0.3), 0..8),
            noise in proptest::collection::vec(-1.0f64..1.0, 300),
            noise_level in prop_oneof![Just(0.0), Just(1e-3), Just(1.0)],
            bad in prop_oneof![3 => Just(None), 1 => (0usize..300, prop_oneof![Just(f64::NAN), Just(f64::INFINITY)]).prop_map(Some)],
            miss_at in proptest::collection::vec(0usize..300, 0..3),
            starts in proptest::option::of(proptest::collection::vec(0usize..400, 0..5)),
            order in proptest::option::of(1usize..6),
        ) {
            let mut u = vec![0.5; 300];
            for (k, uk) in u.iter_mut().enumerate() {
                if let Some((_, l)) = levels.iter().filter(|(s, _)| *s <= k).max_by_key(|(s, _)| *s) {
                    *uk = *l;
                }
            }
            for (s, w, a) in pulses {
                for uk in u.iter_mut().skip(s).take(w) {
                    *uk += a;
                }
            }
            let mut miss = vec![false; 300];
            for k in miss_at {
                miss[k] = true;
            }
            // A first-order lag of the throttle plus noise, sometimes with a bad value.
            let mut y = vec![0.0; 300];
            let mut state = 0.0;
            for k in 0..300 {
                state = 0.8 * state + u[k];
                y[k] = state + noise_level * noise[k];
            }
            if let Some((k, v)) = bad {
                y[k] = v;
            }
            for k in 0..300 {
                if miss[k] {
                    y[k] = f64::NAN;
                }
            }
            let chans = [&y[..]];
            let input = PulseInput { dt_s: 0.001, u: &u, y: &chans, missing: &miss, pulse_starts: starts.as_deref() };
            let mut w = Workspace::new(&Limits { max_samples: 512, max_block_rows: 32, max_block_cols: 32, ..Limits::default() }).unwrap();
            let _ = w.identify(&input, &IdentOptions { order, ..IdentOptions::default() });
            let m = MarkovSeq::from_data(1, 1, y.clone()).unwrap();
            let _ = w.identify_markov(&m, 0.001, &IdentOptions { order, ..IdentOptions::default() });
        }
    }
}
