//! Logs from stands propid has never seen (issue 11, item 1): the dialects of
//! `propid_testkit::dialects` — one simulated stand written as many benches write their exports —
//! each read by `identify --json` and `diagnose --json` through the binary, in the units it comes
//! in (`source.units`, `source.input_range`), or refused (exit 3) with a message naming what to
//! pass, and identified: the thrust gain, every step's dead time and time constant within
//! tolerance of the stand's own.

use crate::support::propid;
use propid_testkit::dialects::{dialects, Dialect, LEVELS, TRUTH};
use serde_json::Value;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// What is wrong with the reading of one dialect (empty: read right).
fn check(d: &Dialect, dir: &std::path::Path) -> Vec<String> {
    let mut bad = Vec::new();
    let path = dir.join(format!("{}.csv", d.name));
    std::fs::write(&path, &d.text).unwrap();
    let file = path.to_str().unwrap();
    let e = &d.expect;
    if let Some(mentions) = &e.refused_without_args {
        let (code, out, err) = propid(&["identify", file, "--json"]);
        if code != 3 || !out.is_empty() {
            bad.push(format!(
                "without {:?}: exit {code}, not a refusal (exit 3)",
                e.args
            ));
        }
        for m in mentions {
            if !err.contains(m) {
                bad.push(format!("refusal does not name {m:?}: {err}"));
            }
        }
    }
    let run = |cmd: &str| {
        let mut args = vec![cmd, file, "--json"];
        args.extend(e.args.iter().copied());
        let (code, out, err) = propid(&args);
        match code {
            0 => serde_json::from_str::<Value>(&out).map_err(|x| format!("{cmd}: {x}")),
            _ => Err(format!("{cmd} {:?}: exit {code}: {err}", e.args)),
        }
    };
    let v = match run("identify") {
        Ok(v) => v,
        Err(x) => {
            bad.push(x);
            return bad;
        }
    };
    let s = &v["source"];
    for &(key, column, unit, factor) in &e.units {
        let u = &s["units"][key];
        let ok = u["column"] == column
            && u["unit"] == unit
            && (f(&u["factor"]) / factor - 1.0).abs() < 1e-9;
        if !ok {
            bad.push(format!(
                "units.{key} = {u}, not {column} in {unit} (x{factor})"
            ));
        }
    }
    if s["input_range"] != serde_json::json!(e.input_range)
        || s["input_range_from"] != e.input_range_from
    {
        bad.push(format!(
            "input_range {} from {}, not {:?} from {}",
            s["input_range"], s["input_range_from"], e.input_range, e.input_range_from
        ));
    }
    for (pointer, want) in &e.source {
        if s.pointer(pointer) != Some(want) {
            bad.push(format!(
                "source{pointer} = {:?}, not {want}",
                s.pointer(pointer)
            ));
        }
    }
    let gain = f(&v["model"]["dc_gain"]);
    let gain_ok = (gain / e.gain_n - 1.0).abs() < 0.03;
    if !gain_ok {
        bad.push(format!(
            "DC gain {gain}, not {} N per unit throttle",
            e.gain_n
        ));
    }
    let warned = v["warnings"]
        .as_array()
        .is_some_and(|w| w.iter().any(|w| w["kind"] == "nonpositive_gain"));
    if warned != (e.gain_n <= 0.0) {
        bad.push(format!(
            "identify warnings {} (a gain ≤ 0 must be warned of, only then)",
            v["warnings"]
        ));
    }
    let steps = v["steps"].as_array().cloned().unwrap_or_default();
    if steps.len() != LEVELS.len() - 1 {
        bad.push(format!("{} steps, not {}", steps.len(), LEVELS.len() - 1));
    }
    let dt = f(&v["model"]["dt_s"]);
    for st in &steps {
        let (dead, tau) = (f(&st["dead_time_s"]), f(&st["time_constant_s"]));
        let ok = (dead - TRUTH.dead_s).abs() <= 1.5 * dt && (tau / TRUTH.tau_s - 1.0).abs() < 0.15;
        if !ok {
            bad.push(format!(
                "step {st}: not dead time {} s, time constant {} s",
                TRUTH.dead_s, TRUTH.tau_s
            ));
        }
    }
    match run("diagnose") {
        Err(x) => bad.push(x),
        Ok(dv) => {
            let nonpositive = dv["warnings"]
                .as_array()
                .is_some_and(|w| w.iter().any(|w| w["kind"] == "nonpositive_gain"));
            if nonpositive != (e.gain_n <= 0.0) {
                bad.push(format!(
                    "diagnose warnings {} (a gain ≤ 0 must be warned of, only then)",
                    dv["warnings"]
                ));
            }
        }
    }
    bad
}

#[test]
fn exports_of_unseen_stands_are_read_in_their_units_or_refused_naming_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let all = dialects();
    assert!(all.len() >= 12, "{} dialects", all.len());
    let failures: Vec<String> = all
        .iter()
        .flat_map(|d| {
            check(d, dir.path())
                .into_iter()
                .map(|m| format!("{}: {m}", d.name))
        })
        .collect();
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
