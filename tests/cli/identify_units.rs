//! `propid identify` on stand exports in the units they come in (issue 11, item 1): a
//! Tyto/RCbenchmark-style export with a bare `ESC signal` in 0..2047, thrust in gram-force,
//! torque in N·mm and sensor cells left empty between sensor updates; a plain CSV whose
//! `throttle` holds fractions; commands whose scale cannot be decided; files without a header.

use crate::support::propid;
use std::path::{Path, PathBuf};

use serde_json::Value;

fn identify(file: &Path, extra: &[&str]) -> Value {
    let mut args = vec!["identify", file.to_str().unwrap(), "--json"];
    args.extend_from_slice(extra);
    let (code, out, err) = propid(&args);
    assert_eq!(code, 0, "propid {args:?}: {err}");
    serde_json::from_str(&out).expect("one JSON object")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// Deterministic noise in [-1, 1].
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// The staircase of the export: ESC signal (0..2047, no unit) levels, each held `HOLD_S`.
const LEVELS: [f64; 6] = [300.0, 600.0, 900.0, 1200.0, 1500.0, 1800.0];
const HOLD_S: f64 = 2.5;
/// The stand's thrust: `THRUST_GF · x²` at throttle `x`, reached through a dead time and a lag.
const THRUST_GF: f64 = 1800.0;
const DEAD_S: f64 = 0.03;
const TAU_S: f64 = 0.05;

/// A Tyto/RCbenchmark-style export: rows about every 10 ms (jittered), the command on every
/// row, each sensor on its own rows (thrust one in three, torque one in three, rpm one in two,
/// current one in five, voltage one in ten), the other cells empty. Returns the file and, per
/// level, the mean of the file's own thrust cells over the last half of the hold, in gf.
fn tyto_export(dir: &Path, speed_header: &str) -> (PathBuf, Vec<f64>) {
    let mut text = format!(
        "\u{feff}Time (s),ESC signal,Servo 1 (µs),Torque (N·mm),Thrust (gf),Voltage (V),\
         Current (A),{speed_header},App message\n"
    );
    let mut noise = Lcg(7);
    // The plant at 1 ms: first-order lag after a dead time, on the static map's level.
    let total_ms = (LEVELS.len() as f64 * HOLD_S * 1000.0) as usize;
    let cmd_at = |ms: usize| LEVELS[((ms as f64 / 1000.0) / HOLD_S) as usize % LEVELS.len()];
    let dead = (DEAD_S * 1000.0) as usize;
    let mut state = THRUST_GF * (LEVELS[0] / 2047.0).powi(2);
    let mut speed = 26_000.0 * LEVELS[0] / 2047.0;
    let a = (-1e-3 / TAU_S).exp();
    let mut thrust_ms = Vec::with_capacity(total_ms);
    let mut speed_ms = Vec::with_capacity(total_ms);
    for ms in 0..total_ms {
        let x = cmd_at(ms.saturating_sub(dead)) / 2047.0;
        state = a * state + (1.0 - a) * THRUST_GF * x * x;
        speed = a * speed + (1.0 - a) * 26_000.0 * x;
        thrust_ms.push(state);
        speed_ms.push(speed);
    }
    let mut level_cells = vec![Vec::new(); LEVELS.len()];
    let (mut t, mut k) = (0.0f64, 0usize);
    while t < LEVELS.len() as f64 * HOLD_S - 0.02 {
        let ms = ((t * 1000.0) as usize).min(total_ms - 1);
        let x = cmd_at(ms) / 2047.0;
        let cell = |on: bool, v: f64| if on { format!("{v}") } else { String::new() };
        let thrust = thrust_ms[ms] + noise.next();
        if k % 3 == 0 {
            let level = (t / HOLD_S) as usize;
            if t - level as f64 * HOLD_S >= HOLD_S / 2.0 {
                level_cells[level].push(thrust);
            }
        }
        let amps = 25.0 * x.powf(2.5) + 0.3;
        text.push_str(&format!(
            "{t},{},,{},{},{},{},{},\n",
            cmd_at(ms),
            cell(k % 3 == 1, 0.02 * thrust_ms[ms]),
            cell(k % 3 == 0, thrust),
            cell(k % 10 == 5, 16.8 - 0.02 * amps),
            cell(k % 5 == 2, amps),
            cell(
                k % 2 == 0,
                speed_ms[ms]
                    * if speed_header.contains("eRPM") {
                        7.0
                    } else {
                        1.0
                    }
            ),
        ));
        t += 0.010 + 0.002 * noise.next();
        k += 1;
    }
    let path = dir.join("tyto_export.csv");
    std::fs::write(&path, text).unwrap();
    let means = level_cells
        .iter()
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect();
    (path, means)
}

#[test]
fn tyto_export_is_read_from_its_command_in_its_units() {
    let dir = tempfile::tempdir().unwrap();
    let (file, means_gf) = tyto_export(dir.path(), "Motor Electrical Speed (RPM)");
    let v = identify(&file, &["--poles", "14"]);
    let s = &v["source"];
    assert_eq!(
        s["input"], "ESC signal",
        "the command, not steps from the response"
    );
    assert!(s.get("steps").is_none(), "{}", s["steps"]);
    assert_eq!(s["input_range"], serde_json::json!([0.0, 2047.0]));
    assert_eq!(s["input_range_from"], "values: 0..2047 (DShot/raw ESC)");
    let u = &s["units"];
    assert_eq!(
        u["thrust"],
        serde_json::json!({"column": "Thrust (gf)", "unit": "gf", "factor": 0.00980665})
    );
    assert_eq!(u["torque"]["column"], "Torque (N·mm)");
    assert_eq!(
        (u["torque"]["unit"].as_str(), f(&u["torque"]["factor"])),
        (Some("N·mm"), 1e-3)
    );
    // RCbenchmark's electrical speed in RPM is already mechanical: --poles leaves it alone.
    assert_eq!(u["rpm"]["column"], "Motor Electrical Speed (RPM)");
    assert_eq!(
        (u["rpm"]["unit"].as_str(), f(&u["rpm"]["factor"])),
        (Some("RPM"), 1.0)
    );
    assert_eq!(u["current"]["unit"], "A");
    assert_eq!(u["throttle"]["unit"], "raw ESC");
    assert!((f(&u["throttle"]["factor"]) - 1.0 / 2047.0).abs() < 1e-15);
    // Sensors at their own rates are carried, not dropped: almost no sample is missing.
    let samples = s["samples"].as_u64().unwrap();
    assert!(samples > 1400, "{samples}");
    assert!(s["missing"].as_u64().unwrap() <= 3, "{}", s["missing"]);
    let thrust = &s["csv"]["channels"]["thrust"];
    assert!((f(&thrust["own_dt_s"]) - 0.03).abs() < 0.003, "{thrust}");
    assert!(
        thrust["bridged"].as_u64().unwrap() > samples / 2,
        "{thrust}"
    );
    // The static map's thrust levels are the file's own level means, in newtons.
    let levels = v["static_map"]["thrust"]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), LEVELS.len(), "{levels:?}");
    for ((l, want_gf), raw) in levels.iter().zip(&means_gf).zip(LEVELS) {
        assert!((f(&l["throttle"]) - raw / 2047.0).abs() < 1e-3, "{l}");
        let want = want_gf * 0.00980665;
        assert!((f(&l["mean"]) / want - 1.0).abs() < 0.01, "{l} vs {want} N");
    }
    assert_eq!(v["static_map"]["thrust"]["unit"], "N");
    // Its power map T = k·max(u − u0, 0)^e predicts every level above 15 % of full thrust
    // within 12 % (issue 11, "How we will know"): full thrust = the top level's mean.
    let power = &v["static_map"]["thrust"]["power"];
    let (k, u0, e) = (f(&power["k"]), f(&power["u0"]), f(&power["exponent"]));
    let full = levels.iter().map(|l| f(&l["mean"])).fold(0.0, f64::max);
    let mut checked = 0;
    for l in levels {
        let (x, mean) = (f(&l["throttle"]), f(&l["mean"]));
        if mean > 0.15 * full {
            let predicted = k * (x - u0).max(0.0).powf(e);
            assert!(
                (predicted / mean - 1.0).abs() < 0.12,
                "{l}: power map {power} predicts {predicted} N"
            );
            checked += 1;
        }
    }
    assert!(checked >= 4, "{checked} levels above 15 % of {full} N");
    assert_eq!(
        v["static_map"]["rpm"]["levels"].as_array().unwrap().len(),
        6
    );
    // Every step of the staircase carries its dead time and time constant (30 ms and 50 ms in
    // the stand, thrust sampled every 30 ms).
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(steps.len(), LEVELS.len() - 1, "{steps:?}");
    for st in steps {
        assert!((f(&st["dead_time_s"]) - DEAD_S).abs() < 0.015, "{st}");
        assert!(
            (f(&st["time_constant_s"]) / TAU_S - 1.0).abs() < 0.2,
            "{st}"
        );
    }
    // Thrust per throttle, in newtons: between the slopes of T = 17.65 N · x² at the ends.
    let gain = f(&v["model"]["dc_gain"]);
    assert!((3.0..40.0).contains(&gain), "{}", v["model"]["dc_gain"]);
    // With --input none the steps are found in the response instead, and said so.
    let v = identify(&file, &["--input", "none"]);
    assert_eq!(v["source"]["input"], "steps found from the response");
    assert!(v["source"]["steps"]
        .as_array()
        .is_some_and(|s| !s.is_empty()));
    // Their figures, timed from the response: the time constant, no dead time (the command's
    // time is not in the record), no command levels, no static map.
    let steps = v["steps"].as_array().unwrap();
    let timed: Vec<&Value> = steps
        .iter()
        .filter(|st| st["time_constant_s"].is_number())
        .collect();
    assert!(timed.len() >= LEVELS.len() - 2, "{steps:?}");
    for st in steps {
        assert!(
            st["dead_time_s"].is_null() && st["from"].is_null() && st["to"].is_null(),
            "{st}"
        );
    }
    for st in timed {
        assert!(
            (f(&st["time_constant_s"]) / TAU_S - 1.0).abs() < 0.2,
            "{st}"
        );
    }
    assert_eq!(v["static_map"], serde_json::json!({}));
}

