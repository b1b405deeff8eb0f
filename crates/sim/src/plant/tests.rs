//! The plant against closed forms (ZOH step, DC gain), its noise, quantisation, saturation,
//! derived channels and configuration checks.

use super::*;

fn clean() -> PlantConfig {
    PlantConfig {
        noise_rms_n: 0.0,
        quantum_n: 0.0,
        discharge_v_per_s: 0.0,
        internal_resistance_ohm: 0.0,
        ..PlantConfig::default()
    }
}

/// Closed-form unit-step response of the continuous 2nd-order system, for comparison.
fn step_response(fn_hz: f64, zeta: f64, t: f64) -> f64 {
    let wn = 2.0 * std::f64::consts::PI * fn_hz;
    if zeta < 1.0 {
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        let phi = zeta.acos();
        1.0 - (-zeta * wn * t).exp() * (wd * t + phi).sin() / (1.0 - zeta * zeta).sqrt()
    } else {
        let r = (zeta * zeta - 1.0).sqrt();
        let (s1, s2) = (-wn * (zeta - r), -wn * (zeta + r));
        1.0 + (s2 * (s1 * t).exp() - s1 * (s2 * t).exp()) / (s1 - s2)
    }
}

#[test]
fn zoh_step_matches_continuous_response_under_and_overdamped() {
    for &(fn_hz, zeta) in &[(12.0, 0.3), (8.0, 1.7)] {
        let cfg = PlantConfig {
            fn_hz,
            zeta,
            ..clean()
        };
        let dt = 1e-3;
        let mut p = Plant::new(&cfg, dt, 1).unwrap();
        for k in 0..500 {
            let m = p.step(0.5);
            let want = 0.5 * cfg.gain_n_per_throttle * step_response(fn_hz, zeta, k as f64 * dt);
            assert!(
                (m.thrust_n - want).abs() < 1e-9,
                "k={k} {} vs {want}",
                m.thrust_n
            );
        }
    }
}

#[test]
fn first_sample_has_no_feedthrough_and_dc_gain_is_k() {
    let cfg = clean();
    let mut p = Plant::new(&cfg, 1e-3, 1).unwrap();
    assert_eq!(p.step(1.0).thrust_n, 0.0);
    assert!(p.step(1.0).thrust_n > 0.0);
    p.settle(0.4);
    let m = p.step(0.4);
    assert!((m.thrust_n - 0.4 * cfg.gain_n_per_throttle).abs() < 1e-12);
}

#[test]
fn same_seed_same_noise_and_noise_has_the_configured_rms() {
    let cfg = PlantConfig {
        quantum_n: 0.0,
        ..PlantConfig::default()
    };
    let run = |seed| {
        let mut p = Plant::new(&cfg, 1e-3, seed).unwrap();
        p.settle(0.5);
        (0..4000).map(|_| p.step(0.5).thrust_n).collect::<Vec<_>>()
    };
    let (a, b, c) = (run(7), run(7), run(8));
    assert_eq!(a, b);
    assert_ne!(a, c);
    let mean = a.iter().sum::<f64>() / a.len() as f64;
    let rms = (a.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
    assert!((rms / cfg.noise_rms_n - 1.0).abs() < 0.1, "rms {rms}");
}

#[test]
fn quantisation_and_adc_saturation() {
    let cfg = PlantConfig {
        noise_rms_n: 0.0,
        quantum_n: 0.05,
        adc_full_scale_n: 5.0,
        ..PlantConfig::default()
    };
    let mut p = Plant::new(&cfg, 1e-3, 1).unwrap();
    p.settle(0.1234);
    let m = p.step(0.1234);
    assert!(((m.thrust_n / 0.05) - (m.thrust_n / 0.05).round()).abs() < 1e-9);
    assert!(!m.adc_saturated);
    p.settle(0.9);
    let m = p.step(0.9);
    assert!(m.adc_saturated);
    assert_eq!(m.thrust_n, 5.0);
}

#[test]
fn derived_channels_are_plausible() {
    let cfg = PlantConfig::default();
    let mut p = Plant::new(&cfg, 1e-3, 1).unwrap();
    p.settle(cfg.reference_throttle);
    let m = p.step(cfg.reference_throttle);
    assert!((m.rpm - cfg.rpm_at_reference).abs() < 1e-9);
    assert!((m.torque_nm - cfg.torque_m * cfg.reference_thrust_n()).abs() < 1e-12);
    let i = cfg.idle_current_a + cfg.current_at_reference_a;
    assert!((m.current_a - i).abs() < 1e-12);
    assert!((m.voltage_v - (cfg.battery_v - cfg.internal_resistance_ohm * i)).abs() < 1e-12);
    p.settle(0.0);
    let m0 = p.step(0.0);
    assert_eq!(m0.rpm, 0.0);
    assert!(m0.voltage_v > m.voltage_v);
}

#[test]
fn bad_parameters_are_refused_with_the_key_named() {
    let bad = [
        PlantConfig {
            fn_hz: f64::NAN,
            ..PlantConfig::default()
        },
        PlantConfig {
            fn_hz: 600.0,
            ..PlantConfig::default()
        },
        PlantConfig {
            zeta: 0.0,
            ..PlantConfig::default()
        },
        PlantConfig {
            noise_rms_n: -1.0,
            ..PlantConfig::default()
        },
        PlantConfig {
            reference_throttle: 1.0,
            ..PlantConfig::default()
        },
    ];
    let keys = [
        "plant.fn_hz",
        "plant.fn_hz",
        "plant.zeta",
        "plant.noise_rms_n",
        "plant.reference_throttle",
    ];
    for (cfg, key) in bad.iter().zip(keys) {
        match Plant::new(cfg, 1e-3, 0) {
            Err(PlantError::InvalidParameter { key: k, .. }) => assert_eq!(k, key),
            other => panic!("expected refusal of {key}, got {other:?}"),
        }
    }
    assert!(Plant::new(&PlantConfig::default(), 0.0, 0).is_err());
}

#[test]
fn config_parses_from_toml_and_refuses_unknown_keys() {
    let cfg: PlantConfig = toml::from_str("fn_hz = 9.5\nzeta = 1.2\n").unwrap();
    assert_eq!(cfg.fn_hz, 9.5);
    assert_eq!(
        cfg.gain_n_per_throttle,
        PlantConfig::default().gain_n_per_throttle
    );
    assert!(toml::from_str::<PlantConfig>("fn_hz = 9.5\nfoo = 1\n").is_err());
}
