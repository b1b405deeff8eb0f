//! The input lead (`src/diagnose/lead.rs`) through the binary: a stand logger that sends the
//! command, reads the load cell and writes both on one row logs a thrust that has already
//! answered the command beside it. The 2nd-order core, whose input acts from its own row on,
//! could only imitate that with a time constant far below a sample and left the residual at
//! 4 × the noise (`unexplained`); with the lead the record is explained to the noise by its
//! quadratic static map alone. The same stand logged a row later (the plain hold) keeps it.

use serde_json::Value;

use crate::support::propid;

/// A 40 Hz staircase up and down of a propeller (T = 12·u² N, first-order lag of 60 ms, no
/// dead time), the thrust of each row read `late` rows after the command beside it was sent
/// (0: on the same row), noise σ = 0.01 N from a fixed linear congruential sequence.
fn write_log(dir: &std::path::Path, late: usize) -> String {
    let dt = 0.025;
    let levels = [0.1, 0.3, 0.5, 0.7, 0.5, 0.3, 0.1, 0.4, 0.6, 0.2];
    let u: Vec<f64> = levels
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(120))
        .collect();
    let a = (-dt / 0.06f64).exp();
    // y[k]: the thrust after the command u[k] acted for one sample.
    let mut y = Vec::with_capacity(u.len());
    let mut t = 12.0 * u[0] * u[0];
    for &uk in &u {
        t = a * t + (1.0 - a) * 12.0 * uk * uk;
        y.push(t);
    }
    let mut seed: u64 = 7;
    let mut noise = || {
        // Sum of 12 uniforms: ≈ Gaussian, σ = 1.
        (0..12)
            .map(|_| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (seed >> 11) as f64 / (1u64 << 53) as f64
            })
            .sum::<f64>()
            - 6.0
    };
    let mut text = String::from("Time (s),ESC signal (µs),Thrust (N)\n");
    for k in late..u.len() {
        let thrust = y[k - late] + 0.01 * noise();
        let cmd = 1000.0 + 1000.0 * u[k];
        text.push_str(&format!("{:.3},{cmd:.0},{thrust:.5}\n", k as f64 * dt));
    }
    let path = dir.join(format!("same_row_{late}.csv"));
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

fn diagnose(file: &str) -> Value {
    let (code, out, err) = propid(&["diagnose", file, "--json"]);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

fn effects(v: &Value) -> Vec<&str> {
    v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|f| f["effect"].as_str())
        .collect()
}

#[test]
fn a_thrust_read_on_the_commands_own_row_is_explained_with_a_lead() {
    let dir = tempfile::tempdir().unwrap();
    let v = diagnose(&write_log(dir.path(), 0));
    let lead = v["input_lead"]["samples"]
        .as_f64()
        .unwrap_or_else(|| panic!("{v}"));
    assert!(lead >= 0.5, "{}", v["input_lead"]);
    assert_eq!(effects(&v), ["static_nonlinearity"], "{v}");
    assert_ne!(v["verdict"]["kind"], "unexplained", "{}", v["verdict"]);
    // The summary says it.
    let file = write_log(dir.path(), 0);
    let (_, text, _) = propid(&["diagnose", &file]);
    assert!(text.contains("input lead "), "{text}");
    // A row later, the plain hold: no lead, the same finding, explained as well.
    let v = diagnose(&write_log(dir.path(), 1));
    assert!(v.get("input_lead").is_none(), "{}", v["input_lead"]);
    assert_eq!(effects(&v), ["static_nonlinearity"], "{v}");
    assert_ne!(v["verdict"]["kind"], "unexplained", "{}", v["verdict"]);
}
