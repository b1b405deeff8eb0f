//! The simulated motor + propeller + load cell: a discrete 2nd-order thrust response to the
//! throttle, with seeded noise, quantisation and physically plausible derived channels (torque,
//! rotor speed, battery voltage and current). Effects that real benches show (dead time, a static
//! map, an extra mode, drift, a periodic disturbance, supply sag, saturation) are switched on in
//! [`EffectsConfig`](super::effects::EffectsConfig) and applied around the linear core.
//!
//! # The linear core
//! Thrust `T` follows the throttle `u` (fraction 0..1) as
//!
//! ```text
//!   T'' + 2 ζ ωn T' + ωn² T = ωn² K u,     ωn = 2π fn_hz,  K = gain_n_per_throttle
//! ```
//!
//! so the static map of the clean plant is `T = K u` and its small-signal gain is `K` N per unit
//! throttle everywhere. With the state `x = [T, T']` the system is discretised *exactly* for a
//! zero-order-held input: `A = e^{Ac dt}`, `B = ∫₀^dt e^{Ac s} ds · Bc`, both read off the
//! matrix exponential of the augmented matrix `[[Ac, Bc], [0, 0]] dt` (Van Loan 1978;
//! [`propid_numerics::discretise::discretise_second_order`]). The
//! measurement at step `k` is `y_k = C x_k` (no feed-through, `D = 0`), then
//! `x_{k+1} = A x_k + B u_k`: the throttle held during sample `k` shows in the thrust from sample
//! `k + 1` on, as the Markov convention of `core::markov` expects (`Y_0 = D = 0`, `Y_1 = C B`).
//!
//! # Derived channels (noise-free thrust `T ≥ 0` drives them)
//! - torque: `Q = torque_m · T` (the ratio of the propeller's torque and thrust coefficients,
//!   `C_Q D / C_T`, in metres);
//! - rotor speed: `T = k_T n²`, so `rpm = rpm_at_reference · sqrt(T / T_ref)` where `T_ref` is the
//!   thrust at `reference_throttle`;
//! - current: momentum theory gives an ideal power `P ∝ T^{3/2}`, so
//!   `I = idle_current_a + current_at_reference_a · (T / T_ref)^{3/2}`;
//! - voltage: a battery with open-circuit voltage falling linearly in time and an internal
//!   resistance, `V = battery_v − discharge_v_per_s · t − internal_resistance_ohm · I`.
//!
//! The thrust channel gets white Gaussian noise (`noise_rms_n`) and is quantised to `quantum_n`;
//! the load cell's converter saturates at `±adc_full_scale_n` (flagged in
//! [`Measurement::adc_saturated`]).

use nalgebra::{Matrix2, Vector2};
use propid_numerics::discretise::discretise_second_order;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde::Deserialize;

use super::effects::{EffectState, EffectsConfig};

/// A plant parameter that cannot be simulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlantError {
    /// A configuration value is out of range (the key and the value are named).
    #[error("plant parameter `{key}` = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Configuration key, e.g. `plant.fn_hz` or `plant.effects.dead_time.delay_s`.
        key: &'static str,
        /// The refused value.
        value: f64,
        /// What the valid range is.
        reason: &'static str,
    },
}

/// Configuration of the simulated plant (the `[plant]` table of `config/sim.toml`).
/// Every key has its unit in its name or its doc; unknown keys are refused.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantConfig {
    /// Natural frequency of the thrust response, Hz (> 0, below the Nyquist frequency).
    pub fn_hz: f64,
    /// Damping ratio of the thrust response (> 0; above 1 the poles are real, overdamped).
    pub zeta: f64,
    /// Small-signal (and static) thrust gain, newtons per unit throttle (> 0).
    pub gain_n_per_throttle: f64,
    /// Throttle (0..1, exclusive) at which the derived channels and the static map of the
    /// `static_nonlinearity` effect are referenced.
    pub reference_throttle: f64,
    /// RMS of the white Gaussian noise added to the thrust, newtons (≥ 0).
    pub noise_rms_n: f64,
    /// Load-cell resolution, newtons (≥ 0; 0 = no quantisation).
    pub quantum_n: f64,
    /// The load cell's converter saturates at ± this thrust, newtons (> 0).
    pub adc_full_scale_n: f64,
    /// Torque per thrust, metres (≥ 0): `torque_nm = torque_m · thrust_n`.
    pub torque_m: f64,
    /// Rotor speed at the reference throttle in steady state, rev/min (≥ 0).
    pub rpm_at_reference: f64,
    /// Supply current with the rotor at rest, amperes (≥ 0).
    pub idle_current_a: f64,
    /// Extra current at the reference thrust, amperes (≥ 0); scales with thrust^1.5.
    pub current_at_reference_a: f64,
    /// Open-circuit battery voltage at t = 0, volts (> 0).
    pub battery_v: f64,
    /// Battery internal resistance, ohms (≥ 0).
    pub internal_resistance_ohm: f64,
    /// Fall of the open-circuit voltage with time as the battery discharges, volts per second
    /// (≥ 0).
    pub discharge_v_per_s: f64,
    /// Effects switched on (`[plant.effects.*]`); all off by default.
    pub effects: EffectsConfig,
}

