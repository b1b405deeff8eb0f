//! The stand model against its own equations, and its fit on records it generated itself:
//! rpm with a thrust held at 7 Hz behind a load-cell lag, thrust alone, rpm alone.

use super::fit::{fit, Channel, FitInput};
use super::report::{report, NOT_SEPARABLE};
use super::*;
use crate::segment::SegmentRules;

/// Rows at a Tyto export's rate.
const DT: f64 = 1.0 / 143.0;

/// A stand like a 5" propeller's on a Tyto bench (speed in rev/min, thrust in N).
fn truth() -> StandParams {
    StandParams {
        dead_time_s: 0.03,
        map: SpeedMap {
            speed_ref: 20_000.0,
            command_zero: 0.05,
            command_ref: 0.9,
            exponent: 1.0,
            voltage_ref: 16.0,
        },
        rotor: RotorLaw {
            tau_up_s: 0.035,
            tau_down_s: 0.06,
            tau_speed_exponent: 0.5,
            speed_ref: 20_000.0,
        },
        thrust_exponent: 2.0,
        k_t: 15.0 / (20_000.0f64 * 20_000.0),
        k_q: 0.2 / (20_000.0f64 * 20_000.0),
        current: CurrentLaw {
            idle_a: 0.4,
            per_power: 20.0 / 20_000f64.powi(3),
            per_acceleration: 0.0,
        },
        supply: Supply {
            open_circuit_v: 16.0,
            resistance_ohm: 0.0,
        },
    }
}

/// A staircase up and down over several levels, each held 1.5 s.
fn staircase() -> Vec<f64> {
    let levels = [0.2, 0.4, 0.3, 0.6, 0.9, 0.5, 0.7, 0.25, 0.8, 0.2];
    let per = (1.5 / DT) as usize;
    levels
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(per))
        .collect()
}

/// Deterministic Gaussian-like noise (sum of uniforms of a linear congruential generator).
fn noise(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            let mut acc = 0.0;
            for _ in 0..12 {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                acc += (s >> 11) as f64 / (1u64 << 53) as f64;
            }
            sigma * (acc - 6.0)
        })
        .collect()
}

/// A channel logged through `sensor` with noise `sigma`, and its interpolated-rows flags (the
/// rows a held channel only repeats).
fn logged(x: &[f64], sensor: &Sensor, sigma: f64, seed: u64) -> (Vec<f64>, Vec<bool>) {
    let clean = sense(
        &Sensor {
            refresh_s: 0.0,
            ..*sensor
        },
        DT,
        x,
    );
    let noisy: Vec<f64> = clean
        .iter()
        .zip(noise(x.len(), sigma, seed))
        .map(|(a, b)| a + b)
        .collect();
    let held = hold(&noisy, DT, sensor.refresh_s);
    let flags: Vec<bool> = (0..held.len())
        .map(|k| k > 0 && held[k] == held[k - 1])
        .collect();
    (held, flags)
}

fn quantity(p: &StandParams, q: Quantity, u: &[f64]) -> Vec<f64> {
    let c = rotor_course(p, DT, u, None);
    c.speed
        .iter()
        .zip(&c.rate)
        .map(|(&n, &r)| q.of(p, n, r))
        .collect()
}

fn rules() -> SegmentRules {
    SegmentRules::for_record(DT, true)
}

fn close(what: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: {got} vs {want} (± {tol})"
    );
}

