//! `identify`'s DC gain is the one the record's steady levels show (issue 11): on a staircase
//! through a hardening static map, OKID's realisation alone gave the wrong sign; the published
//! gain is the Markov sequence's own, and a gain the levels contradict is refused (exit 4,
//! `dc_gain_contradicts_levels`, the hint naming both numbers). A thrust that falls as the
//! command rises (a load cell mounted reversed) is warned and its curves fit its magnitude.

use std::path::{Path, PathBuf};

use crate::support::propid;
use propid_testkit::{add_noise, Plant};
use serde_json::Value;

/// A 50 Hz staircase, 300 samples per level, through `T = 10·u³` and a slow overdamped lag
/// (`fn` 0.1 Hz, ζ 2), from steady state, 0.2 N noise.
fn staircase(levels: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let u: Vec<f64> = levels
        .iter()
        .flat_map(|&v| std::iter::repeat(v).take(300))
        .collect();
    let v: Vec<f64> = u.iter().map(|x| 10.0 * x.powi(3)).collect();
    let mut y = Plant::new(0.1, 2.0, 1.0, 0.02).simulate(&v, 0.0).remove(0);
    add_noise(&mut y, 0.2, 1);
    (u, y)
}

fn write_csv(dir: &Path, u: &[f64], y: &[f64]) -> PathBuf {
    let mut text = String::from("t_s,throttle,thrust_N\n");
    for k in 0..u.len() {
        text.push_str(&format!("{:.3},{:.4},{:.5}\n", k as f64 * 0.02, u[k], y[k]));
    }
    let path = dir.join("staircase.csv");
    std::fs::write(&path, text).unwrap();
    path
}

fn identify(file: &Path) -> (i32, Value, String) {
    let (code, out, err) = propid(&["identify", "--json", file.to_str().unwrap()]);
    (
        code,
        serde_json::from_str(&out).expect("one JSON object"),
        err,
    )
}

/// The least-squares slope of the static map's thrust levels, from the JSON.
fn levels_slope(v: &Value) -> f64 {
    let pts: Vec<(f64, f64)> = v["static_map"]["thrust"]["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| (l["throttle"].as_f64().unwrap(), l["mean"].as_f64().unwrap()))
        .collect();
    let n = pts.len() as f64;
    let (mu, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mu) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mu).powi(2)).sum();
    sxy / sxx
}

#[test]
fn a_slow_hardening_staircase_gets_the_gain_of_its_levels() {
    let dir = tempfile::tempdir().unwrap();
    let (u, y) = staircase(&[0.2, 0.35, 0.5, 0.65, 0.8]);
    let (code, v, err) = identify(&write_csv(dir.path(), &u, &y));
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["quality"]["accepted"], true, "{}", v["quality"]);
    let g = v["model"]["dc_gain"].as_f64().unwrap();
    let slope = levels_slope(&v);
    assert!(slope > 5.0, "{slope}");
    assert!(
        g / slope > 0.25 && g / slope < 4.0,
        "gain {g}, levels {slope}"
    );
    let okid = &v["source"]["okid"];
    assert_eq!(okid["dc_gain_from"], "markov_sum", "{okid}");
    // what the realisation alone published before
    assert!(okid["realised_dc_gain"].as_f64().unwrap() <= 0.0, "{okid}");
}

/// A staircase at 50 Hz whose logger stopped during a hold at 0.12 before each level above
/// 0.2 (the noahcurtiss firmware's unlogged holds): in the logged record the thrust falls at
/// every step up, then climbs to the new level. Thrust through `10·u²` and a 2 Hz, ζ 0.7 lag;
/// a torque channel `0.012·T` beside it.
fn staircase_with_unlogged_holds() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (mut full, mut logged) = (Vec::new(), Vec::new());
    for i in 1..=24 {
        let level = 0.04 * i as f64;
        if level > 0.2 {
            full.extend(std::iter::repeat(0.12).take(200));
            logged.extend(std::iter::repeat(false).take(200));
        }
        full.extend(std::iter::repeat(level).take(350));
        logged.extend(std::iter::repeat(true).take(350));
    }
    let v: Vec<f64> = full.iter().map(|x| 10.0 * x * x).collect();
    let t = Plant::new(2.0, 0.7, 1.0, 0.02).simulate(&v, 0.0).remove(0);
    let keep = |x: &[f64]| -> Vec<f64> {
        x.iter()
            .zip(&logged)
            .filter(|(_, k)| **k)
            .map(|(v, _)| *v)
            .collect()
    };
    let (u, mut thrust) = (keep(&full), keep(&t));
    let mut torque: Vec<f64> = thrust.iter().map(|x| 0.012 * x).collect();
    add_noise(&mut thrust, 0.02, 2);
    add_noise(&mut torque, 0.0005, 3);
    (u, thrust, torque)
}

