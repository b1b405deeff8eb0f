//! Effects that real propulsion benches show, each switchable with its parameters (issue 5).
//! They are the `[plant.effects.<name>]` tables of `config/sim.toml`; a table that is present
//! switches its effect on. The names are public (they match `propid diagnose`'s findings):
//!
//! | effect | parameters | where it acts |
//! |---|---|---|
//! | `dead_time` | `delay_s` | throttle delayed by `round(delay_s / dt)` samples |
//! | `static_nonlinearity` | `exponent` | throttle through `u_ref · (u / u_ref)^p` before the linear core |
//! | `extra_mode` | `fn_hz`, `zeta`, `gain` | load-cell path `(1 − g) + g · ωm² / (s² + 2ζωm s + ωm²)` |
//! | `baseline_drift` | `rate_per_s` | `+ rate_per_s · t` on the thrust, N/s |
//! | `periodic_disturbance` | `freq_hz`, `amplitude`, `phase_rad` | `+ amplitude · sin(2π f t + φ)`, N |
//! | `supply_sag` | `gain_per_volt` | throttle scaled by `1 + gain_per_volt · (V − battery_v)` |
//! | `saturation` | `level`, `signal` | throttle clipped at `level` (0..1), or the thrust sensor at `level` N |
//! | `asymmetric_dynamics` | `up_scale`, `down_scale` | the core's time scale while the thrust is driven up / falls back (`ωn / scale`) |
//! | `stiffness_nonlinearity` | `k3_per_k1` | a cubic restoring term in the core, `ωn² (T + ε T³)`, ε in 1/N² |
//!
//! Order in one step: delay → throttle clip → static map → supply sag → core (with its
//! direction-dependent time scale and cubic stiffness, [`propid_numerics::nonlinear_core`]) →
//! load-cell path (extra mode) → drift and disturbance → noise → sensor clip → quantisation.

use crate::delay_line::DelayLine;
use propid_numerics::EffectName;

use nalgebra::{Matrix2, Vector2};
use serde::Deserialize;

use super::plant::{check, PlantConfig, PlantError};
use propid_numerics::discretise::discretise_second_order;
use propid_numerics::nonlinear_core::CoreLaw;

/// `dead_time`: a transport delay of the throttle (ESC update, filtering, logging).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeadTime {
    /// Delay, seconds (≥ 0, at most 1 s); rounded to whole samples.
    pub delay_s: f64,
}

/// `static_nonlinearity`: thrust ∝ throttle^p in steady state (about 2 with thrust ∝ rpm² and
/// rpm ∝ throttle), equal to the linear plant's thrust at `reference_throttle`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaticNonlinearity {
    /// Exponent `p` of the power law (0.2 ..= 5); above 1 the gain hardens with throttle.
    pub exponent: f64,
}

/// `extra_mode`: an unmodelled resonance in the load-cell path (stand, mount, frame).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtraMode {
    /// Natural frequency of the mode, Hz (> 0, below Nyquist).
    pub fn_hz: f64,
    /// Damping ratio of the mode (> 0).
    pub zeta: f64,
    /// Share of the force that passes through the resonant path (0 < gain ≤ 1; default 1).
    #[serde(default = "one")]
    pub gain: f64,
}

fn one() -> f64 {
    1.0
}

/// `baseline_drift`: load-cell creep or thermal drift.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaselineDrift {
    /// Drift of the measured thrust, newtons per second (finite, either sign).
    pub rate_per_s: f64,
}

/// `periodic_disturbance`: vibration or mains pick-up unrelated to the input.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeriodicDisturbance {
    /// Frequency, Hz (> 0, below Nyquist).
    pub freq_hz: f64,
    /// Amplitude added to the measured thrust, newtons (≥ 0).
    pub amplitude: f64,
    /// Phase at t = 0, radians (default 0).
    #[serde(default)]
    pub phase_rad: f64,
}

