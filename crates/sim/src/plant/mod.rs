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
//! `k + 1` on, as the Markov convention of `propid_numerics::markov` expects (`Y_0 = D = 0`,
//! `Y_1 = C B`).
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

// `config.rs`: the `[plant]` table, its defaults and range checks; `model.rs`: the plant that
// steps (linear core, effects around it, derived channels, noise, quantisation, saturation).
mod config;
mod model;

#[cfg(test)]
mod tests;

pub(crate) use config::check;
pub use config::{PlantConfig, PlantError};
pub use model::{Measurement, Plant};
