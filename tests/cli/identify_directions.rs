//! Spin-up and spin-down side by side (`steps_by_direction`): a stand whose thrust rises with a
//! 40 ms time constant and falls with 90 ms (a motor driven up, coasting down), written as a
//! plain 200 Hz export, read through the binary; each direction's medians are its own.

use crate::support::{median_rows, propid};
use serde_json::Value;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// Throttle levels, each held 1.5 s at 200 Hz; thrust `10 N · u` through a 10 ms dead time and
/// a lag of 40 ms rising, 90 ms falling.
fn export() -> String {
    let dt = 0.005;
    let levels = [0.2, 0.5, 0.3, 0.7, 0.4, 0.8, 0.5, 0.2];
    let mut s = String::from("time_s,throttle,thrust_N\n");
    let (mut y, mut k) = (2.0f64, 0usize);
    let u_at = |k: usize| levels[(k / 300).min(levels.len() - 1)];
    while k < 300 * levels.len() {
        let target = 10.0 * u_at(k.saturating_sub(2));
        let tau: f64 = if target > y { 0.040 } else { 0.090 };
        y += (target - y) * (1.0 - (-dt / tau).exp());
        let wobble = ((k * 7919) % 101) as f64 / 100.0 - 0.5;
        s.push_str(&format!(
            "{:.3},{:.2},{:.4}\n",
            k as f64 * dt,
            u_at(k),
            y + 0.005 * wobble
        ));
        k += 1;
    }
    s
}

#[test]
fn spin_up_and_spin_down_have_their_own_medians() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("asym.csv");
    std::fs::write(&path, export()).unwrap();
    let file = path.to_str().unwrap();
    let (code, out, err) = propid(&["identify", file, "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let d = &v["steps_by_direction"];
    let (up, down) = (&d["up"], &d["down"]);
    assert_eq!(
        (up["steps"].as_u64(), down["steps"].as_u64()),
        (Some(3), Some(4)),
        "{d}"
    );
    assert!(
        (f(&up["time_constant_s"]) / 0.040 - 1.0).abs() < 0.15,
        "{d}"
    );
    assert!(
        (f(&down["time_constant_s"]) / 0.090 - 1.0).abs() < 0.15,
        "{d}"
    );
    for side in [up, down] {
        assert!((f(&side["dead_time_s"]) - 0.010).abs() <= 0.0051, "{d}");
    }
    // The summary prints them under the step table, up first.
    let (code, human, err) = propid(&["identify", file]);
    assert_eq!(code, 0, "{err}");
    let medians = median_rows(&human);
    assert_eq!(medians.len(), 2, "{human}");
    assert!(
        medians[0].contains(" up ") && medians[1].contains(" down "),
        "{human}"
    );
}