/// `supply_sag`: the ESC's output follows the supply voltage as the battery sags.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupplySag {
    /// Relative change of the throttle-to-thrust gain per volt of supply, 1/V (−1 ..= 1):
    /// the effective throttle is `u · (1 + gain_per_volt · (V − battery_v))`. The plant's
    /// battery model (`battery_v`, `internal_resistance_ohm`, `discharge_v_per_s`) makes V sag
    /// with current and with time.
    pub gain_per_volt: f64,
}

/// Which signal a `saturation` clips.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SaturationSignal {
    /// The throttle command: above `level` (0..1) more command has no effect.
    #[default]
    Throttle,
    /// The thrust sensor: readings above `level` newtons read `level`.
    Sensor,
}

/// `saturation`: the throttle or the sensor clips.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Saturation {
    /// Clip level: absolute throttle 0..1 (`signal = "throttle"`) or thrust in N (`"sensor"`).
    pub level: f64,
    /// What clips (default `"throttle"`).
    #[serde(default)]
    pub signal: SaturationSignal,
}

/// `asymmetric_dynamics`: spin-up and spin-down differ (the ESC drives the rotor up; without
/// active braking only drag brings it down). The core runs with `ωn / up_scale` while the
/// input drives the thrust up (`K u − T − ε T³ ≥ 0`) and with `ωn / down_scale` while it falls
/// back: every time constant of the response is multiplied by that scale.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AsymmetricDynamics {
    /// Time scale while the thrust is driven up (dimensionless, 0.05 ..= 20; 1 = the plant's).
    pub up_scale: f64,
    /// Time scale while the thrust falls back (dimensionless, 0.05 ..= 20).
    pub down_scale: f64,
}

/// `stiffness_nonlinearity`: a hardening (`k3_per_k1 > 0`) or softening (`< 0`) spring in the
/// core, `T'' + 2ζωn T' + ωn² (T + ε T³) = ωn² K u` (`m y'' + d y' + k1 y + k3 y³ = u`, the
/// Silverbox benchmark, with `ε = k3/k1`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StiffnessNonlinearity {
    /// `ε = k3 / k1`, per newton squared (finite; a softening spring must keep
    /// `1 + 3 ε T² > 0` over the thrust it reaches, or the core has no steady state there).
    pub k3_per_k1: f64,
}

/// The effects switched on; a table present in the config switches its effect on.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectsConfig {
    /// Transport delay of the throttle.
    pub dead_time: Option<DeadTime>,
    /// Power-law static map before the linear core.
    pub static_nonlinearity: Option<StaticNonlinearity>,
    /// Resonance in the load-cell path.
    pub extra_mode: Option<ExtraMode>,
    /// Linear drift of the thrust reading.
    pub baseline_drift: Option<BaselineDrift>,
    /// Sinusoid added to the thrust reading.
    pub periodic_disturbance: Option<PeriodicDisturbance>,
    /// Gain following the supply voltage.
    pub supply_sag: Option<SupplySag>,
    /// Throttle or sensor clip.
    pub saturation: Option<Saturation>,
    /// Spin-up and spin-down on different time scales.
    pub asymmetric_dynamics: Option<AsymmetricDynamics>,
    /// Cubic stiffness in the core.
    pub stiffness_nonlinearity: Option<StiffnessNonlinearity>,
}

impl EffectsConfig {
    /// Names of the effects switched on, in catalogue order.
    pub fn names(&self) -> Vec<EffectName> {
        let mut v = Vec::new();
        let on = [
            (self.dead_time.is_some(), EffectName::DeadTime),
            (
                self.static_nonlinearity.is_some(),
                EffectName::StaticNonlinearity,
            ),
            (self.extra_mode.is_some(), EffectName::ExtraMode),
            (self.baseline_drift.is_some(), EffectName::BaselineDrift),
            (
                self.periodic_disturbance.is_some(),
                EffectName::PeriodicDisturbance,
            ),
            (self.supply_sag.is_some(), EffectName::SupplySag),
            (self.saturation.is_some(), EffectName::Saturation),
            (
                self.asymmetric_dynamics.is_some(),
                EffectName::AsymmetricDynamics,
            ),
            (
                self.stiffness_nonlinearity.is_some(),
                EffectName::StiffnessNonlinearity,
            ),
        ];
        for (is_on, name) in on {
            if is_on {
                v.push(name);
            }
        }
        v
    }

