//! Step figures from a vibrating stand: a first-order motor (θ 20 ms, τ 40 ms, no overshoot)
//! whose load cell reads with Gaussian noise 5 % of each step, exported in gram-force at
//! 200 Hz and read through the binary. Read sample by sample such noise was a 13.5 % "overshoot"
//! and a settling time as long as the hold; the figures now come from the response smoothed as
//! its noise requires (`smoothing_samples`), the overshoot is a bound (`overshoot_below_pct`)
//! and the settling time is the motor's.

use crate::support::{median_rows, propid};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde_json::Value;

const G0: f64 = 9.80665;

/// Levels 0.3 ↔ 0.5 held 1 s each, thrust 10 N per unit throttle, noise 0.1 N (5 % of the
/// 2 N steps).
fn export(seed: u64) -> String {
    let (dt, tau, delay) = (0.005f64, 0.040f64, 4usize);
    let levels = [0.3, 0.5, 0.3, 0.5, 0.3, 0.5, 0.3, 0.5, 0.3];
    let u_at = |k: usize| levels[(k / 200).min(levels.len() - 1)];
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.1).unwrap();
    let mut s = String::from("Time (s),Throttle (%),Thrust (gf)\n");
    let mut x = 3.0f64;
    for k in 0..200 * levels.len() {
        x += (10.0 * u_at(k.saturating_sub(delay)) - x) * (1.0 - (-dt / tau).exp());
        let y = x + noise.sample(&mut rng);
        s.push_str(&format!(
            "{:.3},{:.0},{:.1}\n",
            k as f64 * dt,
            100.0 * u_at(k),
            1e3 * y / G0
        ));
    }
    s
}

#[test]
fn a_noisy_load_cell_shows_no_overshoot_and_the_motors_settling_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("noisy.csv");
    std::fs::write(&path, export(3)).unwrap();
    let file = path.to_str().unwrap();
    let (code, out, err) = propid(&["identify", file, "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 8, "{out}");
    // Settling into ±10 %: θ + τ ln 10 (the step's first sample counts as its time).
    let want = 0.020 + 0.040 * 10f64.ln();
    for s in steps {
        assert!(s["smoothing_samples"].as_u64().unwrap() > 1, "{s}");
        assert!(s["overshoot_pct"].is_null(), "{s}");
        assert!(s["overshoot_below_pct"].as_f64().unwrap() < 12.0, "{s}");
        let settle = s["settling_90_s"].as_f64().unwrap();
        assert!((settle - want).abs() < 0.3 * want, "settling {settle}: {s}");
        let tau = s["time_constant_s"].as_f64().unwrap();
        assert!((tau - 0.040).abs() < 0.012, "τ {tau}: {s}");
    }
    for side in ["up", "down"] {
        let d = &v["steps_by_direction"][side];
        assert!(d["overshoot_pct"].is_null(), "{d}");
        assert!(d["overshoot_below_pct"].as_f64().is_some(), "{d}");
    }
    // The summary prints the bound as one.
    let (code, human, err) = propid(&["identify", file]);
    assert_eq!(code, 0, "{err}");
    let medians = median_rows(&human);
    assert_eq!(medians.len(), 2, "{human}");
    assert!(medians.iter().all(|l| l.contains("< ")), "{human}");
}
