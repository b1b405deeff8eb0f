//! Seeded simulated-stand cases for the acceptance harness of `diagnose` (issue 29 items 4 and
//! 6), under three kinds of record (pulses about operating points, steps, a Tyto-style
//! staircase), and the truth a finding is held to: [`case`], the 2nd-order plants and hidden
//! effects of [`crate::synth`] (thrust and voltage); [`stand_case`], motor stands (the `motor`
//! plant: rpm, thrust, current and voltage) with each effect of the stand catalogue hidden.

use propid_numerics::EffectName;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::effects::{BaselineDrift, ExtraMode, PeriodicDisturbance, Saturation, SaturationSignal};
use crate::plant::{MotorConfig, Plant, PlantConfig, PlantError, PlantKind, SensorConfig};
use crate::synth::{self, hide_effect, random_plant, Measured, DT_S};

/// The kind of record a case is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordKind {
    /// [`synth::throttle_plan`]: five operating points with short pulses (15 s).
    Pulse,
    /// Eight levels of 1.5 s, steps up and down of 0.10–0.42 (12 s).
    Step,
    /// Up from 0.30 to 0.72 in steps of 0.06, then down in two steps (0.51, 0.30), 1 s
    /// each (10 s): the shape of a stand's step test.
    Staircase,
}

impl RecordKind {
    /// Every kind, in table order.
    pub const ALL: [RecordKind; 3] = [RecordKind::Pulse, RecordKind::Step, RecordKind::Staircase];

    /// Name in tables.
    pub fn as_str(self) -> &'static str {
        match self {
            RecordKind::Pulse => "pulse",
            RecordKind::Step => "step",
            RecordKind::Staircase => "staircase",
        }
    }

    /// The throttle sequence, one value per sample of [`DT_S`].
    pub fn plan(self) -> Vec<f64> {
        self.plan_at(DT_S)
    }

    /// The throttle sequence, one value per sample of `dt_s`.
    pub fn plan_at(self, dt_s: f64) -> Vec<f64> {
        let held = |levels: &[f64], s: f64| -> Vec<f64> {
            let per = (s / dt_s).round() as usize;
            levels
                .iter()
                .flat_map(|&l| std::iter::repeat(l).take(per))
                .collect()
        };
        match self {
            RecordKind::Pulse => synth::throttle_plan_at(dt_s),
            RecordKind::Step => held(&[0.35, 0.6, 0.4, 0.72, 0.45, 0.55, 0.3, 0.65], 1.5),
            RecordKind::Staircase => held(
                &[0.30, 0.36, 0.42, 0.48, 0.54, 0.60, 0.66, 0.72, 0.51, 0.30],
                1.0,
            ),
        }
    }
}

/// Case `i` of `kind` with effect `name` hidden (`None`: clean): a seeded random plant of
/// [`random_plant`] (overdamped for odd `i`), the effect's parameters drawn by
/// [`hide_effect`], run through [`RecordKind::plan`].
pub fn case(
    kind: RecordKind,
    name: Option<EffectName>,
    i: u64,
) -> Result<(PlantConfig, Measured), PlantError> {
    let len = name.map_or("clean", EffectName::as_str).len() as u64;
    let k = RecordKind::ALL.iter().position(|&x| x == kind).unwrap_or(0) as u64;
    let seed = 0x57a0_0000 + k * 1_000_003 + i * 7919 + len * 104_729;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut cfg = random_plant(&mut rng, i % 2 == 1);
    if let Some(name) = name {
        hide_effect(&mut cfg, name, &mut rng);
    }
    let m = synth::run(&cfg, &kind.plan(), seed ^ 0xabcdef)?;
    Ok((cfg, m))
}

/// The parameter a finding of an effect is held to: the key of the finding's parameters, the
/// true value, and the tolerance (absolute or relative).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Key in the finding's parameters.
    pub key: &'static str,
    /// The true value in the finding's terms.
    pub value: f64,
    /// Largest error accepted.
    pub tolerance: f64,
    /// Whether the error is relative to `value`.
    pub relative: bool,
}

impl Truth {
    /// The error of an estimate (relative or absolute as the truth says).
    pub fn error(&self, estimate: f64) -> f64 {
        let e = (estimate - self.value).abs();
        if self.relative {
            e / self.value.abs()
        } else {
            e
        }
    }

