//! `propid identify` on what `propid sim --record` writes (a TSP/1 pulse experiment with device
//! IMPULSE_START events and 500 ms ramps between three operating points), and the audit's bad
//! inputs: an absurd `--order`, an absurd `--fs`, `--esc-us MIN,MAX`, non-finite models.

use crate::support::{propid, second_order_sim};
use std::path::Path;

use propid_numerics::identify::{check_finite, identify_any, AnyError, AnyInput, PathTaken};
use propid_numerics::okid::OkidOptions;
use propid_numerics::IdentOptions;
use serde_json::Value;

/// The 2nd-order plant (`kind = "second_order"`, the code's default).
const FN_HZ: f64 = 12.0;
const ZETA: f64 = 0.7;
const GAIN: f64 = 12.0;

fn record(dir: &Path, name: &str, extra: &[&str]) -> String {
    let f = dir.join(name).to_str().unwrap().to_owned();
    let cfg = second_order_sim(dir);
    let mut args = vec!["sim", "--config", &cfg, "--record", &f, "--seconds", "20"];
    args.extend_from_slice(extra);
    let (code, _, err) = propid(&args);
    assert_eq!(code, 0, "sim --record: {err}");
    f
}

fn identify(args: &[&str]) -> Value {
    let (code, out, err) = propid(args);
    assert_eq!(code, 0, "stderr: {err}");
    assert_eq!(out.lines().count(), 1, "exactly one JSON line: {out}");
    serde_json::from_str(&out).expect("valid JSON")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn sim_recording_takes_the_pulse_path_with_three_operating_points() {
    let dir = tempfile::tempdir().unwrap();
    let file = record(dir.path(), "r.tsp", &[]);
    let v = identify(&["identify", &file, "--json"]);
    assert_eq!(v["source"]["path"], "pulse", "{}", v["source"]);
    let m = &v["model"];
    assert!(m["pulses"].as_u64().unwrap() >= 20, "{}", m["pulses"]);
    // 24 one-sample pulses of 0.05 and 0.1 throttle under 0.01 N of noise: fn and DC gain are
    // known to about 3 %, ζ to about 8 % (jackknife); seed 1 gives fn +3.6 %, ζ +9.5 %,
    // gain +2.9 %. Each must also lie within 3 jackknife standard deviations.
    let u = &m["uncertainty"];
    for (key, truth, tol) in [("fn_hz", FN_HZ, 0.05), ("zeta", ZETA, 0.12)] {
        let (est, sd) = (f(&m[key]), f(&u[key]));
        assert!(rel(est, truth) < tol, "{key} {est} vs {truth}");
        assert!(sd.is_finite() && sd > 0.0, "uncertainty {key}: {u}");
        assert!(
            (est - truth).abs() < 3.0 * sd,
            "{key} {est} ± {sd} vs {truth}"
        );
    }
    let (g, sd) = (f(&m["dc_gain"]), f(&u["dc_gain"]));
    assert!(rel(g, GAIN) < 0.05, "dc_gain {g}");
    assert!(
        sd.is_finite() && (g - GAIN).abs() < 3.0 * sd,
        "dc_gain {g} ± {sd}"
    );
    let noise = f(&m["noise_rms"]);
    assert!(
        (0.005..0.02).contains(&noise),
        "noise_rms {noise} (sim: 0.01 N)"
    );

    let ops = &v["operating_points"];
    assert_eq!(ops["kind"], "staircase", "{ops}");
    let pts = ops["points"].as_array().unwrap();
    let levels: Vec<f64> = pts.iter().map(|p| f(&p["level"])).collect();
    assert_eq!(levels, [0.3, 0.45, 0.6], "{ops}");
    for p in pts {
        assert_eq!(p["path"], "pulse", "{p}");
        assert!(rel(f(&p["fn_hz"]), FN_HZ) < 0.15, "{p}");
        assert!(rel(f(&p["dc_gain"]), GAIN) < 0.15, "{p}");
    }
}

#[test]
fn bit_flipped_recording_still_takes_the_pulse_path() {
    let dir = tempfile::tempdir().unwrap();
    let file = record(dir.path(), "b.tsp", &["--bit-flips", "1e-4"]);
    let v = identify(&["identify", &file, "--json"]);
    assert_eq!(v["source"]["path"], "pulse", "{}", v["source"]);
    assert!(
        v["source"]["missing"].as_u64().unwrap() > 0,
        "flips cost samples"
    );
    let m = &v["model"];
    let (kept, skipped) = (
        m["pulses"].as_u64().unwrap(),
        m["pulses_skipped"].as_u64().unwrap(),
    );
    assert!(kept >= 5 && skipped > 0, "kept {kept}, skipped {skipped}");
    assert!(rel(f(&m["fn_hz"]), FN_HZ) < 0.15, "{}", m["fn_hz"]);
    assert!(rel(f(&m["dc_gain"]), GAIN) < 0.15, "{}", m["dc_gain"]);
}

/// A small CSV: random throttle around 0.4 through a 2nd-order plant, 500 Hz.
fn csv(dir: &Path, n: usize, jitter: bool) -> String {
    let (fn_hz, zeta, k, dt) = (10.0f64, 0.5, 5.0, 0.002);
    let w = 2.0 * std::f64::consts::PI * fn_hz;
    let (mut y, mut v, mut t) = (0.0f64, 0.0f64, 0.0f64);
    let mut text = String::from("t_s,throttle_pct,thrust_N\n");
    for i in 0..n {
        let u = 0.4 + 0.05 * (((i * 7919) % 101) as f64 / 50.0 - 1.0);
        for _ in 0..10 {
            let a = w * w * (k * u - y) - 2.0 * zeta * w * v;
            v += a * dt / 10.0;
            y += v * dt / 10.0;
        }
        text.push_str(&format!("{t},{},{y}\n", 100.0 * u));
        t += if jitter && i % 3 == 0 { 1.6 * dt } else { dt };
    }
    let f = dir.join(format!("rec{n}{jitter}.csv"));
    std::fs::write(&f, text).unwrap();
    f.to_str().unwrap().to_owned()
}

#[test]
fn an_order_larger_than_the_data_supports_is_refused_before_sizing() {
    let dir = tempfile::tempdir().unwrap();
    let file = csv(dir.path(), 2000, false);
    let (code, out, err) = propid(&["identify", &file, "--order", "100000", "--json"]);
    assert_ne!(code, 0);
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("order 100000 is larger than the data supports"),
        "{err}"
    );
}