#[test]
fn the_rotor_follows_its_lag_per_direction_after_the_dead_time() {
    let p = StandParams {
        rotor: RotorLaw {
            tau_speed_exponent: 0.0,
            ..truth().rotor
        },
        ..truth()
    };
    let per = 300;
    let u: Vec<f64> = [0.2, 0.6, 0.2]
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(per))
        .collect();
    let c = rotor_course(&p, DT, &u, None);
    let n_lo = p.map.speed_ss(0.2, 16.0);
    let n_hi = p.map.speed_ss(0.6, 16.0);
    assert!((c.speed[0] - n_lo).abs() < 1e-9);
    // θ = 0.03 s = 4.29 rows: rows per+4 still at the low speed, per+5 moved a part of a row.
    assert!(
        (c.speed[per + 4] - n_lo).abs() < 1e-9,
        "{}",
        c.speed[per + 4]
    );
    assert!(c.speed[per + 5] > n_lo + 1.0);
    // 63 % of the way one τ_up after the dead time: (n(θ + τ) − n_lo)/(n_hi − n_lo) = 1 − 1/e.
    let t = p.dead_time_s + p.rotor.tau_up_s;
    let k = t / DT;
    let (i, f) = (k.floor() as usize, k - k.floor());
    let n_t = c.speed[per + i] + f * (c.speed[per + i + 1] - c.speed[per + i]);
    let share = (n_t - n_lo) / (n_hi - n_lo);
    close("share after τ_up", share, 1.0 - (-1f64).exp(), 0.01);
    // Down: τ_down.
    let t = p.dead_time_s + p.rotor.tau_down_s;
    let k = t / DT;
    let (i, f) = (k.floor() as usize, k - k.floor());
    let n_t = c.speed[2 * per + i] + f * (c.speed[2 * per + i + 1] - c.speed[2 * per + i]);
    let share = (n_hi - n_t) / (n_hi - n_lo);
    close("share after τ_down", share, 1.0 - (-1f64).exp(), 0.01);
}

#[test]
fn a_sensor_lags_delays_and_holds() {
    let x: Vec<f64> = (0..400).map(|k| if k < 100 { 0.0 } else { 1.0 }).collect();
    let s = Sensor {
        delay_s: 10.0 * DT,
        tau_s: 20.0 * DT,
        refresh_s: 0.0,
        offset: 0.5,
        creep_per_s: 0.0,
    };
    let y = sense(&s, DT, &x);
    // Lag of a step that is a ramp over one row (x linear between rows), then the delay.
    assert!((y[109] - 0.5).abs() < 1e-12, "{}", y[109]);
    let k = 100 + 10 + 20; // one τ after the delayed ramp's middle, about
    assert!(
        (y[k] - 0.5 - (1.0 - (-0.975f64).exp())).abs() < 0.02,
        "{}",
        y[k]
    );
    // A lag of 0 is no lag at all.
    assert_eq!(lag(&x, DT, 0.0), x);
    // Held at 7 Hz in 143 Hz rows: 20 or 21 rows per reading.
    let h = hold(&y, DT, 1.0 / 7.0);
    let changes: Vec<usize> = (1..h.len()).filter(|&k| h[k] != h[k - 1]).collect();
    for w in changes.windows(2) {
        assert!((20..=21).contains(&(w[1] - w[0])), "{changes:?}");
    }
}

#[test]
fn a_held_load_cell_is_told_from_the_rotor_when_the_speed_is_logged() {
    let p = truth();
    let u = staircase();
    let rpm = quantity(&p, Quantity::Speed, &u);
    let thrust = quantity(&p, Quantity::Thrust, &u);
    let (rpm, rpm_flags) = logged(&rpm, &Sensor::default(), 30.0, 1);
    let load_cell = Sensor {
        delay_s: 0.10,
        tau_s: 0.15,
        refresh_s: 1.0 / 7.0,
        offset: 0.05,
        creep_per_s: 0.0,
    };
    let (thrust, thrust_flags) = logged(&thrust, &load_cell, 0.02, 2);
    assert!(thrust_flags.iter().filter(|&&f| f).count() > thrust.len() * 9 / 10);
    let channels = [
        Channel {
            key: "thrust",
            quantity: Quantity::Thrust,
            y: &thrust,
            interpolated: &thrust_flags,
        },
        Channel {
            key: "rpm",
            quantity: Quantity::Speed,
            y: &rpm,
            interpolated: &rpm_flags,
        },
    ];
    let f = fit(&FitInput {
        dt_s: DT,
        command: &u,
        voltage: None,
        channels: &channels,
        rules: rules(),
    })
    .unwrap();
    close("θ", f.dead_time_s.0, 0.03, 0.004);
    close("τ_up", f.tau_up_s.0, 0.035, 0.004);
    close("τ_down", f.tau_down_s.0, 0.06, 0.006);
    close("γ", f.tau_speed_exponent.0, 0.5, 0.1);
    close("u0", f.command_zero.0, 0.05, 0.01);
    close("a", f.map_exponent.0, 1.0, 0.03);
    close("e", f.thrust_exponent.0, 2.0, 0.05);
    let k_t_rad = p.k_t * (60.0 / std::f64::consts::TAU).powi(2);
    close("k_t", f.k_t_rad.unwrap().0 / k_t_rad, 1.0, 0.1);
    let thrust = f.channels.iter().find(|c| c.key == "thrust").unwrap();
    close("thrust delay", thrust.delay_s.unwrap().0, 0.10, 0.03);
    close("thrust lag", thrust.tau_s.unwrap().0, 0.15, 0.03);
    close("thrust refresh", thrust.refresh_s.0, 1.0 / 7.0, DT);
    assert!(f.channels[0].reference && f.channels[0].key == "rpm");
    // Every fitted figure has an uncertainty, small against its value.
    for (name, e) in [
        ("θ", f.dead_time_s),
        ("τ_up", f.tau_up_s),
        ("τ_down", f.tau_down_s),
        ("e", f.thrust_exponent),
        ("delay", thrust.delay_s.unwrap()),
    ] {
        let sd = e.1.unwrap_or_else(|| panic!("{name}: no uncertainty"));
        assert!(sd > 0.0 && sd < 0.02 + 0.1 * e.0.abs(), "{name}: {e:?}");
    }
    let r = report(&f);
    assert_eq!(r.reference_channel, "rpm");
    assert!(r.k_t.value.is_some() && r.k_t.uncertainty.is_some());
    assert_eq!(r.rotor_tau_up_s.from.as_deref(), Some("rpm"));
    assert!(r.sensors["rpm"].tau_s.value.is_none());
    assert!(r.sensors["thrust"].tau_s.value.is_some());
    assert!(r.k_q.value.is_none(), "{:?}", r.k_q);
}

