//! Pulse ensembles on a known response: widths, signs and amplitudes average to the
//! one-sample response; missing samples and bad inputs are refused or counted.

use super::*;
use crate::{IdentError, MarkovSeq};

/// y = 2·(one-sample response h_k = 0.5^k) convolved with the throttle deviation.
fn simulate(u: &[f64], level: f64) -> Vec<f64> {
    (0..u.len())
        .map(|k| {
            (0..=k)
                .map(|j| (u[j] - level) * 0.5f64.powi((k - j) as i32))
                .sum::<f64>()
                + 3.0
        })
        .collect()
}

#[test]
fn widths_signs_and_amplitudes_average_to_the_one_sample_response() {
    let mut u = vec![0.4; 400];
    for (s, w, a) in [(50, 1, 0.1), (130, 2, -0.05), (210, 5, 0.02), (385, 3, 0.2)] {
        for k in s..s + w {
            u[k] = 0.4 + a;
        }
    }
    let y = simulate(&u, 0.4);
    let chans = [&y[..]];
    let input = PulseInput {
        dt_s: 0.01,
        u: &u,
        y: &chans,
        missing: &[],
        pulse_starts: None,
    };
    let mut ens = PulseEnsemble::new(400, 1, 8);
    let mut m = MarkovSeq::zeros(1, 1, 400);
    ens.build(&input, 16, &mut m).unwrap();
    assert_eq!(
        ens.kept(),
        3,
        "the last pulse's window is too short: {:?}",
        ens.pulses()
    );
    assert_eq!(ens.skipped(), 1);
    for k in 0..m.len() {
        assert!(
            (m.get(k, 0, 0) - 0.5f64.powi(k as i32)).abs() < 1e-12,
            "k={k}"
        );
    }
}

#[test]
fn one_late_pulse_does_not_leave_the_others_out() {
    // Windows 100, 100, 100 and 650 samples (the last pulse fired late): (pulses reaching L)·L
    // alone would take L = 650 with one pulse; at least half the pulses must reach L.
    let mut u = vec![0.4; 1000];
    for s in [50, 150, 250, 350] {
        u[s] = 0.5;
    }
    let y = simulate(&u, 0.4);
    let chans = [&y[..]];
    let input = PulseInput {
        dt_s: 0.01,
        u: &u,
        y: &chans,
        missing: &[],
        pulse_starts: None,
    };
    let mut ens = PulseEnsemble::new(1000, 1, 8);
    let mut m = MarkovSeq::zeros(1, 1, 1000);
    ens.build(&input, 16, &mut m).unwrap();
    assert_eq!((ens.kept(), ens.skipped()), (4, 0), "{:?}", ens.pulses());
    assert_eq!(m.len(), 100);
}

#[test]
fn missing_sample_in_window_is_averaged_around_never_fatal() {
    let mut u = vec![0.3; 300];
    u[50] = 0.4;
    u[150] = 0.4;
    let mut y = simulate(&u, 0.3);
    let mut miss = vec![false; 300];
    miss[60] = true;
    y[60] = f64::NAN;
    u[60] = f64::NAN;
    let chans = [&y[..]];
    let input = PulseInput {
        dt_s: 0.01,
        u: &u,
        y: &chans,
        missing: &miss,
        pulse_starts: None,
    };
    let mut ens = PulseEnsemble::new(300, 1, 8);
    let mut m = MarkovSeq::zeros(1, 1, 300);
    ens.build(&input, 16, &mut m).unwrap();
    // Both pulses are used; lag 10 of the first one is missing: one pulse there.
    assert_eq!((ens.kept(), ens.skipped()), (2, 0));
    assert_eq!(ens.missing_in_windows(), 1);
    let counts = ens.lag_counts();
    assert_eq!(counts[10], 1);
    assert!(counts.iter().enumerate().all(|(k, c)| *c == 2 || k == 10));
    // Every lag, the missing one included, is the exact response (nothing interpolated).
    for k in 0..m.len() {
        assert!(
            (m.get(k, 0, 0) - 0.5f64.powi(k as i32)).abs() < 1e-12,
            "k={k}"
        );
    }
    // The lag seen by one pulse of two is √2 noisier.
    assert!((ens.growth()[10] - 2f64.sqrt()).abs() < 1e-12);
    assert_eq!(ens.growth()[11], 1.0);
}

#[test]
fn unmeasured_baseline_leaves_the_pulse_out() {
    let mut u = vec![0.3; 300];
    u[50] = 0.4;
    u[150] = 0.4;
    let mut y = simulate(&u, 0.3);
    let mut miss = vec![false; 300];
    // The baseline of the first pulse is the last half of the level before it: 25..50.
    for k in 25..50 {
        miss[k] = true;
        y[k] = f64::NAN;
    }
    let chans = [&y[..]];
    let input = PulseInput {
        dt_s: 0.01,
        u: &u,
        y: &chans,
        missing: &miss,
        pulse_starts: None,
    };
    let mut ens = PulseEnsemble::new(300, 1, 8);
    let mut m = MarkovSeq::zeros(1, 1, 300);
    ens.build(&input, 16, &mut m).unwrap();
    assert_eq!((ens.kept(), ens.skipped()), (1, 1));
}

#[test]
fn bad_inputs() {
    let u = vec![0.3; 50];
    let y = vec![1.0; 50];
    let chans = [&y[..]];
    let input = PulseInput {
        dt_s: 0.01,
        u: &u,
        y: &chans,
        missing: &[],
        pulse_starts: None,
    };
    let mut ens = PulseEnsemble::new(100, 1, 8);
    let mut m = MarkovSeq::zeros(1, 1, 100);
    assert_eq!(
        ens.build(&input, 16, &mut m),
        Err(IdentError::ConstantOutput { channel: 0 })
    );
    let y2: Vec<f64> = (0..50).map(|k| k as f64).collect();
    let chans = [&y2[..]];
    let input = PulseInput { y: &chans, ..input };
    assert_eq!(ens.build(&input, 16, &mut m), Err(IdentError::NoPulse));
    let mut y3 = y2.clone();
    y3[7] = f64::NAN;
    let chans = [&y3[..]];
    let input = PulseInput { y: &chans, ..input };
    assert!(matches!(
        ens.build(&input, 16, &mut m),
        Err(IdentError::NonFinite { sample: 7, .. })
    ));
}
