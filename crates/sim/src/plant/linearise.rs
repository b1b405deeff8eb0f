//! The motor plant ([`super::motor`]) linearised at an operating point: the truth a linear
//! model identified there should match, and how far spin-down being slower than spin-up keeps
//! any linear model from it.
//!
//! # Equilibrium at throttle `u₀` (time `t`)
//! `n₀ = n_ss(u₀, V₀')` with the loaded supply `V₀' = V_oc(t) − R · I(k_T n₀²)` — a fixed point,
//! found by iteration (a contraction: its slope is the sag `ε` below, a few per cent).
//!
//! # Small-signal model (`δn = n − n₀`, `δu = u − u₀`)
//! The supply sags as the speed rises (more current), and the ESC's output with it:
//!
//! ```text
//!   ∂n_ss/∂u = n₀ / u₀,
//!   ∂n_ss/∂n = (n₀ / V₀') · ∂V/∂I · ∂I/∂T · ∂T/∂n = −ε,   ε = 3 R (I₀ − I_idle) / V₀'
//! ```
//!
//! (`I − I_idle ∝ T^{3/2} ∝ n³`). The lag `n' = (n_ss − n)/τ` then linearises to
//! `τ_lin δn' = (n₀/u₀)/(1 + ε) · δu − δn`, and with `δT = 2 k_T n₀ δn`:
//!
//! ```text
//!   gain  g = dT/du = 2 T₀ / (u₀ (1 + ε))            N per unit throttle (grows ∝ u₀)
//!         (with [plant.motor]'s dead band u_z, map exponent a and thrust exponent e:
//!          g = e a T₀ / ((u₀ − u_z)(1 + ε)), ε = (e + 1) R (I₀ − I_idle) / V₀')
//!   τ_lin = τ(n₀, dir) / (1 + ε)                       one per direction: τ_up, τ_down
//!   θ     = round(dead_time_s / dt) · dt
//!   G(s)  = g e^{−sθ} / (τ_lin s + 1)
//! ```
//!
//! (the time constant's change with speed does not enter: it multiplies `n_ss − n`, zero at the
//! equilibrium). The effects of `[plant.effects]` are not part of this truth; an `extra_mode`
//! (a stand resonance in the load-cell path) multiplies `G(s)` by `ωm²/(s² + 2ζωm s + ωm²)`,
//! which leaves the gain as it is and adds its own pair of poles.
//!
//! # Spin-down slower than spin-up: no linear model is exact
//! The lag has two slopes at the equilibrium, so a linear model fitted to pulses of both signs
//! averages them. In discrete time (`a = e^{−dt/τ}`, `a_lin = a − (1 − a) ε`) a one-sample
//! pulse up rises with `τ_up` and decays with `τ_down`, a pulse down the other way round; the
//! average response per unit throttle, `d + 1 + j` samples after the pulse, is
//!
//! ```text
//!   h̄ = (g (1 + ε) / 2) · [(1 − a_up) a_down,lin^j + (1 − a_down) a_up,lin^j]
//! ```
//!
//! whose sum, the DC gain of the ideal linear fit, is `g · (ρ + 1/ρ)/2` with
//! `ρ = (1 − a_up)/(1 − a_down)`: above the true gain by [`MotorLinear::pulse_gain_factor`]
//! `− 1`, and its time constant lies between `τ_up` and `τ_down`. Steps (`identify`'s step
//! figures) see each direction's τ and the gain `g` itself.

use super::{PlantConfig, PlantKind};

/// Steady state of the motor plant at one throttle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Equilibrium {
    /// Rotor speed `n₀`, rev/min.
    pub speed_rpm: f64,
    /// Thrust `T₀ = k_T n₀²`, newtons.
    pub thrust_n: f64,
    /// Supply current `I₀`, amperes.
    pub current_a: f64,
    /// Loaded supply voltage `V₀'`, volts.
    pub voltage_v: f64,
}

/// The motor plant linearised at one operating point (formulas in the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorLinear {
    /// Operating point `u₀`, throttle 0..1.
    pub operating_point: f64,
    /// The steady state there.
    pub equilibrium: Equilibrium,
    /// Supply-sag factor `ε = 3 R (I₀ − I_idle) / V₀'`.
    pub sag: f64,
    /// Small-signal thrust gain `g = dT/du`, N per unit throttle.
    pub gain_n_per_throttle: f64,
    /// Linearised spin-up time constant `τ(n₀, up)/(1 + ε)`, seconds.
    pub tau_up_s: f64,
    /// Linearised spin-down time constant `τ(n₀, down)/(1 + ε)`, seconds.
    pub tau_down_s: f64,
    /// Dead time `θ = d · dt`, seconds.
    pub dead_time_s: f64,
    /// Dead time in samples, `d`.
    pub dead_time_samples: usize,
    /// Sample period, seconds.
    pub dt_s: f64,
    /// `(ρ + 1/ρ)/2`: the DC gain of the ideal linear fit to pulses of both signs over `g`.
    pub pulse_gain_factor: f64,
}

