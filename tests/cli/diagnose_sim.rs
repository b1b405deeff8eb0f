//! The simulated stand hides an effect (`[plant.effects.*]` in its config), `propid sim
//! --record` writes a TSP/1 recording of its experiment plan, `propid diagnose` finds the
//! effect in the recording: the whole chain through the real binary.

use std::process::Command;

fn propid(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn dead_time_hidden_in_the_simulated_stand_is_found_in_its_recording() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("sim.toml");
    std::fs::write(
        &cfg,
        "[plant]\nnoise_rms_n = 0.01\n[plant.effects.dead_time]\ndelay_s = 0.02\n",
    )
    .unwrap();
    let rec = dir.path().join("rec.bin");
    let out = propid(&[
        "sim",
        "--config",
        cfg.to_str().unwrap(),
        "--record",
        rec.to_str().unwrap(),
        "--seconds",
        "10",
    ]);
    assert!(
        out.status.success(),
        "sim: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = propid(&["diagnose", rec.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "diagnose: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let f = v["findings"].as_array().unwrap();
    assert_eq!(f.len(), 1, "{v}");
    assert_eq!(f[0]["effect"], "dead_time");
    let d = f[0]["delay_s"].as_f64().unwrap();
    assert!((d - 0.02).abs() <= 0.0011, "delay {d}");
    // With the delay modelled, the extended model recovers the stand's true dynamics
    // (config defaults: fn 12 Hz, zeta 0.7, 12 N per unit throttle).
    let m = &v["extended"]["model"];
    assert!(
        (m["fn_hz"].as_f64().unwrap() / 12.0 - 1.0).abs() < 0.05,
        "{m}"
    );
    assert!((m["zeta"].as_f64().unwrap() - 0.7).abs() < 0.05, "{m}");
    assert!(
        (m["dc_gain"].as_f64().unwrap() / 12.0 - 1.0).abs() < 0.05,
        "{m}"
    );
    assert!(v["gain"]["rms_ratio"].as_f64().unwrap() < 1.0);
}