#[test]
fn an_absurd_sample_rate_is_a_typed_error() {
    let dir = tempfile::tempdir().unwrap();
    for jitter in [false, true] {
        let file = csv(dir.path(), 500, jitter);
        let (code, _, err) = propid(&["identify", &file, "--fs", "1e300", "--json"]);
        assert_ne!(code, 0);
        assert_ne!(code, 101, "panicked: {err}");
        assert!(err.contains("sample rate 1e300 Hz"), "{err}");
    }
}

#[test]
fn esc_us_takes_min_comma_max_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    let file = csv(dir.path(), 2000, false);
    let v = identify(&["identify", &file, "--esc-us", "1000,2000", "--json"]);
    assert_eq!(v["source"]["format"], "csv");
    let (code, _, err) = propid(&["identify", &file, "--esc-us", "1000", "--json"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--esc-us takes MIN,MAX"), "{err}");
    let (code, _, err) = propid(&["diagnose", &file, "--esc-us", "1000,2000", "--json"]);
    assert_ne!(code, 2, "diagnose refused the documented form: {err}");
}

#[test]
fn okid_noise_rms_is_the_one_step_residual() {
    let dir = tempfile::tempdir().unwrap();
    let file = csv(dir.path(), 2000, false);
    let v = identify(&["identify", &file, "--json"]);
    assert_eq!(v["source"]["path"], "okid");
    let res = &v["source"]["okid"]["residual_rms"];
    let noise = f(&v["model"]["noise_rms"]);
    assert!(
        noise > 0.0 && rel(noise, f(&res[0])) < 1e-12,
        "{noise} vs {res}"
    );
}

#[test]
fn a_non_finite_model_is_refused() {
    // A clean one-sample pulse record through a first-order lag gives a finite order-2 model
    // (no pole pair: fn_hz NaN is legitimate there) ...
    let n = 600;
    let mut u = vec![0.4; n];
    for s in (50..n).step_by(100) {
        u[s] = 0.5;
    }
    let mut y = vec![0.0; n];
    for k in 1..n {
        y[k] = 0.8 * y[k - 1] + 0.2 * 3.0 * u[k - 1];
    }
    y[0] = y[1];
    let (us, ys) = ([&u[..]], [&y[..]]);
    let input = AnyInput {
        dt_s: 0.01,
        u: &us,
        y: &ys,
        missing: &[],
        pulse_starts: None,
    };
    let ident = IdentOptions {
        order: Some(2),
        ..IdentOptions::default()
    };
    let m = identify_any(&input, &ident, &OkidOptions::default()).expect("identify");
    assert_eq!(m.path, PathTaken::Pulse);
    assert!(check_finite(&m.report, None).is_ok());
    // ... but from an ill-conditioned OKID regression a model without fn is refused.
    let mut bad = m.report.clone();
    bad.fn_hz = f64::NAN;
    assert!(check_finite(&bad, Some(10.0)).is_ok());
    let e = check_finite(&bad, Some(4.5e15)).unwrap_err();
    assert!(matches!(
        e,
        AnyError::NonFiniteModel {
            what: "fn_hz/zeta",
            ..
        }
    ));
    assert!(e.to_string().contains("condition 4.5e15"), "{e}");
    let mut bad = m.report;
    bad.a[0][0] = f64::INFINITY;
    assert!(check_finite(&bad, None).is_err());
}
