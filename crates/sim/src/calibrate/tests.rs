use super::*;
use crate::plant::MotorConfig;
use propid_numerics::segment::SegmentRules;
use propid_numerics::stand_model::fit::{fit, Channel, FitInput};
use propid_numerics::stand_model::simulate;

const DT: f64 = 0.005;

/// A stand with a dead band, a map and thrust exponent of its own, a load cell that lags and
/// is refreshed at a fifth of the rows.
fn truth() -> PlantConfig {
    PlantConfig {
        kind: PlantKind::Motor,
        reference_throttle: 0.8,
        rpm_at_reference: 20_000.0,
        battery_v: 16.0,
        internal_resistance_ohm: 0.06,
        discharge_v_per_s: 0.0,
        idle_current_a: 0.5,
        current_at_reference_a: 12.0,
        noise_rms_n: 0.0,
        quantum_n: 0.0,
        motor: MotorConfig {
            thrust_at_reference_n: 9.0,
            tau_up_s: 0.035,
            tau_down_s: 0.06,
            tau_speed_exponent: 0.4,
            dead_time_s: 0.02,
            command_zero: 0.08,
            speed_map_exponent: 0.9,
            thrust_exponent: 2.1,
            current_per_acceleration: 0.0,
            speed_voltage_exponent: 1.0,
        },
        sensors: SensorsConfig {
            thrust: Some(SensorConfig {
                delay_s: 0.04,
                tau_s: 0.09,
                refresh_s: 5.0 * DT,
                offset: 0.2,
                creep_per_s: 0.0,
            }),
            ..SensorsConfig::default()
        },
        ..PlantConfig::default()
    }
}

/// Steps up and down over several levels, 1.5 s each.
fn command() -> Vec<f64> {
    [0.25, 0.5, 0.35, 0.8, 0.6, 0.3, 0.7, 0.45, 0.25]
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(300))
        .collect()
}

struct Log {
    u: Vec<f64>,
    rpm: Vec<f64>,
    thrust: Vec<f64>,
    thrust_read: Vec<bool>,
    current: Vec<f64>,
    voltage: Vec<f64>,
}

/// What the plant `cfg` logs under `command()`, the thrust held over its refresh interval.
fn log_of(cfg: &PlantConfig) -> Log {
    let u = command();
    let rows = replay(cfg, DT, &u, None).unwrap();
    let col = |f: fn(&Measurement) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let thrust_read: Vec<bool> = (0..u.len()).map(|k| k % 5 == 0).collect();
    Log {
        thrust: hold_on(&col(|m| m.thrust_n), &thrust_read),
        thrust_read,
        rpm: col(|m| m.rpm),
        current: col(|m| m.current_a),
        voltage: col(|m| m.voltage_v),
        u,
    }
}

fn fitted(log: &Log) -> StandFit {
    let interpolated: Vec<bool> = log.thrust_read.iter().map(|r| !r).collect();
    let channels = [
        Channel {
            key: "rpm",
            quantity: Quantity::Speed,
            y: &log.rpm,
            interpolated: &[],
        },
        Channel {
            key: "thrust",
            quantity: Quantity::Thrust,
            y: &log.thrust,
            interpolated: &interpolated,
        },
        Channel {
            key: "current",
            quantity: Quantity::Current,
            y: &log.current,
            interpolated: &[],
        },
    ];
    fit(&FitInput {
        dt_s: DT,
        command: &log.u,
        voltage: Some(&log.voltage),
        channels: &channels,
        rules: SegmentRules::for_record(DT, true),
    })
    .unwrap()
}

fn facts(log: &Log) -> LogFacts {
    LogFacts {
        dt_s: DT,
        supply: fit_supply(DT, &log.voltage, Some(&log.current)),
        thrust_noise_n: 0.0,
        command_low: 0.25,
    }
}

/// `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)` at the rows `at`.
fn fit_pct(y: &[f64], yhat: &[f64], at: &[bool]) -> f64 {
    let rows: Vec<usize> = (0..y.len()).filter(|&k| at.is_empty() || at[k]).collect();
    let mean = rows.iter().map(|&k| y[k]).sum::<f64>() / rows.len() as f64;
    let e: f64 = rows.iter().map(|&k| (y[k] - yhat[k]).powi(2)).sum();
    let d: f64 = rows.iter().map(|&k| (y[k] - mean).powi(2)).sum();
    100.0 * (1.0 - (e / d).sqrt())
}