#[test]
fn a_speed_in_erpm_needs_the_pole_count_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (file, _) = tyto_export(dir.path(), "Motor Electrical Speed (eRPM)");
    let v = identify(&file, &[]);
    let unread = &v["source"]["csv"]["unread"][0];
    assert_eq!(unread["column"], "Motor Electrical Speed (eRPM)");
    assert!(
        unread["reason"].as_str().unwrap().contains("--poles N"),
        "{unread}"
    );
    assert!(v["static_map"].get("rpm").is_none());
    // The summary says it too.
    let (code, out, err) = propid(&["identify", file.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("left out  Motor Electrical Speed (eRPM):") && out.contains("--poles N"),
        "{out}"
    );
    let v = identify(&file, &["--poles", "14"]);
    let rpm = &v["source"]["units"]["rpm"];
    assert_eq!(rpm["unit"], "eRPM");
    assert!((f(&rpm["factor"]) - 2.0 / 14.0).abs() < 1e-15, "{rpm}");
    // 7 pole pairs: the mechanical speed of the top level is 26 000 · x rev/min again.
    let top = v["static_map"]["rpm"]["levels"][5]["mean"].clone();
    assert!(
        (f(&top) / (26_000.0 * 1800.0 / 2047.0) - 1.0).abs() < 0.01,
        "{top}"
    );
    let (code, _, err) = propid(&["identify", file.to_str().unwrap(), "--poles", "7"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--poles 7"), "{err}");
}

/// `t_s,throttle,thrust_N`: throttle as fractions 0.40/0.45, thrust `8 N` per unit throttle
/// through a 50 ms lag.
#[test]
fn a_throttle_of_fractions_gives_the_dc_gain_in_newtons_per_unit_throttle() {
    let dir = tempfile::tempdir().unwrap();
    let mut noise = Lcg(3);
    let (dt, a) = (0.01, (-0.01f64 / 0.05).exp());
    let mut y = 8.0 * 0.40;
    let mut text = String::from("t_s,throttle,thrust_N\n");
    for k in 0..1200 {
        let u = if (k / 100) % 2 == 0 { 0.40 } else { 0.45 };
        text.push_str(&format!(
            "{},{u},{}\n",
            k as f64 * dt,
            y + 0.002 * noise.next()
        ));
        y = a * y + (1.0 - a) * 8.0 * u;
    }
    let file = dir.path().join("fractions.csv");
    std::fs::write(&file, text).unwrap();
    let v = identify(&file, &["--order", "1"]);
    assert_eq!(v["source"]["input_range"], serde_json::json!([0.0, 1.0]));
    assert_eq!(v["source"]["input_range_from"], "values: 0..1");
    let gain = f(&v["model"]["dc_gain"]);
    assert!(
        (gain / 8.0 - 1.0).abs() < 0.05,
        "DC gain {gain}, not 8 N per unit throttle"
    );
}

#[test]
fn a_command_whose_scale_the_values_cannot_tell_is_refused_naming_the_options() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("Time (s),ESC signal,Thrust (N)\n");
    for k in 0..600 {
        let us = if (k / 100) % 2 == 0 { 1000 } else { 2000 };
        text.push_str(&format!(
            "{},{us},{}\n",
            0.01 * k as f64,
            us as f64 / 1000.0
        ));
    }
    let file = dir.path().join("bare_esc.csv");
    std::fs::write(&file, text).unwrap();
    let (code, _, err) = propid(&["identify", file.to_str().unwrap(), "--json"]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("ESC signal"), "{err}");
    assert!(
        err.contains("--esc-us MIN,MAX") && err.contains("--input-range MIN,MAX"),
        "{err}"
    );
    let v = identify(&file, &["--esc-us", "1000,2000"]);
    assert_eq!(v["source"]["input_range_from"], "--esc-us");
    let v = identify(&file, &["--input-range", "0,2047"]);
    assert_eq!(v["source"]["input_range_from"], "--input-range");
    assert_eq!(v["source"]["input_range"], serde_json::json!([0.0, 2047.0]));
    let (code, _, err) = propid(&["identify", file.to_str().unwrap(), "--input-range", "5,5"]);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn an_input_of_unknown_unit_in_whole_numbers_of_no_usual_range_is_refused_naming_input_range() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("Time (s),setpoint,Thrust (N)\n");
    for k in 0..600 {
        let raw = if (k / 100) % 2 == 0 { 60 } else { 200 };
        text.push_str(&format!(
            "{},{raw},{}\n",
            0.01 * k as f64,
            raw as f64 / 100.0
        ));
    }
    let file = dir.path().join("setpoint_8bit.csv");
    std::fs::write(&file, text).unwrap();
    let path = file.to_str().unwrap();
    let (code, out, err) = propid(&["identify", path, "--json", "--input", "setpoint"]);
    assert_eq!(code, 3, "{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("setpoint") && err.contains("--input-range MIN,MAX"),
        "{err}"
    );
    let v = identify(&file, &["--input", "setpoint", "--input-range", "0,255"]);
    assert_eq!(v["source"]["input_range"], serde_json::json!([0.0, 255.0]));
    assert_eq!(v["source"]["input_range_from"], "--input-range");
    // 255 raw per unit throttle, 0.01 N per raw: 2.55 N per unit throttle.
    let gain = f(&v["model"]["dc_gain"]);
    assert!((gain / 2.55 - 1.0).abs() < 0.05, "DC gain {gain}");
    // A signed signal (a benchmark's voltage) is no command: taken as it is, and said so.
    let mut text = String::from("Time (s),setpoint,Thrust (N)\n");
    for k in 0..600 {
        let raw = if (k / 100) % 2 == 0 { -0.5 } else { 0.5 };
        text.push_str(&format!("{},{raw},{}\n", 0.01 * k as f64, 2.0 + raw));
    }
    std::fs::write(&file, text).unwrap();
    let v = identify(&file, &["--input", "setpoint"]);
    let from = v["source"]["input_range_from"].as_str().unwrap_or_default();
    assert!(from.starts_with("raw"), "{from}");
    assert_eq!(v["source"]["units"]["setpoint"]["factor"], 1.0);
    let (code, out, err) = propid(&["identify", path, "--input", "setpoint"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("taken as it is, factor 1 (raw"), "{out}");
}

#[test]
fn a_file_without_a_command_column_needs_input_none() {
    let dir = tempfile::tempdir().unwrap();
    let rows: String = (0..300)
        .map(|k| format!("{},{}\n", 0.01 * k as f64, if k < 150 { 1.0 } else { 2.0 }))
        .collect();
    let file = dir.path().join("response.csv");
    std::fs::write(&file, format!("t_s,thrust_N\n{rows}")).unwrap();
    let (code, _, err) = propid(&["identify", file.to_str().unwrap()]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("--input none") && err.contains("--input NAME"),
        "{err}"
    );
}

/// The headerless noahcurtiss log (no licence: read from ../shared/data only).
#[test]
fn a_file_without_a_header_is_refused_naming_columns() {
    let root = std::env::var_os("PROPID_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let file = root.join("noahcurtiss-blctrl-steps/robbe12.0.txt");
    if !file.exists() {
        eprintln!(
            "skipped: {} is absent (shared dataset noahcurtiss-blctrl-steps; set \
             PROPID_SHARED_DATA)",
            file.display()
        );
        return;
    }
    let (code, out, err) = propid(&["identify", file.to_str().unwrap(), "--json"]);
    assert_eq!(code, 3, "{out}{err}");
    assert!(out.is_empty(), "{out}");
    assert!(err.contains("--columns"), "{err}");
    assert!(err.contains("no header"), "{err}");
    // Named, its 8-bit command (10..250) is refused too until its range is given.
    let cols = "cmd,current,maxpwm,temp,rpm,res,volt,force";
    let base = [
        "identify",
        file.to_str().unwrap(),
        "--json",
        "--columns",
        cols,
    ];
    let with =
        |extra: &[&'static str]| [&base[..], &["--output", "force", "--fs", "50"], extra].concat();
    let (code, _, err) = propid(&with(&[]));
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("--input-range"), "{err}");
    let (code, out, err) = propid(&with(&["--input-range", "0,255"]));
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["source"]["input"], "cmd");
    assert_eq!(v["source"]["input_range_from"], "--input-range");
}