#[test]
fn unlogged_holds_give_the_levels_gain_or_a_refusal_never_the_jumps_sign() {
    let dir = tempfile::tempdir().unwrap();
    let (u, thrust, torque) = staircase_with_unlogged_holds();
    // one output: the Markov sequence's gain, the levels' sign
    let one = write_csv(dir.path(), &u, &thrust);
    let (code, v, err) = identify(&one);
    assert_eq!(code, 0, "{err}");
    let g = v["model"]["dc_gain"].as_f64().unwrap();
    let slope = levels_slope(&v);
    assert!(
        g / slope > 0.25 && g / slope < 4.0,
        "gain {g}, levels {slope}"
    );
    assert!(v["source"]["okid"]["realised_dc_gain"].as_f64().unwrap() < 0.0);
    // two outputs keep the realisation's gains (gain.rs): thrust's contradicts its levels
    let mut text = String::from("t_s,throttle,thrust_N,torque_Nm\n");
    for k in 0..u.len() {
        text.push_str(&format!(
            "{:.3},{:.4},{:.5},{:.6}\n",
            k as f64 * 0.02,
            u[k],
            thrust[k],
            torque[k]
        ));
    }
    let two = dir.path().join("two.csv");
    std::fs::write(&two, text).unwrap();
    let (code, out, err) = propid(&[
        "identify",
        "--json",
        two.to_str().unwrap(),
        "--output",
        "thrust_N",
        "--output",
        "torque_Nm",
    ]);
    assert_eq!(code, 4, "{out} {err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let q = &v["quality"];
    assert_eq!(q["accepted"], false);
    assert!(
        q["flaws"]
            .as_array()
            .unwrap()
            .contains(&Value::from("dc_gain_contradicts_levels")),
        "{q}"
    );
    let hint = q["hint"].as_str().unwrap();
    assert!(hint.contains("steady levels"), "{hint}");
    assert!(
        v["model"]["dc_gain"][0].as_f64().unwrap() < 0.0,
        "{}",
        v["model"]
    );
    assert!(err.contains("dc_gain_contradicts_levels"), "{err}");
}

#[test]
fn a_reversed_load_cell_is_warned_and_its_curves_fit_the_magnitude() {
    let dir = tempfile::tempdir().unwrap();
    let (u, y) = staircase(&[0.2, 0.35, 0.5, 0.65, 0.8]);
    let neg: Vec<f64> = y.iter().map(|v| -v).collect();
    let (code, up, err) = identify(&write_csv(dir.path(), &u, &y));
    assert_eq!(code, 0, "{err}");
    let (code, down, err) = identify(&write_csv(dir.path(), &u, &neg));
    assert_eq!(code, 0, "{err}");
    let kinds: Vec<&str> = down["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w["kind"].as_str())
        .collect();
    assert!(kinds.contains(&"nonpositive_gain"), "{}", down["warnings"]);
    let (m, n) = (&up["static_map"]["thrust"], &down["static_map"]["thrust"]);
    assert!(m.get("falls_with_command").is_none(), "{m}");
    assert_eq!(n["falls_with_command"], true, "{n}");
    let f = |v: &Value| v.as_f64().unwrap();
    // The map of 10·u³: the magnitude's exponent near 3, its k and t_max negated.
    assert!((f(&m["power"]["exponent"]) - 3.0).abs() < 0.5, "{m}");
    assert_eq!(f(&n["power"]["exponent"]), f(&m["power"]["exponent"]));
    assert_eq!(f(&n["power"]["k"]), -f(&m["power"]["k"]));
    assert_eq!(f(&n["expo"]["t_max"]), -f(&m["expo"]["t_max"]));
    assert!(f(&n["expo"]["t_max"]) < -5.0, "{n}");
    let (_, text, _) = propid(&[
        "identify",
        write_csv(dir.path(), &u, &neg).to_str().unwrap(),
    ]);
    assert!(
        text.contains("falls     the thrust falls as the command rises"),
        "{text}"
    );
}

#[test]
fn an_output_of_no_known_quantity_has_its_map_under_output() {
    // A force sensor read in ADC counts: a column the unit table does not know.
    let dir = tempfile::tempdir().unwrap();
    let (u, y) = staircase(&[0.2, 0.35, 0.5, 0.65, 0.8]);
    let path = write_csv(dir.path(), &u, &y);
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replacen("thrust_N", "force_counts", 1);
    std::fs::write(&path, text).unwrap();
    let (code, out, err) = propid(&[
        "identify",
        "--json",
        path.to_str().unwrap(),
        "--output",
        "force_counts",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let m = &v["static_map"]["output"];
    assert_eq!(m["unit"], "?", "{m}");
    assert_eq!(m["levels"].as_array().unwrap().len(), 5, "{m}");
    // The map of 10·u³.
    let e = m["power"]["exponent"].as_f64().unwrap();
    assert!((e - 3.0).abs() < 0.5, "{m}");
    assert!(v["static_map"].get("thrust").is_none());
}