    /// Checks every parameter of the effects switched on; the error names the key.
    pub fn validate(&self, dt_s: f64) -> Result<(), PlantError> {
        let nyquist = 0.5 / dt_s;
        if let Some(d) = &self.dead_time {
            let ok = d.delay_s.is_finite() && (0.0..=1.0).contains(&d.delay_s);
            check(
                ok,
                "plant.effects.dead_time.delay_s",
                d.delay_s,
                "must be in [0, 1] s",
            )?;
        }
        if let Some(s) = &self.static_nonlinearity {
            let ok = s.exponent.is_finite() && (0.2..=5.0).contains(&s.exponent);
            let key = "plant.effects.static_nonlinearity.exponent";
            check(ok, key, s.exponent, "must be in [0.2, 5]")?;
        }
        if let Some(m) = &self.extra_mode {
            let ok = m.fn_hz.is_finite() && m.fn_hz > 0.0 && m.fn_hz < nyquist;
            let why = "must be > 0 and below Nyquist";
            check(ok, "plant.effects.extra_mode.fn_hz", m.fn_hz, why)?;
            let ok = m.zeta.is_finite() && m.zeta > 0.0 && m.zeta <= 20.0;
            check(
                ok,
                "plant.effects.extra_mode.zeta",
                m.zeta,
                "must be in (0, 20]",
            )?;
            let ok = m.gain.is_finite() && m.gain > 0.0 && m.gain <= 1.0;
            check(
                ok,
                "plant.effects.extra_mode.gain",
                m.gain,
                "must be in (0, 1]",
            )?;
        }
        if let Some(d) = &self.baseline_drift {
            let key = "plant.effects.baseline_drift.rate_per_s";
            check(
                d.rate_per_s.is_finite(),
                key,
                d.rate_per_s,
                "must be finite",
            )?;
        }
        if let Some(p) = &self.periodic_disturbance {
            let ok = p.freq_hz.is_finite() && p.freq_hz > 0.0 && p.freq_hz < nyquist;
            let key = "plant.effects.periodic_disturbance.freq_hz";
            check(ok, key, p.freq_hz, "must be > 0 and below Nyquist")?;
            let ok = p.amplitude.is_finite() && p.amplitude >= 0.0;
            let key = "plant.effects.periodic_disturbance.amplitude";
            check(ok, key, p.amplitude, "must be >= 0")?;
            let key = "plant.effects.periodic_disturbance.phase_rad";
            check(p.phase_rad.is_finite(), key, p.phase_rad, "must be finite")?;
        }
        if let Some(s) = &self.supply_sag {
            let ok = s.gain_per_volt.is_finite() && (-1.0..=1.0).contains(&s.gain_per_volt);
            let key = "plant.effects.supply_sag.gain_per_volt";
            check(ok, key, s.gain_per_volt, "must be in [-1, 1] per volt")?;
        }
        if let Some(s) = &self.saturation {
            let ok = match s.signal {
                SaturationSignal::Throttle => s.level.is_finite() && s.level > 0.0 && s.level < 1.0,
                SaturationSignal::Sensor => s.level.is_finite() && s.level > 0.0,
            };
            let why = "must be in (0, 1) for the throttle, > 0 N for the sensor";
            check(ok, "plant.effects.saturation.level", s.level, why)?;
        }
        if let Some(a) = &self.asymmetric_dynamics {
            let ok = |v: f64| v.is_finite() && (0.05..=20.0).contains(&v);
            let why = "must be in [0.05, 20]";
            let key = "plant.effects.asymmetric_dynamics.up_scale";
            check(ok(a.up_scale), key, a.up_scale, why)?;
            let key = "plant.effects.asymmetric_dynamics.down_scale";
            check(ok(a.down_scale), key, a.down_scale, why)?;
        }
        if let Some(s) = &self.stiffness_nonlinearity {
            let key = "plant.effects.stiffness_nonlinearity.k3_per_k1";
            check(s.k3_per_k1.is_finite(), key, s.k3_per_k1, "must be finite")?;
        }
        Ok(())
    }

