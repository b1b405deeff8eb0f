//! A supply sag hidden in a stand log that has one of its own: a 100 Hz Tyto-style export (µs,
//! gf, volts) of a first-order motor whose thrust follows the throttle squared and the supply
//! voltage squared (a discharging battery with the load's IR drop), read 3 samples late. The
//! injected log is the same file with its thrust scaled by `1 + g (V − V̄)`, as the issue's
//! acceptance hides a voltage-dependent gain.
//!
//! Measured before the fix: the injected log named a softening "spring" (−0.4 % of stiffness
//! at the RMS thrust) in place of the stand's own dead time: taken when the supply term still
//! sat on the drive, it stood in for the side's misfit, and the side settled after it. The
//! search now runs again on the settled model, and a term left implausible there is removed.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde_json::Value;

use super::read::{diagnose_json, How};

const G0: f64 = 9.80665;

/// The export: 12 levels held 5 s each at 100 Hz; `scale(V, V̄)` multiplies the thrust (1 for
/// the clean log).
fn export(scale: impl Fn(f64, f64) -> f64) -> String {
    let (dt, tau, delay) = (0.01f64, 0.04f64, 3usize);
    let levels = [
        0.0, 0.15, 0.3, 0.45, 0.6, 0.75, 0.9, 0.7, 0.5, 0.35, 0.2, 0.0,
    ];
    let per = 500;
    let n = per * levels.len();
    let u_at = |k: usize| levels[(k / per).min(levels.len() - 1)];
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let noise = Normal::new(0.0, 0.02).unwrap();
    let (mut x, mut rows) = (0.0f64, Vec::with_capacity(n));
    for k in 0..n {
        let t = k as f64 * dt;
        x += (u_at(k.saturating_sub(delay)) - x) * (1.0 - (-dt / tau).exp());
        let v = 16.6 - 0.05 * t - 1.5 * x * x;
        let thrust = 9.0 * x * x * (v / 16.6).powi(2) + noise.sample(&mut rng);
        rows.push((t, u_at(k), thrust, v));
    }
    let v_mean = rows.iter().map(|r| r.3).sum::<f64>() / n as f64;
    let mut s = String::from("Time (s),ESC signal (µs),Thrust (gf),Voltage (V)\n");
    for (t, u, thrust, v) in rows {
        let y = thrust * scale(v, v_mean);
        s.push_str(&format!(
            "{t:.2},{:.0},{:.2},{v:.3}\n",
            1000.0 + 1000.0 * u,
            1e3 * y / G0
        ));
    }
    s
}

fn diagnose(text: &str) -> Value {
    diagnose_json("stand.csv", text.as_bytes(), How::default())
}

fn effects(v: &Value) -> Vec<String> {
    let mut e: Vec<String> = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["effect"].as_str().unwrap().to_string())
        .collect();
    e.sort();
    e
}

fn gain_per_volt(v: &Value) -> f64 {
    v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["effect"] == "supply_sag")
        .and_then(|f| f["gain_per_volt"].as_f64())
        .unwrap_or(f64::NAN)
}

#[test]
fn a_sag_hidden_on_a_stands_own_is_found_and_names_nothing_else() {
    let g = 0.08;
    let clean = diagnose(&export(|_, _| 1.0));
    let hidden = diagnose(&export(|v, v_mean| 1.0 + g * (v - v_mean)));
    let want = ["dead_time", "static_nonlinearity", "supply_sag"];
    assert_eq!(effects(&clean), want, "{}", clean["findings"]);
    assert_eq!(effects(&hidden), want, "{}", hidden["findings"]);
    let found = gain_per_volt(&hidden) - gain_per_volt(&clean);
    assert!((found / g - 1.0).abs() < 0.1, "hidden g {g}, found {found}");
}
