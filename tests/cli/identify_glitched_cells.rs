//! A stand export whose load cell glitched now and then: 5 % of its thrust cells, at random,
//! hold `NaN`, `-`, `inf` or `#N/A` instead of a reading. Those samples are missing (counted in
//! `missing_samples`), and OKID, whose every regression row needs its whole window of lags,
//! lowers its automatic observer order to what the whole windows allow instead of refusing
//! the record (`propid_numerics::okid::gap_observer_order`; before, such exports were refused
//! as "too short for OKID").

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use serde_json::Value;

use crate::support::propid;

/// A 50 Hz staircase of ESC pulses (2 s a level) through a first-order lag of `TAU_S` to
/// 900 gf at full throttle, 2 gf of noise, written as a Tyto-style export with `glitched` of
/// the thrust cells replaced by what stand software writes for a reading it lacks.
fn export(glitched: f64) -> String {
    let levels = [1100, 1300, 1500, 1300, 1700, 1400, 1600, 1200];
    let a = (-0.02f64 / TAU_S).exp();
    let noise = Normal::new(0.0, 2.0).unwrap();
    let mut rng = StdRng::seed_from_u64(3);
    let marks = ["NaN", "-", "inf", "#N/A"];
    let mut x = 0.0;
    let mut out = String::from("Time (s),ESC signal (µs),Thrust (gf)\n");
    for (i, &l) in levels.iter().enumerate() {
        for k in 0..100 {
            x = a * x + (1.0 - a) * 900.0 * (l - 1000) as f64 / 1000.0;
            let t = 0.02 * (i * 100 + k) as f64;
            let cell = if rng.gen_range(0.0..1.0) < glitched {
                marks[rng.gen_range(0..marks.len())].to_string()
            } else {
                format!("{:.2}", x + noise.sample(&mut rng))
            };
            out.push_str(&format!("{t:.3},{l},{cell}\n"));
        }
    }
    out
}

/// The lag's time constant, s.
const TAU_S: f64 = 0.05;

#[test]
fn a_load_cell_that_glitched_in_five_percent_of_its_cells_is_identified() {
    let dir = tempfile::tempdir().unwrap();
    let run = |glitched: f64| {
        let path = dir.path().join(format!("glitched-{glitched}.csv"));
        std::fs::write(&path, export(glitched)).unwrap();
        let (code, out, err) = propid(&["identify", "--json", path.to_str().unwrap()]);
        assert_eq!(code, 0, "{err}");
        serde_json::from_str::<Value>(&out).unwrap()
    };
    let clean = run(0.0);
    let glitched = run(0.05);
    let model = &glitched["model"];
    let missing = model["missing_samples"].as_u64().unwrap();
    assert!((20..=60).contains(&missing), "{missing}");
    assert_eq!(clean["model"]["missing_samples"], 0);
    // The same first-order answer as the clean export: τ and the gain in newtons.
    for v in [&clean, &glitched] {
        let tau = v["model"]["time_constants_s"][0].as_f64().unwrap();
        assert!((tau - TAU_S).abs() < 0.1 * TAU_S, "τ {tau}");
        let gain = v["model"]["dc_gain"].as_f64().unwrap();
        assert!(
            (gain - 0.9 * 9.80665).abs() < 0.02 * 0.9 * 9.80665,
            "{gain}"
        );
    }
}
