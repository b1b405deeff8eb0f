//! A stand whose load cell was not tared and whose ESC draws current at rest
//! (`static_map::offset`): a Tyto-style export in µs and gram-force, a staircase from zero
//! command up to 90 % and back to zero. The thrust's reading at zero command is named
//! (`static_map.thrust.zero_offset`, the `thrust_zero_offset` warning), the power law and the
//! expo describe the thrust above it (e = 2 from throttle 0, a = 1, as the stand's 900 gf·u²),
//! the levels stay as read; the ESC's idle current is the current map's zero; a tared cell
//! gives neither.

use crate::support::propid;
use serde_json::Value;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

const G0: f64 = 9.80665;
/// Throttle levels, each held 3 s at 50 Hz.
const LEVELS: [f64; 11] = [0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.5, 0.0];

/// The export: thrust `900 gf·u²` through a 60 ms lag plus `tare_gf`, current
/// `0.4 A + 25 A·u³`, both with a little deterministic noise.
fn export(tare_gf: f64) -> String {
    let dt = 0.02;
    let a = (-dt / 0.06f64).exp();
    let mut y = 0.0;
    let mut s = String::from("Time (s),ESC signal (µs),Thrust (gf),Current (A)\n");
    let mut k = 0usize;
    for &u in &LEVELS {
        for _ in 0..150 {
            y = a * y + (1.0 - a) * 900.0 * u * u;
            let wobble = ((k * 7919) % 101) as f64 / 100.0 - 0.5;
            let amps = 0.4 + 25.0 * u * u * u + 0.01 * wobble;
            s.push_str(&format!(
                "{:.3},{:.0},{:.2},{amps:.3}\n",
                k as f64 * dt,
                1000.0 + 1000.0 * u,
                y + tare_gf + 2.0 * wobble
            ));
            k += 1;
        }
    }
    s
}

fn identify(dir: &std::path::Path, tare_gf: f64, json: bool) -> (Value, String) {
    let path = dir.join(format!("tare_{tare_gf}.csv"));
    std::fs::write(&path, export(tare_gf)).unwrap();
    let file = path.to_str().unwrap();
    let (code, out, err) = propid(&["identify", file, "--json"]);
    assert_eq!(code, 0, "{err}");
    let human = if json {
        String::new()
    } else {
        propid(&["identify", file]).1
    };
    (serde_json::from_str(&out).unwrap(), human)
}

#[test]
fn an_untared_load_cell_is_named_and_its_curves_fit_the_thrust_above_it() {
    let dir = tempfile::tempdir().unwrap();
    for tare_gf in [30.0, -30.0] {
        let (v, human) = identify(dir.path(), tare_gf, false);
        let map = &v["static_map"]["thrust"];
        let z = f(&map["zero_offset"]["value"]);
        assert!(
            (z - tare_gf * G0 / 1000.0).abs() < 0.002,
            "tare {tare_gf} gf: zero_offset {}",
            map["zero_offset"]
        );
        assert_eq!(map["zero_offset"]["levels"], 2);
        let p = &map["power"];
        let (k, u0, e) = (f(&p["k"]), f(&p["u0"]), f(&p["exponent"]));
        assert!(
            (e - 2.0).abs() < 0.05 && u0.abs() < 0.02,
            "tare {tare_gf}: {p}"
        );
        let a = f(&map["expo"]["a"]);
        assert!(
            (a - 1.0).abs() < 0.03,
            "tare {tare_gf}: expo {}",
            map["expo"]
        );
        // The levels are the file's readings; the zero plus the power law predicts them.
        for l in map["levels"].as_array().unwrap() {
            let (u, mean) = (f(&l["throttle"]), f(&l["mean"]));
            let want = 0.9 * G0 * u * u + tare_gf * G0 / 1000.0;
            assert!((mean - want).abs() < 0.01, "level {l}: not {want}");
            let law = z + k * (u - u0).max(0.0).powf(e);
            assert!((law - mean).abs() < 0.01, "level {l}: the map gives {law}");
        }
        let warned: Vec<&Value> = v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|w| w["kind"] == "thrust_zero_offset")
            .collect();
        assert_eq!(warned.len(), 1, "{}", v["warnings"]);
        assert!(
            warned[0]["message"].as_str().unwrap().contains("not tared"),
            "{}",
            warned[0]
        );
        assert!(
            human.contains("  zero      ") && human.contains("thrust_zero_offset"),
            "{human}"
        );
        // The ESC's idle current.
        let cur = &v["static_map"]["current"];
        assert!(
            (f(&cur["zero_offset"]["value"]) - 0.4).abs() < 0.01,
            "{}",
            cur["zero_offset"]
        );
        assert!(
            (f(&cur["power"]["exponent"]) - 3.0).abs() < 0.1,
            "{}",
            cur["power"]
        );
    }
}

#[test]
fn a_tared_cell_keeps_its_map_through_zero_and_says_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (v, _) = identify(dir.path(), 0.0, true);
    let map = &v["static_map"]["thrust"];
    assert!(map.get("zero_offset").is_none(), "{map}");
    assert!(
        (f(&map["power"]["exponent"]) - 2.0).abs() < 0.05,
        "{}",
        map["power"]
    );
    assert!(
        !v["warnings"].to_string().contains("thrust_zero_offset"),
        "{}",
        v["warnings"]
    );
}
