//! The calibrated simulation through the binary (`docs/stand-model.md`): `diagnose
//! --sim-config` writes the stand fitted on a generated Tyto-style export as a `propid sim`
//! configuration, `sim --replay-command` replays the export's command through it into a CSV in
//! the export's columns and units that scores as the fit did, and `demo --sim-config` runs the
//! daemon against that stand.

use serde_json::Value;

use crate::identify_stand_model::write_export;
use crate::support::propid;

/// The columns of a CSV text: header names, then the rows' numbers (NaN for an empty cell).
fn columns(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|s| s.trim_start_matches('\u{feff}').to_string())
        .collect();
    let mut cols = vec![Vec::new(); head.len()];
    for l in lines {
        for (c, cell) in l.split(',').enumerate() {
            cols[c].push(cell.parse().unwrap_or(f64::NAN));
        }
    }
    (head, cols)
}

/// `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)`.
fn fit_pct(y: &[f64], yhat: &[f64]) -> f64 {
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let e: f64 = y.iter().zip(yhat).map(|(a, b)| (a - b).powi(2)).sum();
    let d: f64 = y.iter().map(|a| (a - mean).powi(2)).sum();
    100.0 * (1.0 - (e / d).sqrt())
}

#[test]
fn the_calibrated_stand_replays_the_log_within_a_point_of_the_fit_and_runs_the_demo() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("tyto.csv");
    let toml = dir.path().join("stand.toml");
    let sim = dir.path().join("sim.csv");
    write_export(&log);
    let (log_s, toml_s, sim_s) = (
        log.to_str().unwrap(),
        toml.to_str().unwrap(),
        sim.to_str().unwrap(),
    );
    let (code, out, err) = propid(&["diagnose", log_s, "--json", "--sim-config", toml_s]);
    assert_eq!(code, 0, "{err}");
    let d: Value = serde_json::from_str(&out).unwrap();
    let fitted = d["sim_config"]["fit_percent"].as_object().unwrap().clone();
    assert_eq!(fitted.len(), 3, "thrust, rpm, current: {}", d["sim_config"]);
    // The configuration is the stand's: a motor with the load cell's lag on the thrust.
    let cfg = propid_sim::SimConfig::load(&toml).unwrap();
    let cell = cfg.plant.sensors.thrust.expect("a thrust sensor");
    assert!((cell.tau_s - 0.15).abs() < 0.04, "{cell:?}");
    assert!((cell.refresh_s - 1.0 / 7.0).abs() < 0.01, "{cell:?}");

    let (code, out, err) = propid(&[
        "sim",
        "--config",
        toml_s,
        "--replay-command",
        log_s,
        "--out",
        sim_s,
    ]);
    assert_eq!(code, 0, "{err}");
    let r: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(r["type"], "sim_replay", "{r}");
    for (key, f) in &fitted {
        let (f, s) = (f.as_f64().unwrap(), r["fit_percent"][key].as_f64().unwrap());
        eprintln!("{key}: fit {f:.2} %, replay {s:.2} %");
        assert!(
            (f - s).abs() <= 1.0 && f > 80.0,
            "{key}: fit {f}, replay {s}"
        );
    }
    // SIM.csv has the log's columns, in its units: scored from the files, it agrees.
    let (log_head, log_cols) = columns(&std::fs::read_to_string(&log).unwrap());
    let (sim_head, sim_cols) = columns(&std::fs::read_to_string(&sim).unwrap());
    let mut want = log_head.clone();
    want.sort();
    let mut got = sim_head.clone();
    got.sort();
    assert_eq!(got, want);
    let col = |head: &[String], cols: &[Vec<f64>], name: &str| {
        cols[head.iter().position(|h| h == name).unwrap()].clone()
    };
    for (name, key) in [
        ("Motor Electrical Speed (RPM)", "rpm"),
        ("Current (A)", "current"),
    ] {
        let y = col(&log_head, &log_cols, name);
        let s = col(&sim_head, &sim_cols, name);
        let from_files = fit_pct(&y, &s);
        let reported = r["fit_percent"][key].as_f64().unwrap();
        assert!(
            (from_files - reported).abs() < 0.1,
            "{name}: {from_files} vs {reported}"
        );
    }
    let (y, s) = (
        col(&log_head, &log_cols, "Thrust (gf)"),
        col(&sim_head, &sim_cols, "Thrust (gf)"),
    );
    let ymax = y.iter().copied().fold(f64::MIN, f64::max);
    let smax = s.iter().copied().fold(f64::MIN, f64::max);
    assert!((smax / ymax - 1.0).abs() < 0.05, "gf: {smax} vs {ymax}");
}
