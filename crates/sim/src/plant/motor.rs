//! The motor plant (`[plant] kind = "motor"`): rotor speed as a first-order lag of the throttle
//! with a direction- and speed-dependent time constant, an ESC dead time, thrust ∝ speed² and a
//! supply that sags with the current drawn. Its linearisation at an operating point is in
//! [`super::linearise`].
//!
//! # The model
//! Rotor speed `n` (rev/min) follows the throttle `u` (0..1) held during each sample as
//!
//! ```text
//!   n' = (n_ss(u, V) − n) / τ(n, dir)
//!   n_ss(u, V) = n_ref · (u / u_ref) · (V / V₀)         (the ESC applies u·V to the motor)
//!   τ(n, dir)  = τ_dir · (n_ref / max(n, n_ref/10))^γ    (dir = up when n_ss ≥ n, else down)
//!   T = k_T n²,   k_T = T_ref / n_ref²                    (propeller momentum theory)
//! ```
//!
//! with `u_ref = reference_throttle`, `n_ref = rpm_at_reference` (at the open-circuit voltage
//! `V₀ = battery_v`), `T_ref = thrust_at_reference_n`, `τ_up = tau_up_s`,
//! `τ_down = tau_down_s` (spin-down is slower: the ESC brakes less than it drives) and
//! `γ = tau_speed_exponent` (the propeller's drag grows with speed, so the rotor answers faster
//! at speed; `γ = 0`, the default: one τ per direction). The supply is the plant's battery:
//! `V = battery_v − discharge_v_per_s · t − internal_resistance_ohm · I`, with the current
//! `I = idle_current_a + current_at_reference_a · (T / T_ref)^{3/2}` (shaft power ∝ `n³`).
//!
//! Over one sample `dt` the direction and `τ` are frozen at the sample's start and the lag is
//! integrated exactly: `n_{k+1} = n_ss + (n_k − n_ss) · e^{−dt/τ}`. The throttle reaches the
//! motor `d = round(dead_time_s / dt)` samples late (ESC update and commutation latency), and,
//! as with the 2nd-order plant, the throttle held during sample `k` shows in the thrust from
//! sample `k + 1 + d` on.
//!
//! These are the equations of the stand model of the numerics layer
//! ([`propid_numerics::stand_model`]: `SpeedMap`, `RotorLaw`, `T = k_T nᵉ` with `e = 2`),
//! which steps them here ([`MotorConfig::stand_params`] gives the plant as that model's
//! parameters, the truth its fit is held against); the simulated current
//! `I_idle + I_ref (T/T_ref)^{3/2}` is its current law `I₀ + k_I n³` at `e = 2`.

use crate::delay_line::DelayLine;

use super::{MotorConfig, PlantConfig, PlantError};

/// The motor's state: rotor speed and the ESC's delay line.
#[derive(Debug, Clone)]
pub(crate) struct Motor {
    cfg: MotorConfig,
    dt_s: f64,
    /// Rotor speed, rev/min.
    n: f64,
    /// The ESC's dead time.
    delay: DelayLine,
}

impl Motor {
    /// A motor at rest sampled every `dt_s` seconds.
    pub(crate) fn new(plant: &PlantConfig, dt_s: f64) -> Result<Motor, PlantError> {
        plant.motor.validate()?;
        Ok(Motor {
            cfg: plant.motor.clone(),
            dt_s,
            n: 0.0,
            delay: DelayLine::new(plant.motor.dead_time_samples(dt_s)),
        })
    }

    /// Rotor speed, rev/min.
    pub(crate) fn speed_rpm(&self) -> f64 {
        self.n
    }

    /// Thrust `k_T nᵉ`, newtons ([`MotorConfig::thrust_n`]).
    pub(crate) fn thrust_n(&self, plant: &PlantConfig) -> f64 {
        self.cfg.thrust_n(plant, self.n)
    }

    /// `n'` under the (delayed, mapped) throttle `u` and supply `voltage_v`, rev/min per s.
    pub(crate) fn rate(&self, plant: &PlantConfig, u: f64, voltage_v: f64) -> f64 {
        let target = self.cfg.speed_ss(plant, u, voltage_v);
        self.cfg.rotor_law(plant).rate(self.n, target)
    }

    /// The ESC's delay line: pushes `u`, returns the throttle of `d` samples ago (0 before the
    /// line is full, the settled throttle after [`Motor::settle`]).
    pub(crate) fn delay(&mut self, u: f64) -> f64 {
        self.delay.push(u)
    }

    /// Advances one sample with the (delayed, mapped) throttle `u` held and supply `voltage_v`.
    pub(crate) fn advance(&mut self, plant: &PlantConfig, u: f64, voltage_v: f64) {
        let target = self.cfg.speed_ss(plant, u, voltage_v);
        self.n = self.cfg.rotor_law(plant).advance(self.n, target, self.dt_s);
    }

    /// Steady state at throttle `throttle` and mapped throttle `u` under the supply `voltage_v`.
    pub(crate) fn settle_at(&mut self, plant: &PlantConfig, throttle: f64, u: f64, voltage_v: f64) {
        self.delay.settle(throttle);
        self.n = self.cfg.speed_ss(plant, u, voltage_v);
    }

    /// Steady state at throttle `throttle` (the ESC's line full of it) and mapped throttle `u`,
    /// with the supply sag solved as in [`super::linearise`].
    pub(crate) fn settle(&mut self, plant: &PlantConfig, throttle: f64, u: f64, t_s: f64) {
        self.delay.settle(throttle);
        self.n = super::linearise::equilibrium(plant, u, t_s).speed_rpm;
    }
}
