//! `propid demo`, the README's first command, through the real binary: the simulated stand on a
//! pty inside the process, the daemon against it, one model per operating point near the
//! simulator's true plant, the gain schedule, and a clean link. The built-in stand is the motor
//! plant (its truth changes with the level); a `--sim-config` without `kind` is the 2nd-order
//! plant (one truth everywhere).

use serde_json::Value;
use std::process::Command;

use crate::support::propid;

const BIN: &str = env!("CARGO_BIN_EXE_propid");

/// The built-in demo's motor: each printed model row `t throttle gain ± sd (truth) off% τ
/// (τ_up/τ_down) θ (θ_truth)` within the tolerances the demo states (src/cli/demo/truth.rs:
/// gain 15 %, τ within [0.8 τ_up, 1.2 τ_down], dead time 1.5 samples of 4 ms), and the gain
/// growing with the level as the truth's does.
#[test]
fn demo_of_the_motor_prints_models_beside_the_linearised_truth_and_the_gain_grows() {
    let (code, out, err) = propid(&["demo"]);
    assert_eq!(code, 0, "{err}");
    let rows: Vec<Vec<f64>> = out
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .take_while(|l| !l.contains('|'))
        .map(|l| {
            l.replace(['(', ')', '/', '±', '%'], " ")
                .split_whitespace()
                .map(|t| t.parse::<f64>().unwrap_or_else(|e| panic!("{l}: {t}: {e}")))
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 3, "{out}");
    let (mut last_gain, mut last_truth) = (0.0, 0.0);
    for (r, level) in rows.iter().zip([0.3, 0.45, 0.6]) {
        let [_, throttle, gain, _sd, truth, off, tau, up, down, dead, dead_truth] = r[..] else {
            panic!("{r:?} in {out}")
        };
        assert_eq!(throttle, level, "{out}");
        assert!(
            (gain / truth - 1.0).abs() <= 0.15,
            "gain {gain} vs {truth}: {out}"
        );
        // the printed truth has two decimals and the offset one: their rounding adds up to
        // 100·0.005/truth + 0.05 percentage points
        assert!(
            (100.0 * (gain / truth - 1.0) - off).abs() <= 0.05 + 0.5 / truth + 1e-9,
            "{r:?}"
        );
        assert!(
            tau >= 0.8 * up && tau <= 1.2 * down,
            "tau {tau} vs {up}/{down}: {out}"
        );
        assert!(up < down, "spin-down slower: {r:?}");
        assert!(
            (dead - dead_truth).abs() <= 6.0,
            "dead {dead} vs {dead_truth}: {out}"
        );
        assert!(gain > last_gain && truth > 1.15 * last_truth, "{out}");
        (last_gain, last_truth) = (gain, truth);
    }
    // the schedule repeats them with the linear fit's offset and the verdict
    let schedule: Vec<&str> = out.lines().filter(|l| l.ends_with("| yes")).collect();
    assert_eq!(schedule.len(), 3, "{out}");
    assert!(out.contains("spin-down is slower than spin-up"), "{out}");
    assert!(
        out.contains(", 0 lost, 0 frames dropped, 3 models"),
        "{out}"
    );
}

/// The demo's three models checked against the simulator's 2nd-order plant.
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
fn demo_against_a_csv_stand_gives_the_same_operating_points() {
    // the demo's stand speaking the CSV fallback, with the 2nd-order plant named: slow ramps
    // (steps below the level tolerance) and pulses found from the throttle column
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("sim.toml");
    std::fs::write(
        &cfg,
        "[stand]\nprotocol = \"csv\"\nsample_rate_hz = 250\n[plant]\nkind = \"second_order\"\n\
         [experiment]\n\
         levels = [0.3, 0.45, 0.6]\npulse_amplitudes = [0.1, 0.15]\nramp_ms = 300\n\
         settle_ms = 500\npulse_spacing_ms = 250\npulses_per_level = 8\n",
    )
    .unwrap();
    check_demo(&["--sim-config", cfg.to_str().unwrap()]);
}
