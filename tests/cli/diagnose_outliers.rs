//! Isolated outliers in a diagnosed record (issue 12, item 6): one wrong sample of the load cell
//! (a spike to twice the record's peak, a dropout to 0) is left out by `propid diagnose` with
//! the rule of `propid identify` (`propid_numerics::outliers`), counted in `source.outliers`
//! and the summary, and the findings are those of the clean record; so is a start-up transient
//! (`source.start_up_transient`, `propid_numerics::startup`, the rule of `propid identify`). (Before, the same records
//! kept the effect's name but its score fell tenfold and the verdict went from `explained` or
//! `effects_found` to `unexplained`, the fit lost 3-4 points.)

use std::path::Path;

use crate::support::propid;
use propid_numerics::EffectName;
use propid_sim::synth;
use propid_testkit::inject::Samples;
use propid_testkit::{add_noise, throttle, Plant};
use serde_json::Value;

/// The simulated case `effect` #0 as a CSV file's samples.
fn case(effect: Option<EffectName>) -> Samples {
    let (_, m) = synth::case(effect, 0).unwrap();
    Samples {
        dt_s: synth::DT_S,
        t0_s: 0.0,
        u: m.u,
        y: m.y,
        voltage: Some(m.voltage),
    }
}

/// `diagnose --json` of `s` written as `file`.
fn diagnose(file: &Path, s: &Samples) -> Value {
    std::fs::write(file, s.to_csv()).unwrap();
    let f = file.to_str().unwrap();
    let (code, out, err) = propid(&["diagnose", "--json", "--input", "u", "--output", "y", f]);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).expect("one JSON object")
}

/// The effects named, in order.
fn named(v: &Value) -> Vec<String> {
    let f = v["findings"].as_array().cloned().unwrap_or_default();
    f.iter().map(|f| f["effect"].to_string()).collect()
}

/// A sample near `at` whose command is constant 3 samples either side (outside the rule's
/// command guard).
fn quiet_sample(u: &[f64], at: usize) -> usize {
    (at..u.len() - 3)
        .find(|&k| u[k - 3..=k + 3].iter().all(|&x| x == u[k]))
        .expect("a hold")
}

#[test]
fn a_spike_and_a_dropout_are_left_out_and_counted_and_change_no_finding() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("rec.csv");
    for effect in [
        None,
        Some(EffectName::DeadTime),
        Some(EffectName::PeriodicDisturbance),
    ] {
        let s = case(effect);
        let clean = diagnose(&file, &s);
        assert_eq!(
            clean["source"]["outliers"], 0,
            "{effect:?}: {}",
            clean["source"]
        );
        let peak = s.y.iter().copied().fold(f64::MIN, f64::max);
        let mut bad = s.clone();
        let (a, b) = (quiet_sample(&s.u, 2345), quiet_sample(&s.u, 5111));
        bad.y[a] = 2.0 * peak;
        bad.y[b] = 0.0;
        let got = diagnose(&file, &bad);
        assert_eq!(
            got["source"]["outliers"], 2,
            "{effect:?}: {}",
            got["source"]
        );
        assert_eq!(got["source"]["samples"], s.y.len());
        assert_eq!(got["source"]["missing"], 0);
        assert_eq!(named(&got), named(&clean), "{effect:?}");
        assert_eq!(
            got["verdict"]["kind"], clean["verdict"]["kind"],
            "{effect:?}"
        );
        // the fits move by no more than two samples' worth of data
        let fit = |v: &Value| v["baseline"]["fit_percent"].as_f64().unwrap();
        assert!(
            (fit(&got) - fit(&clean)).abs() < 0.5,
            "{effect:?}: {} vs {}",
            fit(&got),
            fit(&clean)
        );
        if let Some(effect) = effect {
            assert_eq!(
                named(&clean)[0],
                format!("\"{effect}\""),
                "{effect}: {clean}"
            );
        }
    }
    // the summary says it
    let s = case(None);
    let mut bad = s.clone();
    let a = quiet_sample(&s.u, 3000);
    bad.y[a] = 0.0;
    std::fs::write(&file, bad.to_csv()).unwrap();
    let f = file.to_str().unwrap();
    let (code, out, err) = propid(&["diagnose", "--input", "u", "--output", "y", f]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("outliers: 1 isolated sample(s) of the output left out"),
        "{out}"
    );
}

/// 4 s at 1 kHz of the plant (fn 12 Hz, ζ 0.7, 12 N/throttle) held at 0.45 (5.4 N),
/// one-sample pulses of ±0.05/±0.1 every 250 samples from 0.2 s, 0.01 N noise, plus a load
/// cell's tare settling from `a` N with τ = 0.3 s, as `propid identify` reads it.
fn pulse_record(a: f64) -> String {
    let n = 4000;
    let pulses: Vec<_> = (0..15)
        .map(|i| {
            let amp = if i % 4 < 2 { 0.05 } else { 0.1 };
            (200 + 250 * i, 1, if i % 2 == 0 { amp } else { -amp })
        })
        .collect();
    let u = throttle(n, &[(0, 0.45)], &pulses);
    let mut y = Plant::new(12.0, 0.7, 12.0, 0.001)
        .simulate(&u, 0.0)
        .remove(0);
    add_noise(&mut y, 0.01, 21);
    let mut text = String::from("t_s,throttle,thrust_N\n");
    for k in 0..n {
        let t = k as f64 * 0.001;
        let v = y[k] + a * (-t / 0.3).exp();
        text.push_str(&format!("{t:.4},{:.4},{v:.5}\n", u[k]));
    }
    text
}

#[test]
fn a_start_up_transient_is_left_out_and_said() {
    // before: 0.3 N named periodic_disturbance, asymmetric_dynamics and baseline_drift with a
    // baseline DC gain of 1 500 N (verdict unexplained); the clean record names nothing
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("rec.csv");
    let run = |text: String| -> Value {
        std::fs::write(&file, text).unwrap();
        let (code, out, err) = propid(&["diagnose", "--json", file.to_str().unwrap()]);
        assert_eq!(code, 0, "{err}");
        serde_json::from_str(&out).expect("one JSON object")
    };
    let clean = run(pulse_record(0.0));
    assert_eq!(
        clean["source"]["start_up_transient"], 0,
        "{}",
        clean["source"]
    );
    let gain = |v: &Value| v["baseline"]["model"]["dc_gain"].as_f64().unwrap();
    for a in [0.3, -1.0] {
        let got = run(pulse_record(a));
        let left_out = got["source"]["start_up_transient"].as_u64().unwrap();
        assert!((500..=2000).contains(&left_out), "{a} N: {}", got["source"]);
        assert_eq!(named(&got), named(&clean), "{a} N");
        // the output-error fit of 4 s of one-sample pulses is loose (clean: 11.3 N for 12 N;
        // 0.3 N left out: 10.1 N), but of the plant (before: 1 500 N, −1 977 N)
        let (g, w) = (gain(&got), gain(&clean));
        assert!((g - w).abs() < 0.15 * w, "{a} N: DC gain {g} vs {w}");
    }
    // the summary says it
    std::fs::write(&file, pulse_record(0.3)).unwrap();
    let (code, out, _) = propid(&["diagnose", file.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert!(out.contains("start-up transient: the first "), "{out}");
}