    /// The core's nonlinear law ([`CoreLaw`]): the linear core unless `asymmetric_dynamics` or
    /// `stiffness_nonlinearity` is on.
    pub fn core_law(&self) -> CoreLaw {
        let mut law = CoreLaw::default();
        if let Some(a) = &self.asymmetric_dynamics {
            law.up_scale = a.up_scale;
            law.down_scale = a.down_scale;
        }
        if let Some(s) = &self.stiffness_nonlinearity {
            law.cubic = s.k3_per_k1;
        }
        law
    }
}

/// Run-time state of the effects of one plant (delay line, extra-mode state).
#[derive(Debug, Clone)]
pub(crate) struct EffectState {
    cfg: EffectsConfig,
    /// The `dead_time` effect.
    delay: DelayLine,
    mode: Option<(Matrix2<f64>, Vector2<f64>, Vector2<f64>)>,
}

impl EffectState {
    pub(crate) fn new(
        cfg: &EffectsConfig,
        _plant: &PlantConfig,
        dt_s: f64,
        _seed: u64,
    ) -> Result<EffectState, PlantError> {
        cfg.validate(dt_s)?;
        let delay_samples = cfg
            .dead_time
            .as_ref()
            .map_or(0, |d| (d.delay_s / dt_s).round() as usize);
        let mode = cfg.extra_mode.as_ref().map(|m| {
            let (a, b) = discretise_second_order(m.fn_hz, m.zeta, 1.0, dt_s);
            (a, b, Vector2::zeros())
        });
        Ok(EffectState {
            cfg: cfg.clone(),
            delay: DelayLine::new(delay_samples),
            mode,
        })
    }

    /// Pushes `u` into the delay line and returns the throttle of the dead time ago (0 before
    /// the line is full, or the settled throttle after [`EffectState::settle`]).
    pub(crate) fn delay(&mut self, u: f64) -> f64 {
        self.delay.push(u)
    }

    /// Throttle clip, static map and supply sag: the input the linear core sees.
    pub(crate) fn input_map(&self, u: f64, voltage_v: f64, plant: &PlantConfig) -> f64 {
        let mut u = u;
        if let Some(s) = &self.cfg.saturation {
            if s.signal == SaturationSignal::Throttle {
                u = u.min(s.level);
            }
        }
        if let Some(s) = &self.cfg.static_nonlinearity {
            let r = plant.reference_throttle;
            u = r * (u.max(0.0) / r).powf(s.exponent);
        }
        if let Some(s) = &self.cfg.supply_sag {
            u *= 1.0 + s.gain_per_volt * (voltage_v - plant.battery_v);
        }
        u
    }

    /// Steady state at throttle `u` and true thrust `thrust_n`.
    pub(crate) fn settle(&mut self, u: f64, thrust_n: f64) {
        self.delay.settle(u);
        if let Some((_, _, x)) = &mut self.mode {
            *x = Vector2::new(thrust_n, 0.0);
        }
    }

    /// The load-cell path: returns this sample's reading of true thrust `t_n` and advances the
    /// extra mode (if any) with `t_n` held for the sample.
    pub(crate) fn sensor_path(&mut self, t_n: f64) -> f64 {
        match (&mut self.mode, &self.cfg.extra_mode) {
            (Some((a, b, x)), Some(m)) => {
                let y = (1.0 - m.gain) * t_n + m.gain * x[0];
                *x = *a * *x + *b * t_n;
                y
            }
            _ => t_n,
        }
    }

    /// Drift and periodic disturbance at time `t_s`, newtons.
    pub(crate) fn additive(&self, t_s: f64) -> f64 {
        let mut y = 0.0;
        if let Some(d) = &self.cfg.baseline_drift {
            y += d.rate_per_s * t_s;
        }
        if let Some(p) = &self.cfg.periodic_disturbance {
            y += p.amplitude * (2.0 * std::f64::consts::PI * p.freq_hz * t_s + p.phase_rad).sin();
        }
        y
    }