#[test]
fn a_log_the_sim_wrote_gives_its_parameters_back_in_the_configuration() {
    let cfg = truth();
    let log = log_of(&cfg);
    let f = fitted(&log);
    let got = calibrate(&f, &Extensions::whole(&f), &facts(&log));
    let p = &got.config.plant;
    let close = |what: &str, got: f64, want: f64, tol: f64| {
        assert!(
            (got - want).abs() <= tol * want.abs().max(1e-9),
            "{what}: {got} vs {want} (±{}%)",
            100.0 * tol
        )
    };
    // The reference moves to the log's highest command (0.8 here, as the truth's).
    close("reference_throttle", p.reference_throttle, 0.8, 1e-9);
    close("rpm_at_reference", p.rpm_at_reference, 20_000.0, 0.01);
    close("tau_up_s", p.motor.tau_up_s, 0.035, 0.05);
    close("tau_down_s", p.motor.tau_down_s, 0.06, 0.05);
    close("tau_speed_exponent", p.motor.tau_speed_exponent, 0.4, 0.1);
    assert!(
        (p.motor.dead_time_s - 0.02).abs() <= DT,
        "{}",
        p.motor.dead_time_s
    );
    close("command_zero", p.motor.command_zero, 0.08, 0.1);
    close("speed_map_exponent", p.motor.speed_map_exponent, 0.9, 0.03);
    close("thrust_exponent", p.motor.thrust_exponent, 2.1, 0.02);
    close(
        "thrust_at_reference_n",
        p.motor.thrust_at_reference_n,
        9.0,
        0.02,
    );
    close("battery_v", p.battery_v, 16.0, 0.01);
    close(
        "internal_resistance_ohm",
        p.internal_resistance_ohm,
        0.06,
        0.05,
    );
    close("idle_current_a", p.idle_current_a, 0.5, 0.05);
    close(
        "current_at_reference_a",
        p.current_at_reference_a,
        12.0,
        0.03,
    );
    let s = p.sensors.thrust.expect("a thrust sensor");
    close("thrust tau_s", s.tau_s, 0.09, 0.1);
    assert!((s.delay_s - 0.04).abs() <= DT, "thrust delay {}", s.delay_s);
    close("thrust refresh_s", s.refresh_s, 5.0 * DT, 1e-6);
    close("thrust offset", s.offset, 0.2, 0.05);
    // It is a configuration `propid sim` accepts, and reads back as written.
    let text = to_toml(&got.config, &["test".into()]);
    let back = SimConfig::from_toml_str(&text, "<calibrated>").unwrap();
    assert_eq!(back.plant, got.config.plant);
    assert_eq!(back.stand, got.config.stand);
    assert_eq!(back.experiment, got.config.experiment);
}

#[test]
fn the_calibrated_plant_replayed_scores_as_the_fit_on_every_channel() {
    let log = log_of(&truth());
    let f = fitted(&log);
    let ext = Extensions::whole(&f);
    let cal = calibrate(&f, &ext, &facts(&log));
    // The supply sags: the replay is driven with the log's measured voltage.
    assert!(replays_measured_supply(&cal.config.plant));
    let sim = replay(&cal.config.plant, DT, &log.u, Some(&log.voltage)).unwrap();
    let sensors: Vec<_> = fitted_sensors(&f, &ext)
        .into_iter()
        .map(|(_, q, s)| (q, s))
        .collect();
    let model = simulate(&f.params, DT, &log.u, Some(&log.voltage), &sensors);
    for (c, (key, q, _)) in fitted_sensors(&f, &ext).iter().enumerate() {
        let (y, at): (&[f64], &[bool]) = match q {
            Quantity::Speed => (&log.rpm, &[]),
            Quantity::Thrust => (&log.thrust, &log.thrust_read),
            _ => (&log.current, &[]),
        };
        let s: Vec<f64> = sim
            .iter()
            .map(|m| match q {
                Quantity::Speed => m.rpm,
                Quantity::Thrust => m.thrust_n,
                _ => m.current_a,
            })
            .collect();
        let by_fit = fit_pct(y, &model[c], at);
        let by_sim = fit_pct(y, &s, at);
        assert!(
            (by_fit - by_sim).abs() <= 1.0 && by_fit > 90.0,
            "{key}: fit {by_fit:.2} %, simulated {by_sim:.2} %"
        );
    }
}

#[test]
fn the_supply_fit_holds_a_negative_resistance_at_zero() {
    let i: Vec<f64> = (0..50).map(|k| (k % 7) as f64).collect();
    let v: Vec<f64> = (0..50)
        .map(|k| 16.0 - 0.1 * i[k] - 0.01 * k as f64 * 0.1)
        .collect();
    let s = fit_supply(0.1, &v, Some(&i)).unwrap();
    assert!((s.resistance_ohm - 0.1).abs() < 1e-9 && (s.discharge_v_per_s - 0.01).abs() < 1e-9);
    let rising: Vec<f64> = (0..50).map(|k| 16.0 + 0.1 * i[k]).collect();
    let s = fit_supply(0.1, &rising, Some(&i)).unwrap();
    assert_eq!(s.resistance_ohm, 0.0);
}
