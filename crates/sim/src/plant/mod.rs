//! The simulated motor + propeller + load cell, of one of two kinds (`[plant] kind`):
//! `"second_order"` (the default of the code and the tests), a discrete 2nd-order thrust
//! response with the same dynamics at every throttle, described below; or `"motor"`
//! ([`motor`]: thrust ∝ speed², a first-order speed lag slower down than up, dead time, supply
//! sag; linearised per operating point in [`MotorLinear`]), the stand of `config/sim.toml` and
//! `propid demo`. Both have seeded noise, quantisation and physically plausible derived
//! channels (torque, rotor speed, battery voltage and current). Effects that real benches show (dead time, a static
//! map, an extra mode, drift, a periodic disturbance, supply sag, saturation) are switched on in
//! [`EffectsConfig`](super::effects::EffectsConfig) and applied around the linear core.
//!
//! # The 2nd-order core
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
//! `k + 1` on, as the Markov convention of `propid_numerics::markov` expects (`Y_0 = D = 0`,
//! `Y_1 = C B`).
//!
//! # Derived channels (noise-free thrust `T ≥ 0` drives them; the motor's rpm is its state)
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

// `config.rs`: the `[plant]` table, its defaults and range checks; `model.rs`: the plant that
// steps (its core, effects around it, derived channels, noise, quantisation, saturation);
// `motor.rs`: the motor core and `[plant.motor]`; `linearise.rs`: the motor's linearisation.
mod config;
mod linearise;
mod model;
pub mod motor;
pub mod sensors;

#[cfg(test)]
mod motor_tests;
#[cfg(test)]
mod tests;

pub(crate) use config::check;
pub use config::{MotorConfig, PlantConfig, PlantError, PlantKind};
pub use linearise::{equilibrium, Equilibrium, MotorLinear};
pub use model::{Measurement, Plant};
pub use sensors::{SensorConfig, SensorsConfig};