    /// Whether an estimate is within the tolerance.
    pub fn holds(&self, estimate: f64) -> bool {
        self.error(estimate) <= self.tolerance
    }
}

/// The truth of the main parameter of effect `name` hidden in `cfg` (the tolerances of
/// `docs/detection.md`); `v_mean` is the record's mean supply voltage (`diagnose` reports a
/// supply sag's gain at it: `g / (1 + g (V̄ − battery_v))`). `None` when `cfg` does not hide
/// `name`.
pub fn truth(name: EffectName, cfg: &PlantConfig, v_mean: f64) -> Option<Truth> {
    let e = &cfg.effects;
    let t = |key, value, tolerance, relative| Truth {
        key,
        value,
        tolerance,
        relative,
    };
    Some(match name {
        EffectName::DeadTime => t(
            "delay_samples",
            (e.dead_time.as_ref()?.delay_s / DT_S).round(),
            1.0,
            false,
        ),
        EffectName::StaticNonlinearity => t(
            "exponent",
            e.static_nonlinearity.as_ref()?.exponent,
            0.10,
            true,
        ),
        EffectName::ExtraMode => t("fn_hz", e.extra_mode.as_ref()?.fn_hz, 0.05, true),
        EffectName::BaselineDrift => t(
            "rate_per_s",
            e.baseline_drift.as_ref()?.rate_per_s,
            0.15,
            true,
        ),
        EffectName::PeriodicDisturbance => t(
            "amplitude",
            e.periodic_disturbance.as_ref()?.amplitude,
            0.15,
            true,
        ),
        EffectName::SupplySag => {
            let g = e.supply_sag.as_ref()?.gain_per_volt;
            t(
                "gain_per_volt",
                g / (1.0 + g * (v_mean - cfg.battery_v)),
                0.03,
                true,
            )
        }
        EffectName::Saturation => t("level", e.saturation.as_ref()?.level, 0.01, false),
        EffectName::AsymmetricDynamics => {
            let a = e.asymmetric_dynamics.as_ref()?;
            t("down_over_up", a.down_scale / a.up_scale, 0.10, true)
        }
        EffectName::StiffnessNonlinearity => t(
            "k3_per_k1",
            e.stiffness_nonlinearity.as_ref()?.k3_per_k1,
            0.15,
            true,
        ),
        // Effects of the stand baseline only: never hidden in this plant.
        EffectName::SensorLag | EffectName::SpeedDependentTau => return None,
    })
}

/// Row period of the motor-stand cases, s (100 Hz: a stand logger's rate).
pub const STAND_DT_S: f64 = 0.01;

/// The channels a motor-stand case logs, one value per row of [`STAND_DT_S`].
#[derive(Debug, Clone)]
pub struct StandRecord {
    /// Throttle commanded.
    pub u: Vec<f64>,
    /// Thrust read by the load cell, N.
    pub thrust: Vec<f64>,
    /// Rotor speed, rev/min (with the probe's noise).
    pub rpm: Vec<f64>,
    /// Supply current, A (with the shunt's noise).
    pub current: Vec<f64>,
    /// Supply voltage, V (with the divider's noise).
    pub voltage: Vec<f64>,
}

/// A random motor stand (`kind = "motor"`, [`crate::plant::motor`]) whose thrust path the
/// stand baseline of `diagnose` models as it is: rotor speed at the reference throttle 0.6
/// 12 000–24 000 rev/min, thrust there 4–15 N (∝ speed²), ESC dead band 0–0.08, one rotor
/// time constant 20–60 ms (up = down, no change with speed), no ESC dead time, a stiff supply
/// (no internal resistance, no discharge), current 10–20 A at the reference; thrust noise
/// 0.01–0.03 N RMS, 1 mN quantum. An `underdamped` stand's load cell reads the thrust through
/// a resonance of the stand ([`EffectName::ExtraMode`], `fn` 8–20 Hz, `ζ` 0.15–0.4): part
/// of that stand, named by `diagnose` as `extra_mode` ([`stand_background`]).
pub fn random_stand(rng: &mut StdRng, underdamped: bool) -> PlantConfig {
    let tau = rng.gen_range(0.02..0.06);
    let mut cfg = PlantConfig {
        kind: PlantKind::Motor,
        motor: MotorConfig {
            thrust_at_reference_n: rng.gen_range(4.0..15.0),
            tau_up_s: tau,
            tau_down_s: tau,
            tau_speed_exponent: 0.0,
            dead_time_s: 0.0,
            command_zero: rng.gen_range(0.0..0.08),
            speed_map_exponent: 1.0,
            thrust_exponent: 2.0,
            current_per_acceleration: 0.0,
            speed_voltage_exponent: 1.0,
        },
        reference_throttle: 0.6,
        rpm_at_reference: rng.gen_range(12_000.0..24_000.0),
        noise_rms_n: rng.gen_range(0.01..0.03),
        quantum_n: 0.001,
        idle_current_a: 0.5,
        current_at_reference_a: rng.gen_range(10.0..20.0),
        battery_v: 16.8,
        internal_resistance_ohm: 0.0,
        discharge_v_per_s: 0.0,
        ..PlantConfig::default()
    };
    if underdamped {
        cfg.effects.extra_mode = Some(ExtraMode {
            fn_hz: rng.gen_range(8.0..20.0),
            zeta: rng.gen_range(0.15..0.4),
            gain: 1.0,
        });
    }
    cfg
}

