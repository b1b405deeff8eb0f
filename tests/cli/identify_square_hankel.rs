//! `propid identify --hankel square` on a 20 000-sample one-pulse record: the Hankel is the
//! largest near-square one the pulse window allows (≈ 10 000 × 10 000 blocks, far beyond what a
//! dense SVD could allocate) and the model matches the exact second-order plant.

use std::f64::consts::PI;
use std::process::Command;

const N: usize = 20_000;
const FS: f64 = 1000.0;
const FN: f64 = 20.0;
const ZETA: f64 = 0.3;
const PULSE_AT: usize = 100;

/// Exact discrete second-order plant with poles `exp((−ζω ± jω√(1−ζ²)) dt)` and input
/// `(u_{k−1} + u_{k−2})/2` (normalised throttle), one one-sample throttle pulse (µs).
fn write_csv(path: &std::path::Path) {
    let dt = 1.0 / FS;
    let w = 2.0 * PI * FN;
    let r = (-ZETA * w * dt).exp();
    let th = w * (1.0 - ZETA * ZETA).sqrt() * dt;
    let (a1, a2) = (2.0 * r * th.cos(), -r * r);
    let b = (1.0 - a1 - a2) / 2.0;
    let mut u = vec![1300.0; N];
    u[PULSE_AT] = 1500.0;
    let un = |k: usize| (u[k] - 1000.0) / 1000.0;
    let mut y = vec![un(0); N];
    for k in 2..N {
        y[k] = a1 * y[k - 1] + a2 * y[k - 2] + b * (un(k - 1) + un(k - 2));
    }
    // `throttle_us` with the default ESC range 1000..2000 µs: throttle = (µs − 1000)/1000.
    let mut s = String::from("t_s,throttle_us,thrust_N\n");
    for k in 0..N {
        s.push_str(&format!("{:.6},{:.3},{:.12}\n", k as f64 * dt, u[k], y[k]));
    }
    std::fs::write(path, s).unwrap();
}

fn identify(path: &std::path::Path, hankel: &str) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(["identify", path.to_str().unwrap(), "--order", "2", "--json"])
        .args(["--hankel", hankel])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()["model"].clone()
}

#[test]
fn square_hankel_on_a_long_pulse_record() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pulse.csv");
    write_csv(&path);
    let m = identify(&path, "square");
    let rows = m["hankel_block_rows"].as_u64().unwrap() as usize;
    let cols = m["hankel_block_cols"].as_u64().unwrap() as usize;
    // The pulse window runs from the pulse to the end of the record: L ≈ N − PULSE_AT blocks,
    // r + c = L − 1, r ≈ c.
    assert!(rows.abs_diff(cols) <= 1, "{rows} x {cols}");
    assert!((9_800..=10_000).contains(&rows), "{rows} x {cols}");
    assert_eq!(m["svd"], "truncated");
    let fn_hz = m["fn_hz"].as_f64().unwrap();
    let zeta = m["zeta"].as_f64().unwrap();
    assert!((fn_hz - FN).abs() < 1e-3 * FN, "fn {fn_hz}");
    assert!((zeta - ZETA).abs() < 1e-3, "zeta {zeta}");
    // DC gain: the truth, and the same as the automatically sized Hankel (the noise floor's
    // span, no longer cut at 128 blocks: 468 here, far below the square one).
    let auto = identify(&path, "auto");
    let auto_rows = auto["hankel_block_rows"].as_u64().unwrap();
    assert!((129..2_000).contains(&auto_rows), "{auto_rows}");
    let (g, ga) = (
        m["dc_gain"].as_f64().unwrap(),
        auto["dc_gain"].as_f64().unwrap(),
    );
    assert!((g - ga).abs() < 1e-6 * ga, "{g} vs {ga}");
    // The plant's gain per unit throttle is exactly 1 (b·2 / (1 − a1 − a2)).
    assert!((g - 1.0).abs() < 1e-6, "dc gain {g}");
}

#[test]
fn hankel_larger_than_the_record_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pulse.csv");
    write_csv(&path);
    let out = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(["identify", path.to_str().unwrap(), "--order", "2"])
        .args(["--hankel", "15000x15000"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("too short"), "{err}");
}
