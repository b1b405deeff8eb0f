//! `identify` on a staircase that comes back down (issue 11, the static map): the commands
//! held twice are listed with the shift between their visits (`static_map.thrust.repeats`),
//! and a shift beyond the noise and 2 % of full thrust — a load cell whose zero moved during
//! the run — is the warning `levels_not_repeatable`.

use std::path::{Path, PathBuf};

use crate::support::propid;
use propid_testkit::{add_noise, Plant};
use serde_json::Value;

/// A 50 Hz staircase up 0.2 → 0.8 and down again, 300 samples a level, through `T = 10·u²`
/// and a 3 Hz lag, 0.02 N noise; from the top level on the load cell's zero falls by
/// `zero_shift_n` (a creep that does not come back).
fn up_and_down(dir: &Path, zero_shift_n: f64) -> PathBuf {
    let levels = [0.2, 0.35, 0.5, 0.65, 0.8, 0.65, 0.5, 0.35, 0.2];
    let u: Vec<f64> = levels
        .iter()
        .flat_map(|&v| std::iter::repeat(v).take(300))
        .collect();
    let v: Vec<f64> = u.iter().map(|x| 10.0 * x * x).collect();
    let mut y = Plant::new(3.0, 0.9, 1.0, 0.02).simulate(&v, 0.0).remove(0);
    add_noise(&mut y, 0.02, 5);
    let top = 4 * 300;
    for (k, t) in y.iter_mut().enumerate().skip(top) {
        *t -= zero_shift_n * ((k - top) as f64 / 150.0).min(1.0);
    }
    let mut text = String::from("t_s,throttle,thrust_N\n");
    for k in 0..u.len() {
        text.push_str(&format!("{:.3},{:.4},{:.5}\n", k as f64 * 0.02, u[k], y[k]));
    }
    let path = dir.join(format!("up_and_down_{zero_shift_n}.csv"));
    std::fs::write(&path, text).unwrap();
    path
}

fn identify(file: &Path) -> Value {
    let (code, out, err) = propid(&["identify", "--json", file.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).expect("one JSON object")
}

fn kinds(v: &Value) -> Vec<String> {
    v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w["kind"].as_str().map(str::to_string))
        .collect()
}

#[test]
fn a_zero_that_moved_between_visits_is_warned_and_a_stand_that_repeats_is_not() {
    let dir = tempfile::tempdir().unwrap();
    let steady = identify(&up_and_down(dir.path(), 0.0));
    let repeats = steady["static_map"]["thrust"]["repeats"]
        .as_array()
        .unwrap();
    let at: Vec<f64> = repeats
        .iter()
        .map(|r| r["throttle"].as_f64().unwrap())
        .collect();
    assert_eq!(at, [0.2, 0.35, 0.5, 0.65], "{repeats:?}");
    for r in repeats {
        assert!(r["shift"].as_f64().unwrap().abs() < 0.02, "{r}");
        assert_eq!(r["means"].as_array().unwrap().len(), 2, "{r}");
    }
    assert!(!kinds(&steady).contains(&"levels_not_repeatable".into()));
    // The zero falls 0.3 N (4.7 % of the 6.4 N top level) after the top.
    let moved = identify(&up_and_down(dir.path(), 0.3));
    let w = moved["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["kind"] == "levels_not_repeatable")
        .unwrap_or_else(|| panic!("{}", moved["warnings"]));
    assert!((w["value"].as_f64().unwrap() + 0.3).abs() < 0.03, "{w}");
    let (_, text, _) = propid(&["identify", up_and_down(dir.path(), 0.3).to_str().unwrap()]);
    assert!(
        text.contains("repeats   4 command(s) held again")
            && text.contains("beyond 3 × the visits' spread and 2 % of full scale")
            && text.contains("levels_not_repeatable"),
        "{text}"
    );
}