/// The effects a stand of [`random_stand`] has as part of it (an underdamped stand's
/// resonance), which `diagnose` names without their being hidden.
pub fn stand_background(cfg: &PlantConfig) -> Vec<EffectName> {
    cfg.effects.names()
}

/// Hides effect `name` of the stand catalogue in the motor stand `cfg` with parameters drawn
/// from `rng` (ranges in `docs/detection.md`); `stiffness_nonlinearity` (no part of a stand)
/// hides nothing.
pub fn hide_stand_effect(cfg: &mut PlantConfig, name: EffectName, rng: &mut StdRng) {
    let dt = STAND_DT_S;
    let m = &mut cfg.motor;
    let e = &mut cfg.effects;
    match name {
        EffectName::SensorLag => {
            cfg.sensors.thrust = Some(SensorConfig {
                delay_s: rng.gen_range(1.0..4.0) * dt,
                tau_s: rng.gen_range(2.0..8.0) * dt,
                ..SensorConfig::default()
            })
        }
        // 3–10 rows of ESC latency.
        EffectName::DeadTime => m.dead_time_s = rng.gen_range(3..=10) as f64 * dt,
        EffectName::AsymmetricDynamics => {
            // spin-down slower (drag only) or, every other draw, faster (active braking)
            let ratio: f64 = rng.gen_range(1.6..2.5);
            let ratio = if rng.gen_bool(0.5) {
                ratio
            } else {
                1.0 / ratio
            };
            let mean = m.tau_up_s;
            m.tau_up_s = mean / ratio.sqrt();
            m.tau_down_s = mean * ratio.sqrt();
        }
        EffectName::SpeedDependentTau => m.tau_speed_exponent = rng.gen_range(0.5..1.2),
        EffectName::StaticNonlinearity => {
            m.thrust_exponent = if rng.gen_bool(0.5) {
                rng.gen_range(1.5..1.75)
            } else {
                rng.gen_range(2.3..2.7)
            }
        }
        EffectName::SupplySag => {
            cfg.internal_resistance_ohm = rng.gen_range(0.1..0.25);
            cfg.discharge_v_per_s = rng.gen_range(0.02..0.05);
        }
        EffectName::Saturation => {
            e.saturation = Some(Saturation {
                level: rng.gen_range(0.6..0.7),
                signal: SaturationSignal::Throttle,
            })
        }
        EffectName::BaselineDrift => {
            let r: f64 = rng.gen_range(0.01..0.03);
            e.baseline_drift = Some(BaselineDrift {
                rate_per_s: if rng.gen_bool(0.5) { r } else { -r },
            });
        }
        EffectName::ExtraMode => {
            // a lightly damped resonance (replaces an underdamped stand's own)
            e.extra_mode = Some(ExtraMode {
                fn_hz: rng.gen_range(10.0..35.0),
                zeta: rng.gen_range(0.05..0.2),
                gain: 1.0,
            })
        }
        EffectName::PeriodicDisturbance => {
            e.periodic_disturbance = Some(PeriodicDisturbance {
                freq_hz: rng.gen_range(8.0..40.0),
                amplitude: rng.gen_range(0.03..0.1),
                phase_rad: rng.gen_range(0.0..std::f64::consts::TAU),
            })
        }
        EffectName::StiffnessNonlinearity => {}
    }
}

