//! Issue 5: the `model` objects of `propid diagnose --json` carry the model fields of
//! `propid identify --json` (same names, same JSON types). The real binary on one CSV file.

use std::path::Path;
use std::process::Command;

use propid_sim::synth;
use serde_json::Value;

/// Writes a docs/PROTOCOL.md §6 CSV (t_us, throttle 0..10000, thrust_N) of a synthetic case with a
/// hidden dead time, so that `extended` is not null.
fn write_csv(path: &Path) {
    let (mut cfg, _) = synth::case(None, 3).unwrap();
    cfg.effects.dead_time = Some(propid_sim::effects::DeadTime { delay_s: 0.02 });
    let m = synth::run(&cfg, &synth::throttle_plan(), 7).unwrap();
    let mut s = String::from("t_us,throttle,thrust_N\n");
    for k in 0..m.u.len() {
        let t_us = (k as f64 * synth::DT_S * 1e6).round() as u64;
        let thr = (m.u[k] * 10000.0).round() as u64;
        s.push_str(&format!("{t_us},{thr},{:.4}\n", m.y[k]));
    }
    std::fs::write(path, s).unwrap();
}

fn json(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// Checks that `got` has the JSON shape of `want`: objects with the same keys (recursively),
/// arrays against arrays (first elements compared), numbers, strings, booleans alike. A null
/// stands for a number that is not defined (`identify` writes NaN as null too).
fn same_shape(path: &str, want: &Value, got: &Value) {
    match (want, got) {
        (Value::Object(w), Value::Object(g)) => {
            let wk: Vec<&String> = w.keys().collect();
            for k in &wk {
                assert!(g.contains_key(*k), "{path}.{k} missing in diagnose");
                same_shape(&format!("{path}.{k}"), &w[*k], &g[*k]);
            }
        }
        (Value::Array(w), Value::Array(g)) => {
            if let (Some(a), Some(b)) = (w.first(), g.first()) {
                same_shape(&format!("{path}[0]"), a, b);
            }
        }
        (Value::Number(_) | Value::Null, Value::Number(_) | Value::Null) => {}
        (Value::String(_), Value::String(_)) | (Value::Bool(_), Value::Bool(_)) => {}
        _ => panic!("{path}: identify has {want}, diagnose has {got}"),
    }
}

#[test]
fn diagnose_model_objects_have_the_identify_model_fields() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("stand.csv");
    write_csv(&csv);
    let file = csv.to_str().unwrap();
    let ident = json(&["identify", file, "--json"]);
    let diag = json(&["diagnose", file, "--json"]);
    let want = &ident["model"];
    assert!(want.is_object() && want["dc_gain"].is_number(), "{ident}");
    assert!(
        !diag["extended"].is_null(),
        "the hidden dead time must give an extended model: {diag}"
    );
    for stage in ["baseline", "extended"] {
        let got = &diag[stage]["model"];
        let wk: Vec<&String> = want.as_object().unwrap().keys().collect();
        let gk: Vec<&String> = got.as_object().unwrap().keys().collect();
        for k in &wk {
            assert!(gk.contains(k), "{stage}.model lacks `{k}`: {got}");
        }
        // The only key beyond identify's is the extension's terms.
        assert_eq!(gk.len(), wk.len() + 1, "{stage}.model keys {gk:?}");
        assert!(got["terms"].is_object());
        same_shape(&format!("{stage}.model"), want, got);
        // Defined for the output-error model: finite values.
        for k in ["fn_hz", "zeta", "dc_gain", "noise_rms", "dt_s"] {
            assert!(got[k].as_f64().is_some_and(f64::is_finite), "{stage}.{k}");
        }
        for k in ["m", "d", "k"] {
            assert!(got["mass_spring_damper"][k].as_f64().is_some());
        }
        let poles = got["poles_z"].as_array().unwrap().len();
        assert_eq!(got["indicators"].as_array().unwrap().len(), poles);
        assert_eq!(got["order"].as_u64().unwrap() as usize, poles);
    }
    // The Hankel fields come from the core's run on the estimation part.
    let b = &diag["baseline"]["model"];
    assert!(!b["singular_values"].as_array().unwrap().is_empty());
    assert!(b["svd"] == "dense" || b["svd"] == "truncated", "{b}");
}
