//! `identify` judges what it prints (issue 12 item 6): isolated outlier samples are left out and
//! counted, a model that fails the daemon's quality checks is printed with
//! `"quality": {"accepted": false}` and exits 4, a start-up transient is left out and said
//! (`source.start_up_transient`), and a record holds as many pulses as it has.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support::propid;
use propid_testkit::{add_noise, throttle, Plant};
use serde_json::Value;

/// The plant of the record: fn 12 Hz, ζ 0.7, 12 N per unit throttle, held at 0.45
/// (5.4 N), 1 kHz, 0.01 N noise; one-sample pulses of ±0.05/±0.1 every 250 samples from
/// `first`. `settled`: the thrust starts at the level's steady state (else at 0 N: the record
/// starts while the motor spins up).
fn record(first: usize, settled: bool) -> (Vec<f64>, Vec<f64>) {
    let n = 4000;
    let pulses: Vec<_> = (0..)
        .map(|i| first + 250 * i)
        .take_while(|&s| s + 200 < n)
        .enumerate()
        .map(|(i, s)| {
            let a = if (s / 250) % 2 == 0 { 0.05 } else { 0.1 };
            (s, 1, if i % 2 == 0 { a } else { -a })
        })
        .collect();
    let u = throttle(n, &[(0, 0.45)], &pulses);
    let plant = Plant::new(12.0, 0.7, 12.0, 0.001);
    let mut y = if settled {
        plant.simulate(&u, 0.0).remove(0)
    } else {
        // from rest: one sample at throttle 0 before the record starts
        let mut from_rest = vec![0.0];
        from_rest.extend_from_slice(&u);
        plant.simulate(&from_rest, 0.0).remove(0).split_off(1)
    };
    add_noise(&mut y, 0.01, 11);
    (u, y)
}