/// Motor-stand case `i` of `kind` with effect `name` of the stand catalogue hidden (`None`:
/// clean): a seeded [`random_stand`] (underdamped for even `i`), the effect drawn by
/// [`hide_stand_effect`], run through [`RecordKind::plan_at`] every [`STAND_DT_S`]; rpm noise
/// 10–30 rev/min, current 0.05 A, voltage 5 mV RMS.
pub fn stand_case(
    kind: RecordKind,
    name: Option<EffectName>,
    i: u64,
) -> Result<(PlantConfig, StandRecord), PlantError> {
    let len = name.map_or("clean", EffectName::as_str).len() as u64;
    let k = RecordKind::ALL.iter().position(|&x| x == kind).unwrap_or(0) as u64;
    let seed = 0x57a4_d000 + k * 1_000_003 + i * 7919 + len * 104_729;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut cfg = random_stand(&mut rng, i % 2 == 0);
    if let Some(name) = name {
        hide_stand_effect(&mut cfg, name, &mut rng);
    }
    let rpm_sd = rng.gen_range(10.0..30.0);
    let plan = kind.plan_at(STAND_DT_S);
    let mut plant = Plant::new(&cfg, STAND_DT_S, seed ^ 0xabcdef)?;
    plant.settle(plan.first().copied().unwrap_or(0.0));
    let noise = |sd: f64| Normal::new(0.0, sd).expect("a finite deviation");
    let (n_rpm, n_i, n_v) = (noise(rpm_sd), noise(0.05), noise(0.005));
    let mut r = StandRecord {
        u: Vec::with_capacity(plan.len()),
        thrust: Vec::with_capacity(plan.len()),
        rpm: Vec::with_capacity(plan.len()),
        current: Vec::with_capacity(plan.len()),
        voltage: Vec::with_capacity(plan.len()),
    };
    for &u in &plan {
        let m = plant.step(u);
        r.u.push(u);
        r.thrust.push(m.thrust_n);
        r.rpm.push(m.rpm + n_rpm.sample(&mut rng));
        r.current.push(m.current_a + n_i.sample(&mut rng));
        r.voltage.push(m.voltage_v + n_v.sample(&mut rng));
    }
    Ok((cfg, r))
}