#[test]
fn thrust_alone_gives_the_lags_together_and_refuses_what_needs_the_speed() {
    let p = truth();
    let u = staircase();
    let thrust = quantity(&p, Quantity::Thrust, &u);
    let (thrust, flags) = logged(&thrust, &Sensor::default(), 0.02, 3);
    let channels = [Channel {
        key: "thrust",
        quantity: Quantity::Thrust,
        y: &thrust,
        interpolated: &flags,
    }];
    let f = fit(&FitInput {
        dt_s: DT,
        command: &u,
        voltage: None,
        channels: &channels,
        rules: rules(),
    })
    .unwrap();
    close("θ", f.dead_time_s.0, 0.03, 0.005);
    close("τ_up", f.tau_up_s.0, 0.035, 0.006);
    close("τ_down", f.tau_down_s.0, 0.06, 0.008);
    close("γ", f.tau_speed_exponent.0, 0.5, 0.2);
    close("e", f.thrust_exponent.0, 2.0, 0.08);
    let r = report(&f);
    assert_eq!(r.reference_channel, "thrust");
    assert!(r.k_t.value.is_none() && r.k_t.reason.is_some());
    assert_eq!(
        r.sensors["thrust"].tau_s.reason.as_deref(),
        Some(NOT_SEPARABLE)
    );
    assert!(r.rotor_tau_up_s.note.is_some());
    assert!(r.thrust_exponent.note.is_some());
}

#[test]
fn speed_alone_gives_the_rotor_and_no_load_figures() {
    let p = truth();
    let u = staircase();
    let rpm = quantity(&p, Quantity::Speed, &u);
    let (rpm, flags) = logged(&rpm, &Sensor::default(), 30.0, 4);
    let channels = [Channel {
        key: "rpm",
        quantity: Quantity::Speed,
        y: &rpm,
        interpolated: &flags,
    }];
    let f = fit(&FitInput {
        dt_s: DT,
        command: &u,
        voltage: None,
        channels: &channels,
        rules: rules(),
    })
    .unwrap();
    close("θ", f.dead_time_s.0, 0.03, 0.004);
    close("τ_up", f.tau_up_s.0, 0.035, 0.004);
    close("τ_down", f.tau_down_s.0, 0.06, 0.006);
    close("γ", f.tau_speed_exponent.0, 0.5, 0.1);
    close("n_ref", f.speed_ref_rpm.unwrap().0, 20_000.0, 100.0);
    let r = report(&f);
    assert!(r.thrust_exponent.value.is_none() && r.k_t.value.is_none());
}