    /// Sensor clip; returns the reading and whether it clipped.
    pub(crate) fn sensor_clip(&self, y: f64) -> (f64, bool) {
        match &self.cfg.saturation {
            Some(s) if s.signal == SaturationSignal::Sensor && y >= s.level => (s.level, true),
            _ => (y, false),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::plant::{Plant, PlantConfig};

    use super::*;

    fn clean(effects: EffectsConfig) -> PlantConfig {
        PlantConfig {
            noise_rms_n: 0.0,
            quantum_n: 0.0,
            discharge_v_per_s: 0.0,
            effects,
            ..PlantConfig::default()
        }
    }

    fn run(cfg: &PlantConfig, u: impl Fn(usize) -> f64, n: usize) -> Vec<f64> {
        let mut p = Plant::new(cfg, 1e-3, 3).unwrap();
        p.settle(u(0));
        (0..n).map(|k| p.step(u(k)).thrust_n).collect()
    }

    #[test]
    fn dead_time_shifts_the_response_by_whole_samples() {
        let step = |k: usize| if k >= 10 { 0.6 } else { 0.4 };
        let base = run(&clean(EffectsConfig::default()), step, 200);
        let e = EffectsConfig {
            dead_time: Some(DeadTime { delay_s: 0.0071 }),
            ..Default::default()
        };
        let late = run(&clean(e), step, 200);
        for k in 7..200 {
            assert!((late[k] - base[k - 7]).abs() < 1e-12, "k={k}");
        }
    }

    #[test]
    fn static_map_is_a_power_law_through_the_reference_point() {
        let e = EffectsConfig {
            static_nonlinearity: Some(StaticNonlinearity { exponent: 2.0 }),
            ..Default::default()
        };
        let cfg = clean(e);
        let at = |u: f64| run(&cfg, |_| u, 1)[0];
        let k = cfg.gain_n_per_throttle;
        assert!((at(0.5) - 0.5 * k).abs() < 1e-12);
        assert!((at(0.25) - 0.5 * k * 0.25).abs() < 1e-12);
    }

    #[test]
    fn extra_mode_rings_at_its_frequency_and_keeps_dc() {
        let e = EffectsConfig {
            extra_mode: Some(ExtraMode {
                fn_hz: 60.0,
                zeta: 0.02,
                gain: 1.0,
            }),
            ..Default::default()
        };
        let cfg = clean(e);
        let step = |k: usize| if k >= 10 { 0.6 } else { 0.4 };
        let y = run(&cfg, step, 3000);
        let base = run(&clean(EffectsConfig::default()), step, 3000);
        assert!((y[2999] - base[2999]).abs() < 1e-3);
        let dev = y
            .iter()
            .zip(&base)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(dev > 0.01, "no ringing: {dev}");
    }

    #[test]
    fn drift_disturbance_and_sensor_clip() {
        let e = EffectsConfig {
            baseline_drift: Some(BaselineDrift { rate_per_s: 0.5 }),
            periodic_disturbance: Some(PeriodicDisturbance {
                freq_hz: 50.0,
                amplitude: 0.2,
                phase_rad: 0.0,
            }),
            ..Default::default()
        };
        let y = run(&clean(e), |_| 0.5, 2001);
        assert!((y[2000] - y[0] - 1.0).abs() < 1e-9);
        assert!(
            (y[5] - y[0] - 0.2 * (2.0 * std::f64::consts::PI * 0.25).sin() - 0.0025).abs() < 1e-9
        );
        let e = EffectsConfig {
            saturation: Some(Saturation {
                level: 4.0,
                signal: SaturationSignal::Sensor,
            }),
            ..Default::default()
        };
        let mut p = Plant::new(&clean(e), 1e-3, 1).unwrap();
        p.settle(0.5);
        let m = p.step(0.5);
        assert_eq!(m.thrust_n, 4.0);
        assert!(m.adc_saturated);
    }

    #[test]
    fn throttle_saturation_and_supply_sag() {
        let e = EffectsConfig {
            saturation: Some(Saturation {
                level: 0.6,
                signal: SaturationSignal::Throttle,
            }),
            ..Default::default()
        };
        let cfg = clean(e);
        assert_eq!(run(&cfg, |_| 0.9, 1)[0], run(&cfg, |_| 0.6, 1)[0]);
        let e = EffectsConfig {
            supply_sag: Some(SupplySag { gain_per_volt: 0.1 }),
            ..Default::default()
        };
        let cfg = PlantConfig {
            discharge_v_per_s: 1.0,
            internal_resistance_ohm: 0.0,
            ..clean(e)
        };
        let y = run(&cfg, |_| 0.5, 2000);
        // After 2 s the supply is 2 V lower: the thrust is about 20 % lower.
        assert!((y[1999] / y[0] - 0.8).abs() < 0.01, "{}", y[1999] / y[0]);
    }

    #[test]
    fn asymmetric_dynamics_and_a_hardening_spring_act_in_the_core() {
        let text = "[effects.asymmetric_dynamics]\nup_scale = 1.0\ndown_scale = 3.0\n";
        let cfg: PlantConfig = toml::from_str(text).unwrap();
        assert_eq!(cfg.effects.names(), vec![EffectName::AsymmetricDynamics]);
        let cfg = clean(cfg.effects);
        // Time to 63 % of a step up and of the same step down: three times longer down.
        let t63 = |from: f64, to: f64| {
            let y = run(&cfg, |k| if k >= 1 { to } else { from }, 3000);
            let target = y[0] + 0.632 * (y[2999] - y[0]);
            y.iter()
                .position(|&v| (v - target) * (to - from).signum() >= 0.0)
                .unwrap() as f64
                - 1.0
        };
        // Whole samples (about 20 up): ±1 sample on each.
        let ratio = t63(0.6, 0.4) / t63(0.4, 0.6);
        assert!((ratio - 3.0).abs() < 0.2, "{ratio}");
        // A spring with ε T² = 0.5 at the linear thrust: T + ε T³ = K u holds in steady state.
        let lin = clean(EffectsConfig::default());
        let t_lin = run(&lin, |_| 0.5, 1)[0];
        let e = EffectsConfig {
            stiffness_nonlinearity: Some(StiffnessNonlinearity {
                k3_per_k1: 0.5 / (t_lin * t_lin),
            }),
            ..Default::default()
        };
        let y = run(&clean(e), |_| 0.5, 2000);
        let eps = 0.5 / (t_lin * t_lin);
        assert!((y[1999] + eps * y[1999].powi(3) - t_lin).abs() < 1e-9);
        assert!(y[1999] < 0.9 * t_lin);
        let bad = EffectsConfig {
            asymmetric_dynamics: Some(AsymmetricDynamics {
                up_scale: 0.0,
                down_scale: 1.0,
            }),
            ..Default::default()
        };
        let err = Plant::new(&clean(bad), 1e-3, 0).unwrap_err().to_string();
        assert!(err.contains("asymmetric_dynamics.up_scale"), "{err}");
    }

    #[test]
    fn effects_parse_from_toml_and_bad_values_are_named() {
        let text = "[effects.dead_time]\ndelay_s = 0.02\n[effects.saturation]\nlevel = 0.7\n";
        let cfg: PlantConfig = toml::from_str(text).unwrap();
        assert_eq!(
            cfg.effects.names(),
            vec![EffectName::DeadTime, EffectName::Saturation]
        );
        assert!(toml::from_str::<PlantConfig>("[effects.dead_time]\ndelay = 1\n").is_err());
        let e = EffectsConfig {
            extra_mode: Some(ExtraMode {
                fn_hz: 1e6,
                zeta: 0.1,
                gain: 1.0,
            }),
            ..Default::default()
        };
        let err = Plant::new(&clean(e), 1e-3, 0).unwrap_err();
        assert!(
            err.to_string().contains("plant.effects.extra_mode.fn_hz"),
            "{err}"
        );
    }
}