/// The truths a finding of effect `name` hidden in the motor stand `cfg` is held to (every one
/// must hold; the tolerances of `docs/detection.md`); `v_mean`: the record's mean supply
/// voltage. Empty when `cfg` does not hide `name`.
pub fn stand_truth(name: EffectName, cfg: &PlantConfig, v_mean: f64) -> Vec<Truth> {
    let (m, e) = (&cfg.motor, &cfg.effects);
    let t = |key, value, tolerance, relative| Truth {
        key,
        value,
        tolerance,
        relative,
    };
    match name {
        EffectName::SensorLag => cfg.sensors.thrust.map_or(vec![], |s| {
            vec![
                t("delay_s", s.delay_s, STAND_DT_S, false),
                t("tau_s", s.tau_s, 0.25, true),
            ]
        }),
        EffectName::DeadTime if m.dead_time_s > 0.0 => {
            vec![t("delay_samples", m.dead_time_s / STAND_DT_S, 1.0, false)]
        }
        EffectName::AsymmetricDynamics if m.tau_up_s != m.tau_down_s => {
            vec![t("down_over_up", m.tau_down_s / m.tau_up_s, 0.10, true)]
        }
        EffectName::SpeedDependentTau if m.tau_speed_exponent != 0.0 => {
            vec![t("tau_speed_exponent", m.tau_speed_exponent, 0.25, true)]
        }
        EffectName::StaticNonlinearity if m.thrust_exponent != 2.0 => {
            vec![t("exponent", m.thrust_exponent, 0.10, true)]
        }
        // n ∝ V and T ∝ n²: the thrust's relative change per volt at the mean voltage
        EffectName::SupplySag if cfg.internal_resistance_ohm > 0.0 => {
            vec![t("gain_per_volt", m.thrust_exponent / v_mean, 0.03, true)]
        }
        EffectName::Saturation => e
            .saturation
            .as_ref()
            .map_or(vec![], |s| vec![t("level", s.level, 0.01, false)]),
        EffectName::BaselineDrift => e
            .baseline_drift
            .as_ref()
            .map_or(vec![], |d| vec![t("rate_per_s", d.rate_per_s, 0.15, true)]),
        EffectName::ExtraMode => e
            .extra_mode
            .as_ref()
            .map_or(vec![], |x| vec![t("fn_hz", x.fn_hz, 0.05, true)]),
        EffectName::PeriodicDisturbance => e
            .periodic_disturbance
            .as_ref()
            .map_or(vec![], |p| vec![t("amplitude", p.amplitude, 0.15, true)]),
        _ => vec![],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_numerics::segment::{levels, steps, Command, SegmentRules};

    #[test]
    fn every_kind_has_steps_and_levels_the_segmentation_sees() {
        for kind in RecordKind::ALL {
            let u = kind.plan();
            let rules = SegmentRules::for_record(DT_S, true);
            assert!(levels(Command::new(&u), &rules).len() >= 5, "{kind:?}");
            assert!(steps(Command::new(&u), &rules).len() >= 4, "{kind:?}");
            // a throttle saturation (0.6–0.7) is reached by every kind
            assert!(u.iter().any(|&x| x > 0.7), "{kind:?}");
        }
    }

    #[test]
    fn a_truth_is_held_to_its_tolerance() {
        let t = Truth {
            key: "x",
            value: 2.0,
            tolerance: 0.1,
            relative: true,
        };
        assert!(t.holds(2.19) && !t.holds(2.21) && !t.holds(-2.0));
        let (cfg, _) = case(RecordKind::Step, Some(EffectName::DeadTime), 0).unwrap();
        let d = truth(EffectName::DeadTime, &cfg, 16.0).unwrap();
        assert!(d.holds(d.value + 1.0) && !d.holds(d.value + 2.0));
        assert!(truth(EffectName::Saturation, &cfg, 16.0).is_none());
    }

    #[test]
    fn every_stand_effect_is_hidden_with_a_truth_and_the_record_carries_every_channel() {
        let (clean, r) = stand_case(RecordKind::Staircase, None, 1).unwrap();
        let rows = RecordKind::Staircase.plan_at(STAND_DT_S).len();
        for ch in [&r.u, &r.thrust, &r.rpm, &r.current, &r.voltage] {
            assert_eq!(ch.len(), rows);
            assert!(ch.iter().all(|x| x.is_finite()));
        }
        // the rpm follows the staircase (about 12 000–24 000 rev/min at throttle 0.6)
        let (lo, hi) = (r.rpm[50], r.rpm[rows - 450]);
        assert!(hi > 1.5 * lo && hi > 5_000.0, "{lo} {hi}");
        // a stiff supply: the voltage moves by its noise only
        let v_span = r
            .voltage
            .iter()
            .fold(0.0f64, |m, v| m.max((v - 16.8).abs()));
        assert!(v_span < 0.05, "{v_span}");
        assert!(stand_background(&clean).is_empty());
        let (under, _) = stand_case(RecordKind::Staircase, None, 0).unwrap();
        assert_eq!(stand_background(&under), [EffectName::ExtraMode]);
        for name in EffectName::ALL {
            let (cfg, r) = stand_case(RecordKind::Step, Some(name), 1).unwrap();
            let v = r.voltage.iter().sum::<f64>() / r.voltage.len() as f64;
            let truths = stand_truth(name, &cfg, v);
            if name == EffectName::StiffnessNonlinearity {
                assert!(truths.is_empty());
                continue;
            }
            assert!(!truths.is_empty(), "{name}");
            assert!(stand_truth(name, &clean, v).is_empty(), "{name}");
            // each truth holds for itself and not for an estimate twice its tolerance off
            for t in truths {
                let off = if t.relative {
                    t.value.abs() * t.tolerance
                } else {
                    t.tolerance
                };
                assert!(t.holds(t.value) && !t.holds(t.value + 2.0 * off), "{name}");
            }
        }
        let (sag, r) = stand_case(RecordKind::Step, Some(EffectName::SupplySag), 1).unwrap();
        assert!(sag.internal_resistance_ohm > 0.0);
        let v_min = r.voltage.iter().fold(f64::INFINITY, |m, &v| m.min(v));
        assert!(v_min < 16.3, "the supply sags: {v_min}");
    }
}
