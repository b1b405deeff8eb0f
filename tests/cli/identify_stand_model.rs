//! `identify` reports the stand's physics (`"stand"`, `docs/stand-model.md`): on a generated
//! Tyto-style export (ESC in µs, thrust in gf refreshed at 7 Hz inside 143 Hz rows behind a
//! load-cell lag, rpm, voltage and current at the row rate) the load cell's lag is reported as
//! the thrust sensor's while the rotor's timing comes from the rpm; and on the shared
//! vanderploeg export when present.

use std::path::Path;

use propid_numerics::stand_model::{
    hold, sense, CurrentLaw, Quantity, RotorLaw, Sensor, SpeedMap, StandParams, Supply,
};
use serde_json::Value;

use crate::identify_real_data::shared;
use crate::support::propid;

const DT: f64 = 1.0 / 143.0;
const ROTOR_TAU_UP: f64 = 0.035;
const ROTOR_TAU_DOWN: f64 = 0.05;
const DEAD: f64 = 0.03;
const CELL_DELAY: f64 = 0.10;
const CELL_TAU: f64 = 0.15;
const REFRESH: f64 = 1.0 / 7.0;

/// The stand: 5" propeller-like, speed in rev/min, thrust in N.
fn stand() -> StandParams {
    StandParams {
        dead_time_s: DEAD,
        map: SpeedMap {
            speed_ref: 24_000.0,
            command_zero: 0.05,
            command_ref: 0.95,
            exponent: 1.0,
            voltage_ref: 16.0,
        },
        rotor: RotorLaw {
            tau_up_s: ROTOR_TAU_UP,
            tau_down_s: ROTOR_TAU_DOWN,
            tau_speed_exponent: 0.3,
            speed_ref: 24_000.0,
        },
        thrust_exponent: 2.0,
        k_t: 12.0 / (24_000.0f64 * 24_000.0),
        k_q: 0.15 / (24_000.0f64 * 24_000.0),
        current: CurrentLaw {
            idle_a: 0.5,
            per_power: 25.0 / 24_000f64.powi(3),
            per_acceleration: 0.0,
        },
        supply: Supply {
            open_circuit_v: 16.0,
            resistance_ohm: 0.05,
        },
    }
}

/// A little deterministic noise.
fn wiggle(k: usize, seed: f64) -> f64 {
    ((k as f64 * 12.9898 + seed).sin() * 43_758.545_3).fract() - 0.5
}

/// The export: `Time (s),ESC signal (µs),Thrust (gf),Voltage (V),Current (A),Motor Electrical
/// Speed (RPM)`, the thrust's last reading repeated between its 7 Hz readings.
pub(crate) fn write_export(path: &Path) {
    let levels_us = [
        1100.0, 1300.0, 1200.0, 1500.0, 1850.0, 1400.0, 1650.0, 1150.0, 1750.0,
    ];
    let per = (1.5 / DT) as usize;
    let us: Vec<f64> = levels_us
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(per))
        .collect();
    let u: Vec<f64> = us.iter().map(|v| (v - 1000.0) / 1000.0).collect();
    let p = stand();
    let course = propid_numerics::stand_model::rotor_course(&p, DT, &u, None);
    let x = |q: Quantity| -> Vec<f64> {
        course
            .speed
            .iter()
            .zip(&course.rate)
            .map(|(&n, &r)| q.of(&p, n, r))
            .collect()
    };
    let cell = Sensor {
        delay_s: CELL_DELAY,
        tau_s: CELL_TAU,
        refresh_s: 0.0,
        offset: 0.0,
        creep_per_s: 0.0,
    };
    let thrust: Vec<f64> = sense(&cell, DT, &x(Quantity::Thrust))
        .iter()
        .enumerate()
        .map(|(k, t)| (t + 0.01 * wiggle(k, 1.0)) / 9.80665e-3)
        .collect();
    let thrust = hold(&thrust, DT, REFRESH);
    let (rpm, current) = (x(Quantity::Speed), x(Quantity::Current));
    let mut s = String::from(
        "Time (s),ESC signal (µs),Thrust (gf),Voltage (V),Current (A),Motor Electrical Speed (RPM)\n",
    );
    for k in 0..u.len() {
        s.push_str(&format!(
            "{:.5},{:.0},{:.2},{:.3},{:.3},{:.0}\n",
            k as f64 * DT,
            us[k],
            thrust[k],
            course.voltage[k],
            current[k] + 0.02 * wiggle(k, 2.0),
            rpm[k] + 20.0 * wiggle(k, 3.0),
        ));
    }
    std::fs::write(path, s).unwrap();
}