/// The equilibrium at mapped throttle `u` and time `t_s` (the supply sag solved by iteration).
pub fn equilibrium(plant: &PlantConfig, u: f64, t_s: f64) -> Equilibrium {
    let m = &plant.motor;
    let v_oc = plant.battery_v - plant.discharge_v_per_s * t_s;
    let mut v = v_oc;
    let mut out = Equilibrium {
        speed_rpm: 0.0,
        thrust_n: 0.0,
        current_a: plant.idle_current_a,
        voltage_v: v,
    };
    for _ in 0..100 {
        let n = m.speed_ss(plant, u, v);
        let t = m.thrust_n(plant, n);
        let i = m.current_a(plant, n, 0.0);
        let v_next = v_oc - plant.internal_resistance_ohm * i;
        out = Equilibrium {
            speed_rpm: n,
            thrust_n: t,
            current_a: i,
            voltage_v: v_next,
        };
        if (v_next - v).abs() <= 1e-12 * v_oc.abs() {
            break;
        }
        v = v_next;
    }
    out
}

impl PlantConfig {
    /// The motor plant linearised at throttle `u0` for a sample period `dt_s` and time `t_s`
    /// (the battery discharges); `None` for the 2nd-order plant, whose truth is its own
    /// parameters everywhere.
    pub fn linearise(&self, u0: f64, dt_s: f64, t_s: f64) -> Option<MotorLinear> {
        if self.kind != PlantKind::Motor || !(u0 > 0.0 && dt_s > 0.0) {
            return None;
        }
        let m = &self.motor;
        let eq = equilibrium(self, u0, t_s);
        let load_a = eq.current_a - self.idle_current_a;
        let e = m.thrust_exponent;
        let sag = (e + 1.0) * self.internal_resistance_ohm * load_a / eq.voltage_v;
        // ∂ln n_ss/∂u of the map `((u − u₀)/(u_ref − u₀))^a`.
        let above = u0 - m.command_zero;
        if above <= 0.0 {
            return None;
        }
        let map_slope = m.speed_map_exponent / above;
        let tau_up = m.tau_s(self, eq.speed_rpm, true);
        let tau_down = m.tau_s(self, eq.speed_rpm, false);
        let (a_up, a_down) = ((-dt_s / tau_up).exp(), (-dt_s / tau_down).exp());
        let rho = (1.0 - a_up) / (1.0 - a_down);
        let d = m.dead_time_samples(dt_s);
        Some(MotorLinear {
            operating_point: u0,
            equilibrium: eq,
            sag,
            gain_n_per_throttle: e * eq.thrust_n * map_slope / (1.0 + sag),
            tau_up_s: tau_up / (1.0 + sag),
            tau_down_s: tau_down / (1.0 + sag),
            dead_time_s: d as f64 * dt_s,
            dead_time_samples: d,
            dt_s,
            pulse_gain_factor: 0.5 * (rho + 1.0 / rho),
        })
    }
}

impl MotorLinear {
    /// The average response per unit throttle of a one-sample pulse up and one down (the
    /// module doc's `h̄`), `len` samples from the pulse's sample on: what an exact linear fit
    /// to pulses of both signs reproduces.
    pub fn pulse_average(&self, len: usize) -> Vec<f64> {
        let (dt, eps) = (self.dt_s, self.sag);
        // the raw lags of each direction (the linearised τ times 1 + ε)
        let a_up = (-dt / (self.tau_up_s * (1.0 + eps))).exp();
        let a_down = (-dt / (self.tau_down_s * (1.0 + eps))).exp();
        let (up_lin, down_lin) = (a_up - (1.0 - a_up) * eps, a_down - (1.0 - a_down) * eps);
        let scale = 0.5 * self.gain_n_per_throttle * (1.0 + eps);
        (0..len)
            .map(|k| match k.checked_sub(self.dead_time_samples + 1) {
                None => 0.0,
                Some(j) => {
                    let j = j as i32;
                    scale * ((1.0 - a_up) * down_lin.powi(j) + (1.0 - a_down) * up_lin.powi(j))
                }
            })
            .collect()
    }
}
