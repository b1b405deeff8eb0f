//! Logs slower than a motor's response (issue 11: "steps and staircases, as a propulsion
//! engineer reads them", at the rates hobby stands log): a level is a hold longer than a pulse
//! in time as well as in samples (`SegmentRules::at_rate`), so a 20 Hz or a 10 Hz staircase
//! holding each level 1.5 s (30 or 15 samples, under the 32-sample pulse limit) has its steps,
//! static map and cross-validation folds, and a table of steady averages (a row every few
//! seconds) a level per row. The simulated stand of `propid_testkit::dialects` (gain 10 N,
//! time constant 0.08 s, dead time 0.02 s).

use serde_json::Value;

use crate::support::propid;
use propid_testkit::dialects::{stand, LEVELS, TRUTH};

/// The stand sampled every `dt_s`, `Time (s),Throttle (%),Thrust (N)`.
fn write_log(dir: &std::path::Path, dt_s: f64) -> String {
    let mut text = String::from("Time (s),Throttle (%),Thrust (N)\n");
    for s in stand(dt_s, 7) {
        text.push_str(&format!(
            "{:.3},{:.1},{:.4}\n",
            s.t_s,
            100.0 * s.u,
            s.thrust_n
        ));
    }
    let path = dir.join(format!("stand_{}ms.csv", (1e3 * dt_s).round()));
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

fn json(args: &[&str]) -> Value {
    let (code, out, err) = propid(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    serde_json::from_str(&out).unwrap()
}

#[test]
fn a_slow_staircase_has_its_steps_its_map_and_its_folds() {
    let dir = tempfile::tempdir().unwrap();
    for dt in [0.05, 0.1] {
        let file = write_log(dir.path(), dt);
        let v = json(&["identify", &file, "--json"]);
        let steps = v["steps"].as_array().unwrap();
        assert_eq!(steps.len(), LEVELS.len() - 1, "{dt}: {}", v["steps"]);
        let levels = v["static_map"]["thrust"]["levels"].as_array().unwrap();
        assert_eq!(levels.len(), LEVELS.len(), "{dt}");
        for (l, &u) in levels.iter().zip(&LEVELS) {
            let mean = l["mean"].as_f64().unwrap();
            assert!((mean - TRUTH.gain_n * u).abs() < 0.05, "{dt}: {l}");
        }
        for st in steps {
            match dt {
                // 20 Hz resolves the 0.08 s time constant.
                0.05 => {
                    let tau = st["time_constant_s"].as_f64().unwrap();
                    assert!((tau / TRUTH.tau_s - 1.0).abs() < 0.25, "{st}");
                }
                // At 10 Hz it is shorter than a sample: said, not a number.
                _ => {
                    assert_eq!(st["resolvable"], false, "{st}");
                    assert!(st["time_constant_s"].is_null(), "{st}");
                }
            }
        }
        // Diagnose needs 200 samples: the 20 Hz log has 210. Its folds are cut at the steps.
        if dt == 0.05 {
            let d = json(&["diagnose", &file, "--json"]);
            assert_eq!(
                d["validation"]["method"], "blocked_cv",
                "{}",
                d["validation"]
            );
        }
    }
}

/// A stand's step table, `Time (s),ESC signal (µs),Thrust (N)`: one row per command at
/// `times`, each the steady thrust of a propeller (T = 12·u²); identify's JSON.
fn step_table(dir: &std::path::Path, name: &str, times: &[f64]) -> Value {
    let mut text = String::from("Time (s),ESC signal (µs),Thrust (N)\n");
    for (i, t) in times.iter().enumerate() {
        let c = 1150 + 50 * i;
        let u = (c as f64 - 1000.0) / 1000.0;
        text.push_str(&format!("{t},{c},{:.4}\n", 12.0 * u * u));
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let (_, out, err) = propid(&["identify", path.to_str().unwrap(), "--json"]);
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {err}"))
}

#[test]
fn a_table_of_steady_averages_has_a_level_per_row_at_the_commands_it_ran() {
    let dir = tempfile::tempdir().unwrap();
    // A row every 5 s: every row a level, the map's exponent the propeller's.
    let even: Vec<f64> = (0..10).map(|i| 5.0 * f64::from(i)).collect();
    let v = step_table(dir.path(), "even.csv", &even);
    let levels = v["static_map"]["thrust"]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), even.len(), "{}", v["static_map"]);
    let power = &v["static_map"]["thrust"]["power"];
    let e = power["exponent"].as_f64().unwrap();
    assert!((e - 2.0).abs() < 0.05, "{power}");
    // Rows further apart at higher throttle (the stand waits longer to settle, 5 to 19 s as
    // vanderploeg's StepsTestV2 tables): every row is still a level at the command it ran, its
    // mean the row's thrust. Before, the rows were put on a 5 s grid with the thrust
    // interpolated: a level between two rows blended two levels under one command, and the
    // levels after a spacing wider than 7.5 s were dropped as a gap.
    let uneven = [
        0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 49.0, 64.0, 80.0, 97.0, 115.0, 134.0,
    ];
    let v = step_table(dir.path(), "uneven.csv", &uneven);
    let jitter = &v["source"]["csv"]["jitter"];
    assert_eq!(jitter["steady_rows"], true, "{jitter}");
    let levels = v["static_map"]["thrust"]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), uneven.len(), "{}", v["static_map"]);
    for (i, l) in levels.iter().enumerate() {
        let u = (150.0 + 50.0 * i as f64) / 1000.0;
        assert!((l["throttle"].as_f64().unwrap() - u).abs() < 1e-9, "{l}");
        let row = (12.0 * u * u * 1e4).round() / 1e4;
        assert!(
            (l["mean"].as_f64().unwrap() - row).abs() < 1e-9,
            "{l} vs {row}"
        );
    }
}

#[test]
fn diagnose_refuses_a_command_sampled_more_slowly_than_a_motor_settles() {
    // 400 rows a second apart, a steady thrust each: no dynamics to name (before, a 1 Hz
    // table was "explained" by an 11-second dead time and a 0.2 Hz disturbance).
    let dir = tempfile::tempdir().unwrap();
    let levels = [20.0, 40.0, 30.0, 60.0, 50.0];
    let row = |k: usize| levels[(k / 7) % levels.len()];
    let mut text = String::from("Time (s),Throttle (%),Thrust (N)\n");
    for k in 0..400 {
        let u: f64 = row(k);
        text.push_str(&format!("{k},{u},{:.4}\n", 0.001 * u * u));
    }
    let path = dir.path().join("slow_1hz.csv");
    std::fs::write(&path, text).unwrap();
    let (code, out, err) = propid(&["diagnose", path.to_str().unwrap()]);
    assert_eq!(code, 4, "{out}{err}");
    assert!(err.contains("holds no dynamics"), "{err}");
    // A signal in its own units (a benchmark's signed drive voltage) may drive a plant as slow
    // as its samples: not refused by this rule.
    let mut text = String::from("Time (s),drive_V,level_m\n");
    for k in 0..400 {
        let v = row(k) / 10.0 - 4.5;
        text.push_str(&format!("{k},{v:.2},{:.4}\n", 0.3 * v + 0.001 * k as f64));
    }
    let path = dir.path().join("slow_signal.csv");
    std::fs::write(&path, text).unwrap();
    let args = ["diagnose", path.to_str().unwrap(), "--input", "drive_V"];
    let (code, _, err) = propid(&[&args[..], &["--output", "level_m"]].concat());
    assert_eq!(code, 0, "{err}");
}
