//! `propid demo`, the README's first command, through the real binary: the simulated stand on a
//! pty inside the process, the daemon against it, one model per operating point near the
//! simulator's true plant, the gain schedule, and a clean link.

use serde_json::Value;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_propid");

/// The demo's three models checked against the simulator's plant.
fn check_demo(extra: &[&str]) {
    let out = Command::new(BIN)
        .args(["demo", "--json"])
        .args(extra)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let lines: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect();
    let truth = propid_sim::SimConfig::default().plant;
    let models: Vec<&Value> = lines.iter().filter(|l| l["type"] == "model").collect();
    assert_eq!(models.len(), 3, "{lines:#?}");
    for (m, level) in models.iter().zip([0.3, 0.45, 0.6]) {
        assert_eq!(m["operating_point"], level);
        let rel = |k: &str, t: f64| (m[k].as_f64().unwrap() / t - 1.0).abs();
        assert!(rel("fn_hz", truth.fn_hz) < 0.05, "{m}");
        assert!(rel("zeta", truth.zeta) < 0.1, "{m}");
        assert!(rel("dc_gain", truth.gain_n_per_throttle) < 0.05, "{m}");
    }
    let schedule = lines.iter().find(|l| l["type"] == "schedule").unwrap();
    assert_eq!(schedule["models"].as_array().unwrap().len(), 3);
    let stats = lines.last().unwrap();
    assert_eq!(stats["type"], "stats");
    assert_eq!(stats["samples_lost"], 0);
    assert_eq!(stats["overflows"], 0);
    assert_eq!(stats["models_unreliable"], 0);
}

#[test]
fn demo_identifies_the_simulated_plant_at_three_operating_points() {
    check_demo(&[]);
}

#[test]
fn demo_against_a_csv_stand_gives_the_same_operating_points() {
    // the demo's stand speaking the CSV fallback: slow ramps (steps below the level
    // tolerance) and pulses found from the throttle column
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("sim.toml");
    std::fs::write(
        &cfg,
        "[stand]\nprotocol = \"csv\"\nsample_rate_hz = 250\n[experiment]\n\
         levels = [0.3, 0.45, 0.6]\npulse_amplitudes = [0.1, 0.15]\nramp_ms = 300\n\
         settle_ms = 500\npulse_spacing_ms = 250\npulses_per_level = 8\n",
    )
    .unwrap();
    check_demo(&["--sim-config", cfg.to_str().unwrap()]);
}