fn value(v: &Value, path: &str) -> f64 {
    v.pointer(path)
        .and_then(Value::as_f64)
        .unwrap_or_else(|| panic!("{path}: {v}"))
}

#[test]
fn a_tyto_export_gives_the_rotor_from_rpm_and_the_load_cells_lag_on_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("tyto.csv");
    write_export(&csv);
    let (code, out, err) = propid(&["identify", csv.to_str().unwrap(), "--json"]);
    assert!(code == 0 || code == 4, "{code}: {err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let stand = &v["stand"];
    for key in [
        "esc_dead_time_s",
        "rotor_tau_up_s",
        "rotor_tau_down_s",
        "rotor_tau_speed_exponent",
        "k_t",
        "thrust_exponent",
        "k_q",
    ] {
        assert!(stand[key].get("value").is_some(), "{key}: {stand}");
        assert!(stand[key].get("uncertainty").is_some(), "{key}: {stand}");
    }
    assert_eq!(stand["reference_channel"], "rpm", "{stand}");
    assert_eq!(stand["rotor_tau_up_s"]["from"], "rpm", "{stand}");
    let thrust = &stand["sensors"]["thrust"];
    for key in ["delay_s", "tau_s", "refresh_s"] {
        assert!(thrust[key].get("uncertainty").is_some(), "{key}: {thrust}");
    }
    // The rotor's timing from the rpm, the load cell's lag as the thrust sensor's.
    let near = |path: &str, want: f64, tol: f64| {
        let got = value(stand, path);
        assert!(
            (got - want).abs() <= tol,
            "{path}: {got} vs {want} ± {tol}: {stand}"
        );
    };
    near("/esc_dead_time_s/value", DEAD, 0.01);
    near("/rotor_tau_up_s/value", ROTOR_TAU_UP, 0.01);
    near("/rotor_tau_down_s/value", ROTOR_TAU_DOWN, 0.015);
    near("/sensors/thrust/tau_s/value", CELL_TAU, 0.04);
    near("/sensors/thrust/delay_s/value", CELL_DELAY, 0.04);
    near("/sensors/thrust/refresh_s/value", REFRESH, 0.01);
    near("/thrust_exponent/value", 2.0, 0.1);
    // No torque channel: k_q is refused, with its reason.
    assert!(stand["k_q"]["value"].is_null() && stand["k_q"]["reason"].is_string());
    // Every step is timed on every channel: the thrust's dead time well after the rpm's.
    let steps = v["steps"].as_array().unwrap();
    assert!(steps.len() >= 6, "{}", v["steps"]);
    let late: Vec<f64> = steps
        .iter()
        .filter_map(|s| {
            let c = &s["channels"];
            Some(c["thrust"]["dead_time_s"].as_f64()? - c["rpm"]["dead_time_s"].as_f64()?)
        })
        .collect();
    assert!(late.len() >= 4, "{}", v["steps"]);
    assert!(late.iter().all(|d| *d > 0.05), "{late:?}");
    // The summary prints the figures with their channel.
    let (_, human, _) = propid(&["identify", csv.to_str().unwrap()]);
    assert!(
        human.contains("stand model (the rotor timed on rpm"),
        "{human}"
    );
    assert!(human.contains("(from rpm)"), "{human}");
    assert!(human.contains("step timing per channel"), "{human}");
}

#[test]
fn the_vanderploeg_export_reports_its_stand() {
    let Some(dir) = shared("vanderploeg-rcbenchmark-steps") else {
        return;
    };
    let file = dir.join("90PERCENT_2024-08-13_185523.csv");
    let (code, out, err) = propid(&["identify", file.to_str().unwrap(), "--json"]);
    assert!(code == 0 || code == 4, "{code}: {err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let stand = &v["stand"];
    eprintln!("vanderploeg stand: {stand}");
    assert_eq!(stand["reference_channel"], "rpm", "{stand}");
    // A staircase only up: no spin-down to time.
    assert!(stand["rotor_tau_down_s"]["value"].is_null(), "{stand}");
    let dead = value(stand, "/esc_dead_time_s/value");
    let tau = value(stand, "/rotor_tau_up_s/value");
    assert!((0.0..0.2).contains(&dead), "{stand}");
    assert!(tau > 0.005 && tau < 0.3, "{stand}");
    let e = value(stand, "/thrust_exponent/value");
    assert!((1.5..2.6).contains(&e), "{stand}");
}