impl Default for PlantConfig {
    fn default() -> Self {
        PlantConfig {
            fn_hz: 12.0,
            zeta: 0.7,
            gain_n_per_throttle: 12.0,
            reference_throttle: 0.5,
            noise_rms_n: 0.01,
            quantum_n: 0.001,
            adc_full_scale_n: 50.0,
            torque_m: 0.012,
            rpm_at_reference: 18000.0,
            idle_current_a: 0.4,
            current_at_reference_a: 8.0,
            battery_v: 16.8,
            internal_resistance_ohm: 0.05,
            discharge_v_per_s: 0.002,
            effects: EffectsConfig::default(),
        }
    }
}

/// Checks `ok` (written as a positive check so that NaN fails) or names the key and the value.
pub(crate) fn check(
    ok: bool,
    key: &'static str,
    value: f64,
    reason: &'static str,
) -> Result<(), PlantError> {
    if ok {
        Ok(())
    } else {
        Err(PlantError::InvalidParameter { key, value, reason })
    }
}

impl PlantConfig {
    /// Checks every value for a sample period `dt_s`; the error names the first bad key.
    pub fn validate(&self, dt_s: f64) -> Result<(), PlantError> {
        check(dt_s.is_finite() && dt_s > 0.0, "dt_s", dt_s, "must be > 0")?;
        let nyquist = 0.5 / dt_s;
        check(
            self.fn_hz.is_finite() && self.fn_hz > 0.0 && self.fn_hz < nyquist,
            "plant.fn_hz",
            self.fn_hz,
            "must be > 0 and below the Nyquist frequency",
        )?;
        check(
            self.zeta.is_finite() && self.zeta > 0.0 && self.zeta <= 20.0,
            "plant.zeta",
            self.zeta,
            "must be in (0, 20]",
        )?;
        let positive = [
            (self.gain_n_per_throttle, "plant.gain_n_per_throttle"),
            (self.adc_full_scale_n, "plant.adc_full_scale_n"),
            (self.battery_v, "plant.battery_v"),
        ];
        for (v, key) in positive {
            check(v.is_finite() && v > 0.0, key, v, "must be > 0")?;
        }
        check(
            self.reference_throttle.is_finite()
                && self.reference_throttle > 0.0
                && self.reference_throttle < 1.0,
            "plant.reference_throttle",
            self.reference_throttle,
            "must be in (0, 1)",
        )?;
        let non_negative = [
            (self.noise_rms_n, "plant.noise_rms_n"),
            (self.quantum_n, "plant.quantum_n"),
            (self.torque_m, "plant.torque_m"),
            (self.rpm_at_reference, "plant.rpm_at_reference"),
            (self.idle_current_a, "plant.idle_current_a"),
            (self.current_at_reference_a, "plant.current_at_reference_a"),
            (
                self.internal_resistance_ohm,
                "plant.internal_resistance_ohm",
            ),
            (self.discharge_v_per_s, "plant.discharge_v_per_s"),
        ];
        for (v, key) in non_negative {
            check(v.is_finite() && v >= 0.0, key, v, "must be >= 0")?;
        }
        self.effects.validate(dt_s)
    }

    /// Thrust at the reference throttle in steady state, newtons (the clean static map).
    pub fn reference_thrust_n(&self) -> f64 {
        self.gain_n_per_throttle * self.reference_throttle
    }
}

/// One sample of every channel the stand measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Measured thrust (noise, quantisation, effects), newtons.
    pub thrust_n: f64,
    /// Torque, newton metres.
    pub torque_nm: f64,
    /// Rotor speed, rev/min.
    pub rpm: f64,
    /// Supply voltage at the ESC, volts.
    pub voltage_v: f64,
    /// Supply current, amperes.
    pub current_a: f64,
    /// True when the load cell's converter (or a `saturation` effect on the sensor) clipped.
    pub adc_saturated: bool,
}

/// The simulated plant. Create it with [`Plant::new`], drive it with [`Plant::step`].
#[derive(Debug, Clone)]
pub struct Plant {
    cfg: PlantConfig,
    dt_s: f64,
    a: Matrix2<f64>,
    b: Vector2<f64>,
    x: Vector2<f64>,
    k: u64,
    noise: Option<Normal<f64>>,
    rng: StdRng,
    effects: EffectState,
    last_current_a: f64,
}