fn write_csv(dir: &Path, name: &str, u: &[f64], y: &[f64]) -> PathBuf {
    let mut text = String::from("t_s,throttle,thrust_N\n");
    for k in 0..u.len() {
        text.push_str(&format!(
            "{:.4},{:.4},{:.5}\n",
            k as f64 * 0.001,
            u[k],
            y[k]
        ));
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// `identify --json FILE ARGS`: exit code and the one JSON object printed.
fn identify(file: &Path, args: &[&str]) -> (i32, Value, String) {
    let mut all = vec!["identify", "--json", file.to_str().unwrap()];
    all.extend_from_slice(args);
    let (code, out, err) = propid(&all);
    assert_eq!(out.lines().count(), 1, "one JSON object: {out} {err}");
    (code, serde_json::from_str(&out).unwrap(), err)
}

fn num(v: &Value, path: &str) -> f64 {
    v.pointer(path)
        .and_then(Value::as_f64)
        .unwrap_or_else(|| panic!("{path} in {v}"))
}

#[test]
fn a_single_outlier_sample_is_left_out_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let (u, y) = record(200, true);
    let clean = write_csv(dir.path(), "clean.csv", &u, &y);
    let (code, want, err) = identify(&clean, &[]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(want["source"]["outliers"], 0);
    assert_eq!(want["quality"]["accepted"], true);
    // before: 10 N made the SVD fail (exit 4), 8 N gave fn = NaN with exit 0; 1337 lies in
    // the response of the pulse at 1200
    for bad in [10.0, 8.0] {
        let mut y = y.clone();
        y[1337] = bad;
        let f = write_csv(dir.path(), "outlier.csv", &u, &y);
        let (code, got, err) = identify(&f, &[]);
        assert_eq!(code, 0, "{bad} N: {err}");
        assert_eq!(got["source"]["outliers"], 1, "{bad} N");
        assert_eq!(got["model"]["missing_samples"], 1, "{bad} N");
        assert_eq!(got["quality"]["accepted"], true, "{bad} N");
        for key in ["fn_hz", "zeta", "dc_gain"] {
            let (g, w) = (
                num(&got, &format!("/model/{key}")),
                num(&want, &format!("/model/{key}")),
            );
            assert!((g - w).abs() <= 0.01 * w.abs(), "{bad} N: {key} {g} vs {w}");
        }
        assert!((num(&got, "/model/fn_hz") - 12.0).abs() < 0.6, "{got}");
    }
}

#[test]
fn a_start_up_transient_model_is_rejected_with_exit_4() {
    let dir = tempfile::tempdir().unwrap();
    // the thrust starts at 0 N and the pulses start before it has settled at 5.4 N
    let (u, y) = record(5, false);
    let f = write_csv(dir.path(), "transient.csv", &u, &y);
    let (code, v, err) = identify(&f, &[]);
    assert_eq!(code, 4, "{v}");
    assert!(err.contains("quality checks"), "{err}");
    assert_eq!(v["quality"]["accepted"], false);
    let flaws = v["quality"]["flaws"].as_array().unwrap();
    assert!(!flaws.is_empty(), "{v}");
    assert!(v["quality"]["hint"].is_string());
    // the human summary says so too, with the same exit code
    let (code, out, _) = propid(&["identify", f.to_str().unwrap()]);
    assert_eq!(code, 4);
    assert!(out.contains("quality   REJECTED"), "{out}");
    // the same plant, settled before the first pulse: accepted
    let (u, y) = record(200, false);
    let f = write_csv(dir.path(), "settled.csv", &u, &y);
    let (code, v, err) = identify(&f, &[]);
    assert_eq!(
        (code, &v["quality"]["accepted"]),
        (0, &Value::Bool(true)),
        "{err}"
    );
}

#[test]
fn a_five_thousand_pulse_recording_is_identified() {
    // before: "pulses is 4097, the workspace allows 4096"; a fast plant and 20 ms spacing keep
    // the record short (100 s at 1 kHz, simulated faster than real time)
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("sim.toml");
    std::fs::write(
        &cfg,
        "[plant]\nfn_hz = 100.0\nzeta = 0.7\n[experiment]\nlevels = [0.45]\nramp_ms = 0\n\
         settle_ms = 100\npulse_spacing_ms = 20\npulses_per_level = 5000\n",
    )
    .unwrap();
    let rec = dir.path().join("5000.tsp");
    let out = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(["sim", "--config", cfg.to_str().unwrap(), "--seconds", "120"])
        .arg("--record")
        .arg(&rec)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (code, v, err) = identify(&rec, &["--order", "2"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["model"]["pulses"], 5000);
    assert!(
        (num(&v, "/model/fn_hz") - 100.0).abs() < 3.0,
        "{}",
        v["model"]
    );
    assert!(
        (num(&v, "/model/zeta") - 0.7).abs() < 0.05,
        "{}",
        v["model"]
    );
}

#[test]
fn a_start_up_transient_is_left_out_and_said() {
    let dir = tempfile::tempdir().unwrap();
    let (u, y) = record(200, true);
    let clean = write_csv(dir.path(), "clean.csv", &u, &y);
    let (code, want, err) = identify(&clean, &[]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(want["source"]["start_up_transient"], 0);
    let t = |k: usize| k as f64 * 0.001;
    // a load cell's tare settling by `a` N with time constant `tau` s
    let tare = |a: f64, tau: f64| -> Vec<f64> {
        let decay = y.iter().enumerate();
        decay.map(|(k, v)| v + a * (-t(k) / tau).exp()).collect()
    };
    // an ESC soft start: 80 % of the level at once, the rest with τ = 0.5 s (before: DC gain
    // 12 % low, exit 0)
    let soft = {
        let ramped: Vec<f64> = u
            .iter()
            .enumerate()
            .map(|(k, v)| v - 0.2 * 0.45 * (-t(k) / 0.5).exp())
            .collect();
        let mut y = Plant::new(12.0, 0.7, 12.0, 0.001)
            .simulate(&ramped, 0.0)
            .remove(0);
        add_noise(&mut y, 0.01, 11);
        y
    };
    // (before: −1 N gave a DC gain 11 % low with exit 0); `fixed`: the model must be the clean
    // record's, else it may also be refused (exit 4) — never a wrong model with exit 0
    let cases = [
        ("tare -1 N", tare(-1.0, 0.5), true),
        ("tare +0.3 N", tare(0.3, 0.3), true),
        ("soft start", soft, true),
        ("tare +1 N", tare(1.0, 0.5), false),
    ];
    for (name, y, fixed) in cases {
        let f = write_csv(dir.path(), "start.csv", &u, &y);
        let (code, got, err) = identify(&f, &[]);
        let left_out = got["source"]["start_up_transient"].as_u64().unwrap();
        assert!(
            (500..=2000).contains(&left_out),
            "{name}: {}",
            got["source"]
        );
        if code == 4 && !fixed {
            assert_eq!(got["quality"]["accepted"], false, "{name}");
            continue;
        }
        assert_eq!(code, 0, "{name}: {err}");
        assert_eq!(got["quality"]["accepted"], true, "{name}");
        // the clean record's model within 2 jackknife deviations (or 4 %), and those small
        // (before, −1 N: DC gain 11.1 ± 7.3 N, ζ 0.63 ± 0.45; now 12.4 ± 1.1 N, 0.72 ± 0.06)
        for key in ["fn_hz", "zeta", "dc_gain"] {
            let (g, w) = (
                num(&got, &format!("/model/{key}")),
                num(&want, &format!("/model/{key}")),
            );
            let sd = num(&got, &format!("/model/uncertainty/{key}"));
            let tol = (2.0 * sd).max(0.04 * w.abs());
            assert!((g - w).abs() <= tol, "{name}: {key} {g} ± {sd} vs {w}");
            assert!(sd <= 0.1 * w.abs(), "{name}: {key} {g} ± {sd}");
        }
    }
    // the summary says it
    let f = write_csv(dir.path(), "tare.csv", &u, &tare(-1.0, 0.5));
    let (code, out, _) = propid(&["identify", f.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert!(out.contains("start-up  the first "), "{out}");
}
