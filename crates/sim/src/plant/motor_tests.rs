//! The motor plant against its own formulas: the static map (thrust ∝ throttle² with the supply
//! sag), the linearisation against finite differences of the simulated plant, the direction of
//! the time constant, the dead time, and the pulse average an exact linear fit sees.

use super::*;

fn motor() -> PlantConfig {
    PlantConfig {
        kind: PlantKind::Motor,
        noise_rms_n: 0.0,
        quantum_n: 0.0,
        discharge_v_per_s: 0.0,
        ..PlantConfig::default()
    }
}

const DT: f64 = 0.004;

/// Thrust of the settled plant at `u` (no noise, no quantisation).
fn settled(cfg: &PlantConfig, u: f64) -> f64 {
    let mut p = Plant::new(cfg, DT, 1).unwrap();
    p.settle(u);
    p.step(u).thrust_n
}

#[test]
fn thrust_grows_with_the_square_of_speed_and_the_supply_sags() {
    let cfg = motor();
    let mut p = Plant::new(&cfg, DT, 1).unwrap();
    p.settle(0.5);
    let m = p.step(0.5);
    let eq = equilibrium(&cfg, 0.5, 0.0);
    assert!((m.thrust_n - eq.thrust_n).abs() < 1e-9, "{m:?} {eq:?}");
    // T = k_T n², the speed 2.5 % below rpm_at_reference with the loaded battery
    let k_t = cfg.motor.k_t(&cfg);
    assert!((m.thrust_n - k_t * m.rpm * m.rpm).abs() < 1e-9);
    assert!(m.rpm < cfg.rpm_at_reference && m.rpm > 0.95 * cfg.rpm_at_reference);
    assert!((m.voltage_v - eq.voltage_v).abs() < 1e-9);
    // the static map is about quadratic: twice the throttle, about four times the thrust
    let r = settled(&cfg, 0.6) / settled(&cfg, 0.3);
    assert!(r > 3.5 && r < 4.0, "{r}");
    // and without internal resistance exactly quadratic
    let stiff = PlantConfig {
        internal_resistance_ohm: 0.0,
        ..motor()
    };
    let r = settled(&stiff, 0.6) / settled(&stiff, 0.3);
    assert!((r - 4.0).abs() < 1e-9, "{r}");
}

#[test]
fn the_linearised_gain_is_the_slope_of_the_static_map_and_grows_with_throttle() {
    let cfg = motor();
    let mut last = 0.0;
    for u in [0.3, 0.45, 0.6] {
        let lin = cfg.linearise(u, DT, 0.0).unwrap();
        let h = 1e-5;
        let slope = (settled(&cfg, u + h) - settled(&cfg, u - h)) / (2.0 * h);
        assert!(
            (lin.gain_n_per_throttle / slope - 1.0).abs() < 1e-6,
            "{u}: {lin:?} vs {slope}"
        );
        // ∝ u₀ without sag; the sag (more at more current) takes some of it back
        assert!(lin.gain_n_per_throttle > 1.15 * last, "{u}: {lin:?}");
        last = lin.gain_n_per_throttle;
        assert!(lin.sag > 0.0 && lin.sag < 0.2, "{lin:?}");
        assert!(lin.tau_down_s > lin.tau_up_s);
    }
    assert!(PlantConfig::default().linearise(0.5, DT, 0.0).is_none());
}

#[test]
fn small_steps_follow_the_linearised_time_constant_of_their_direction() {
    let cfg = motor();
    let lin = cfg.linearise(0.45, DT, 0.0).unwrap();
    for (du, tau) in [(0.002, lin.tau_up_s), (-0.002, lin.tau_down_s)] {
        let mut p = Plant::new(&cfg, DT, 1).unwrap();
        p.settle(0.45);
        let y0 = p.step(0.45).thrust_n;
        let y: Vec<f64> = (0..400).map(|_| p.step(0.45 + du).thrust_n - y0).collect();
        let fin = y[399];
        assert!(
            (fin / (lin.gain_n_per_throttle * du) - 1.0).abs() < 0.01,
            "{fin}"
        );
        // dead time d samples, then the sampled lag: y_k = fin (1 − a^(k − d)), a = e^(−dt/τ)
        let d = lin.dead_time_samples;
        assert_eq!(d, 2);
        assert!(y[d].abs() < 1e-9 && y[d + 1].abs() > 1e-4, "{:?}", &y[..4]);
        let k = d + 10;
        let est = -(10.0 * DT) / (1.0 - y[k] / fin).ln();
        assert!((est / tau - 1.0).abs() < 0.02, "{est} vs {tau}");
    }
}

#[test]
fn the_pulse_average_is_what_pulses_of_both_signs_give() {
    let cfg = motor();
    let lin = cfg.linearise(0.45, DT, 0.0).unwrap();
    let h = lin.pulse_average(200);
    let mut avg = vec![0.0; 200];
    for a in [0.01, -0.01] {
        let mut p = Plant::new(&cfg, DT, 1).unwrap();
        p.settle(0.45);
        let base = p.step(0.45).thrust_n;
        let y: Vec<f64> = (0..200)
            .map(|k| p.step(if k == 0 { 0.45 + a } else { 0.45 }).thrust_n - base)
            .collect();
        // y[k] is measured at the start of sample k, the pulse held during sample 0: Y_k
        for k in 0..200 {
            avg[k] += y[k] / a / 2.0;
        }
    }
    let sum: f64 = h.iter().sum();
    assert!((sum / (lin.gain_n_per_throttle * lin.pulse_gain_factor) - 1.0).abs() < 1e-3);
    let peak = h.iter().cloned().fold(0.0, f64::max);
    for k in 0..200 {
        assert!(
            (avg[k] - h[k]).abs() < 0.01 * peak,
            "k={k} {} vs {}",
            avg[k],
            h[k]
        );
    }
}

