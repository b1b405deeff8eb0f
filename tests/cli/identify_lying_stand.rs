//! `propid identify` and `propid replay` of a recording from a stand that lies (issue 27 items
//! 7, 8): clock jumps both ways (the index runs on, `t_us` steps), a HELLO that lies about the
//! rate, absurd finite values among infinite ones. Both read the stream by the one clock rule
//! (`propid_wire::stream::SampleAssembler`): a jump is a `clock_jump` warning and no span of
//! time crosses it; the rate measured is printed beside the HELLO's.

use crate::support::propid;
use serde_json::Value;
use std::path::Path;

/// `propid sim --record` of the 2nd-order plant (fn 12 Hz) at 1 kHz for 20 s with `faults`
/// (lines of its `[faults]` table).
fn record(dir: &Path, faults: &str) -> String {
    let cfg = dir.join("sim.toml");
    std::fs::write(
        &cfg,
        format!("[plant]\nkind = \"second_order\"\n[faults]\n{faults}\n"),
    )
    .unwrap();
    let f = dir.join("r.tsp").to_str().unwrap().to_owned();
    let args = ["sim", "--config", cfg.to_str().unwrap(), "--record", &f];
    let (code, _, err) = propid(&[&args[..], &["--seconds", "20"]].concat());
    assert_eq!(code, 0, "sim --record: {err}");
    f
}

fn identify(file: &str) -> (i32, Value) {
    let (code, out, err) = propid(&["identify", file, "--json"]);
    let v = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out} {err}"));
    (code, v)
}

fn replay(file: &str) -> Vec<Value> {
    let (code, out, err) = propid(&["replay", file]);
    assert_eq!(code, 0, "{err}");
    out.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn warning<'a>(v: &'a Value, kind: &str) -> Option<&'a Value> {
    v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["kind"] == kind)
}

#[test]
fn clock_jumps_both_ways_leave_the_rate_and_the_models_alone() {
    // before: replay published dt 0.021-0.028 s for 0.001 s, identify fn 0.59 Hz; a backward
    // jump gave fn 248 Hz
    for jump in ["25000", "-40000"] {
        let dir = tempfile::tempdir().unwrap();
        let f = record(
            dir.path(),
            &format!("clock_jump_every_samples = 3000\nclock_jump_us = {jump}"),
        );
        let (code, v) = identify(&f);
        assert_eq!(code, 0, "{v}");
        let s = &v["source"];
        assert!(
            (s["rate_hz"].as_f64().unwrap() - 1000.0).abs() < 1e-6,
            "{s}"
        );
        assert_eq!(s["nominal_rate_hz"], 1000.0, "{s}");
        let w = warning(&v, "clock_jump").unwrap_or_else(|| panic!("{v}"));
        let jumps = w["value"].as_f64().unwrap();
        assert!(jumps >= 3.0, "{w}");
        assert_eq!(s["tsp1"]["assemble"]["clock_jumps"].as_f64(), Some(jumps));
        let fn_hz = v["model"]["fn_hz"].as_f64().unwrap();
        assert!((fn_hz - 12.0).abs() < 1.5, "fn {fn_hz}");
        let lines = replay(&f);
        let models: Vec<&Value> = lines.iter().filter(|l| l["type"] == "model").collect();
        assert!(models.len() >= 4, "{lines:#?}");
        for m in models {
            assert!((m["dt_s"].as_f64().unwrap() - 1e-3).abs() < 1e-6, "{m}");
            let f = m["fn_hz"].as_f64().unwrap();
            assert!(f > 9.0 && f < 15.0, "{m}");
        }
        let said = lines.iter().filter(|l| l["kind"] == "clock_jump").count();
        assert_eq!(said as f64, jumps, "the daemon's rule is identify's");
    }
}

#[test]
fn a_hello_rate_that_lies_is_printed_beside_the_measured_one() {
    let dir = tempfile::tempdir().unwrap();
    let f = record(dir.path(), "hello_rate_hz = 65535");
    let (code, v) = identify(&f);
    assert_eq!(code, 0, "{v}");
    let s = &v["source"];
    assert!(
        (s["rate_hz"].as_f64().unwrap() - 1000.0).abs() < 1e-6,
        "{s}"
    );
    assert_eq!(s["nominal_rate_hz"], 65535.0);
    assert_eq!(
        warning(&v, "hello_rate_mismatch").unwrap()["value"],
        65535.0
    );
    let (_, human, _) = propid(&["identify", &f]);
    assert!(
        human.contains("rate      1000.0000 Hz (HELLO: 65535.0000 Hz)"),
        "{human}"
    );
    let lines = replay(&f);
    let w: Vec<&Value> = lines
        .iter()
        .filter(|l| l["kind"] == "hello_rate_mismatch")
        .collect();
    assert_eq!(w.len(), 1, "{lines:#?}");
    assert_eq!(w[0]["hello_hz"], 65535);
}

#[test]
fn a_hello_claiming_0_hz_in_a_binary_recording_is_a_lie() {
    let dir = tempfile::tempdir().unwrap();
    let f = record(dir.path(), "hello_rate_hz = 0");
    let (code, v) = identify(&f);
    assert_eq!(code, 0, "{v}");
    let s = &v["source"];
    assert!(
        (s["rate_hz"].as_f64().unwrap() - 1000.0).abs() < 1e-6,
        "{s}"
    );
    assert_eq!(warning(&v, "hello_rate_mismatch").unwrap()["value"], 0.0);
    let lines = replay(&f);
    let w: Vec<&Value> = lines
        .iter()
        .filter(|l| l["kind"] == "hello_rate_mismatch")
        .collect();
    assert_eq!(w.len(), 1, "{lines:#?}");
    assert_eq!(w[0]["hello_hz"], 0);
}

#[test]
fn absurd_finite_values_are_refused_by_identify_and_never_published_by_replay() {
    let dir = tempfile::tempdir().unwrap();
    let f = record(dir.path(), "absurd_thrust_every_samples = 97");
    let (code, v) = identify(&f);
    assert_ne!(code, 0, "{v}");
    let lines = replay(&f);
    // before: models with dc_gain -1.9e39 entered the schedule
    assert!(lines.iter().all(|l| l["type"] != "model"), "{lines:#?}");
    let refused: Vec<&Value> = lines
        .iter()
        .filter(|l| l["kind"] == "model_unreliable")
        .collect();
    assert!(!refused.is_empty());
    assert!(refused.iter().any(|w| w["reasons"]
        .as_array()
        .unwrap()
        .contains(&"implausible_dc_gain".into())));
    let schedule = lines.iter().find(|l| l["type"] == "schedule").unwrap();
    assert_eq!(schedule["models"].as_array().unwrap().len(), 0);
}