impl Plant {
    /// A plant at rest (throttle 0, thrust 0) sampled every `dt_s` seconds, with noise drawn from
    /// a generator seeded by `seed` (same seed, same inputs ⇒ same measurements).
    pub fn new(cfg: &PlantConfig, dt_s: f64, seed: u64) -> Result<Plant, PlantError> {
        cfg.validate(dt_s)?;
        let (a, b) = discretise_second_order(cfg.fn_hz, cfg.zeta, cfg.gain_n_per_throttle, dt_s);
        let noise = if cfg.noise_rms_n > 0.0 {
            Some(
                Normal::new(0.0, cfg.noise_rms_n).map_err(|_| PlantError::InvalidParameter {
                    key: "plant.noise_rms_n",
                    value: cfg.noise_rms_n,
                    reason: "must be a finite standard deviation",
                })?,
            )
        } else {
            None
        };
        let effects = EffectState::new(&cfg.effects, cfg, dt_s, seed)?;
        Ok(Plant {
            cfg: cfg.clone(),
            dt_s,
            a,
            b,
            x: Vector2::zeros(),
            k: 0,
            noise,
            rng: StdRng::seed_from_u64(seed),
            effects,
            last_current_a: cfg.idle_current_a,
        })
    }

    /// The configuration the plant was built from.
    pub fn config(&self) -> &PlantConfig {
        &self.cfg
    }

    /// Sample period, seconds.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// Time of the next sample, seconds since the plant was created.
    pub fn time_s(&self) -> f64 {
        self.k as f64 * self.dt_s
    }

    /// The discrete linear core `(A, B, C)` with state `[T, T']`, `C = [1, 0]`, `D = 0`.
    pub fn linear_core(&self) -> (Matrix2<f64>, Vector2<f64>) {
        (self.a, self.b)
    }

    /// Puts the plant in steady state at `throttle` (as if it had been held there for ever),
    /// without advancing time. Effects with memory (delay lines, extra mode) settle too.
    pub fn settle(&mut self, throttle: f64) {
        let u = self
            .effects
            .input_map(throttle.clamp(0.0, 1.0), self.cfg.battery_v, &self.cfg);
        self.x = Vector2::new(self.cfg.gain_n_per_throttle * u, 0.0);
        self.effects.settle(throttle.clamp(0.0, 1.0), self.x[0]);
        self.last_current_a = self.current_a(self.x[0]);
    }

    /// Advances one sample with `throttle` (0..1; NaN counts as 0, out-of-range values are
    /// clamped as an ESC would) held during this sample; returns what the stand measures at the
    /// start of the sample (`y_k = C x_k`, see the module doc).
    pub fn step(&mut self, throttle: f64) -> Measurement {
        let throttle = if throttle.is_finite() {
            throttle.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let t_s = self.time_s();
        let thrust_true = self.x[0];
        let current_a = self.current_a(thrust_true);
        let voltage_v = self.cfg.battery_v
            - self.cfg.discharge_v_per_s * t_s
            - self.cfg.internal_resistance_ohm * current_a;
        // Measured thrust: the load-cell path (extra mode), additive terms, noise, clip, quantum.
        let mut thrust = self.effects.sensor_path(thrust_true);
        thrust += self.effects.additive(t_s);
        if let Some(n) = self.noise {
            thrust += n.sample(&mut self.rng);
        }
        let (thrust, mut saturated) = self.effects.sensor_clip(thrust);
        let fs = self.cfg.adc_full_scale_n;
        if thrust.abs() >= fs {
            saturated = true;
        }
        let thrust = quantise(thrust.clamp(-fs, fs), self.cfg.quantum_n);
        // Input path: dead time, then the static map and supply sag, then the linear core.
        let delayed = self.effects.delay(throttle);
        let u = self.effects.input_map(delayed, voltage_v, &self.cfg);
        self.x = self.a * self.x + self.b * u;
        self.k += 1;
        self.last_current_a = current_a;
        let t_pos = thrust_true.max(0.0);
        let t_ref = self.cfg.reference_thrust_n();
        Measurement {
            thrust_n: thrust,
            torque_nm: self.cfg.torque_m * t_pos,
            rpm: self.cfg.rpm_at_reference * (t_pos / t_ref).sqrt(),
            voltage_v,
            current_a,
            adc_saturated: saturated,
        }
    }

    /// Supply current at true thrust `t_n` (momentum theory, see the module doc).
    fn current_a(&self, t_n: f64) -> f64 {
        let r = t_n.max(0.0) / self.cfg.reference_thrust_n();
        self.cfg.idle_current_a + self.cfg.current_at_reference_a * r.powf(1.5)
    }

    /// The current drawn at the last step, amperes.
    pub fn last_current_a(&self) -> f64 {
        self.last_current_a
    }
}

/// Rounds `v` to the nearest multiple of `q` (no rounding for `q == 0`).
fn quantise(v: f64, q: f64) -> f64 {
    if q > 0.0 {
        (v / q).round() * q
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
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
                let want =
                    0.5 * cfg.gain_n_per_throttle * step_response(fn_hz, zeta, k as f64 * dt);
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
}