#[test]
fn motor_keys_are_checked_and_parse_from_toml() {
    let cfg: PlantConfig = toml::from_str("kind = \"motor\"\n[motor]\ntau_up_s = 0.02\n").unwrap();
    assert_eq!(cfg.kind, PlantKind::Motor);
    assert_eq!(cfg.motor.tau_up_s, 0.02);
    assert_eq!(cfg.motor.tau_down_s, MotorConfig::default().tau_down_s);
    assert!(toml::from_str::<PlantConfig>("kind = \"jet\"\n").is_err());
    assert!(toml::from_str::<PlantConfig>("[motor]\ntau = 1.0\n").is_err());
    let bad = PlantConfig {
        motor: MotorConfig {
            tau_down_s: 0.0,
            ..MotorConfig::default()
        },
        ..motor()
    };
    match Plant::new(&bad, DT, 0) {
        Err(PlantError::InvalidParameter { key, .. }) => assert_eq!(key, "plant.motor.tau_down_s"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn core_effects_of_the_second_order_plant_are_refused_on_the_motor_not_ignored() {
    use crate::effects::{AsymmetricDynamics, StiffnessNonlinearity};
    let mut cfg = motor();
    cfg.effects.asymmetric_dynamics = Some(AsymmetricDynamics {
        up_scale: 1.0,
        down_scale: 2.0,
    });
    match Plant::new(&cfg, DT, 0) {
        Err(e @ PlantError::NotForKind { key, .. }) => {
            assert_eq!(key, "plant.effects.asymmetric_dynamics");
            assert!(e.to_string().contains("tau_down_s"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    cfg.effects.asymmetric_dynamics = None;
    cfg.effects.stiffness_nonlinearity = Some(StiffnessNonlinearity { k3_per_k1: 0.01 });
    match Plant::new(&cfg, DT, 0) {
        Err(PlantError::NotForKind { key, .. }) => {
            assert_eq!(key, "plant.effects.stiffness_nonlinearity")
        }
        other => panic!("{other:?}"),
    }
    // the 2nd-order plant takes both
    cfg.kind = PlantKind::SecondOrder;
    assert!(Plant::new(&cfg, DT, 0).is_ok());
}

#[test]
fn the_stand_model_steps_the_motor_plant_and_its_fit_finds_the_plant_again() {
    use propid_numerics::segment::SegmentRules;
    use propid_numerics::stand_model::fit::{fit, Channel, FitInput};
    use propid_numerics::stand_model::{rotor_course, Quantity};
    let cfg = PlantConfig {
        noise_rms_n: 0.01,
        ..motor()
    };
    let per = 250;
    let u: Vec<f64> = [0.3, 0.5, 0.4, 0.7, 0.6, 0.35, 0.55]
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(per))
        .collect();
    let mut p = Plant::new(&cfg, DT, 7).unwrap();
    p.settle(u[0]);
    let rows: Vec<Measurement> = u.iter().map(|&x| p.step(x)).collect();
    let col = |f: fn(&Measurement) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let (rpm, thrust, current, voltage) = (
        col(|m| m.rpm),
        col(|m| m.thrust_n),
        col(|m| m.current_a),
        col(|m| m.voltage_v),
    );
    // One home for the physics: the model's rotor under the plant's own voltage is the
    // plant's rotor, row by row.
    let truth = cfg.motor.stand_params(&cfg, DT);
    let course = rotor_course(&truth, DT, &u, Some(&voltage));
    for (k, (model, plant)) in course.speed.iter().zip(&rpm).enumerate() {
        assert!((model - plant).abs() < 1e-6, "row {k}");
    }
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
            key: "current",
            quantity: Quantity::Current,
            y: &current,
            interpolated: &[],
        },
    ];
    let f = fit(&FitInput {
        dt_s: DT,
        command: &u,
        voltage: Some(&voltage),
        channels: &channels,
        rules: SegmentRules::for_record(DT, true),
    })
    .unwrap();
    let close = |what: &str, got: f64, want: f64, tol: f64| {
        assert!((got - want).abs() <= tol, "{what}: {got} vs {want} ± {tol}")
    };
    close("θ", f.dead_time_s.0, 2.0 * DT, 0.001);
    close("τ_up", f.tau_up_s.0, cfg.motor.tau_up_s, 0.001);
    close("τ_down", f.tau_down_s.0, cfg.motor.tau_down_s, 0.0015);
    close("γ", f.tau_speed_exponent.0, 0.0, 0.05);
    close("e", f.thrust_exponent.0, 2.0, 0.02);
    let k_t_rad = truth.k_t * (60.0 / std::f64::consts::TAU).powi(2);
    close("k_t", f.k_t_rad.unwrap().0 / k_t_rad, 1.0, 0.02);
    close("u0", f.command_zero.0, 0.0, 0.01);
    close(
        "R",
        f.supply_resistance_ohm.unwrap().0,
        cfg.internal_resistance_ohm,
        0.01,
    );
}