#[test]
fn a_staircase_only_up_refuses_the_spin_down() {
    let p = truth();
    let per = (1.5 / DT) as usize;
    let u: Vec<f64> = [0.2, 0.4, 0.6, 0.8]
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(per))
        .collect();
    let rpm = quantity(&p, Quantity::Speed, &u);
    let (rpm, flags) = logged(&rpm, &Sensor::default(), 30.0, 5);
    let channels = [Channel {
        key: "rpm",
        quantity: Quantity::Speed,
        y: &rpm,
        interpolated: &flags,
    }];
    let f = fit(&FitInput {
        dt_s: DT,
        command: &u,
        voltage: None,
        channels: &channels,
        rules: rules(),
    })
    .unwrap();
    close("τ_up", f.tau_up_s.0, 0.035, 0.005);
    let r = report(&f);
    assert!(r.rotor_tau_down_s.value.is_none());
    assert!(r
        .rotor_tau_down_s
        .reason
        .as_deref()
        .unwrap()
        .contains("never falls"));
    // A command that never moves gives no model.
    let flat = vec![0.5; 500];
    let err = fit(&FitInput {
        dt_s: DT,
        command: &flat,
        voltage: None,
        channels: &channels,
        rules: rules(),
    })
    .unwrap_err();
    assert_eq!(err, super::fit::StandModelError::NoCommandChange);
}

/// A rotor that slows by less than its supply sags (`n ∝ V^0.7`, the winding's share of a sag
/// under load): `Structure::voltage_exponent` gives `b` back from rpm and thrust with the
/// measured voltage, and the thrust's and torque's own exponents with `exponent_per_load`.
#[test]
fn the_speeds_voltage_exponent_and_each_loads_own_exponent_are_fitted() {
    use super::fit::{fit_structured, Structure};
    let p = StandParams {
        rotor: RotorLaw {
            tau_speed_exponent: 0.0,
            ..truth().rotor
        },
        ..truth()
    };
    let u = staircase();
    // The supply sags with the command (a bench supply under load), 16.5 → ~13 V.
    let v: Vec<f64> = u.iter().map(|&x| 16.5 - 4.0 * x * x).collect();
    let v_ref = v.iter().sum::<f64>() / v.len() as f64;
    let drive: Vec<f64> = v.iter().map(|&x| v_ref * (x / v_ref).powf(0.7)).collect();
    let course = rotor_course(&p, DT, &u, Some(&drive));
    let rpm: Vec<f64> = course
        .speed
        .iter()
        .zip(noise(u.len(), 10.0, 1))
        .map(|(a, b)| a + b)
        .collect();
    let thrust: Vec<f64> = course
        .speed
        .iter()
        .zip(noise(u.len(), 0.005, 2))
        .map(|(&n, e)| 15.0 * (n / 20_000.0).powf(2.2) + e)
        .collect();
    let torque: Vec<f64> = course
        .speed
        .iter()
        .zip(noise(u.len(), 0.0002, 3))
        .map(|(&n, e)| 0.2 * (n / 20_000.0).powf(2.0) + e)
        .collect();
    let channels = [
        Channel {
            key: "rpm",
            quantity: Quantity::Speed,
            y: &rpm,
            interpolated: &[],
        },
        Channel {
            key: "thrust",
            quantity: Quantity::Thrust,
            y: &thrust,
            interpolated: &[],
        },
        Channel {
            key: "torque",
            quantity: Quantity::Torque,
            y: &torque,
            interpolated: &[],
        },
    ];
    let input = FitInput {
        dt_s: DT,
        command: &u,
        voltage: Some(&v),
        channels: &channels,
        rules: rules(),
    };
    let st = Structure {
        dead_time: true,
        asymmetric: true,
        static_map: true,
        exponent_per_load: true,
        voltage: true,
        voltage_exponent: true,
        ..Structure::default()
    };
    let f = fit_structured(&input, &st, None).unwrap();
    close("b", f.voltage_exponent.unwrap(), 0.7, 0.03);
    let exp = |key: &str| {
        f.fit
            .channels
            .iter()
            .find(|c| c.key == key)
            .and_then(|c| c.exponent)
            .unwrap()
    };
    close("thrust's e", exp("thrust"), 2.2, 0.03);
    close("torque's e", exp("torque"), 2.0, 0.03);
    // n ∝ V (b = 1 held) misses the sag's size: a worse fit of the speed.
    let held = Structure {
        voltage_exponent: false,
        ..st
    };
    let g = fit_structured(&input, &held, None).unwrap();
    let rms = |f: &super::fit::StructuredFit| f.fit.channels[0].rms;
    assert!(rms(&g) > 3.0 * rms(&f), "{} vs {}", rms(&g), rms(&f));
}
