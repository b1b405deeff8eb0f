//! Output-error refinement of the linear core: a modal state-space model fitted to a record by
//! minimising the free-run simulation error, started from the OKID/ERA realisation (and an ARX
//! fit), its order and an integrator chosen by a free-run check on a held-out tail.
//!
//! - [`model`]: the modal structure, its simulation and its `A, B, C, D`.
//! - [`fit`]: the output-error criterion, its analytic Jacobian (sensitivity equations) and
//!   the Levenberg–Marquardt fit ([`crate::levenberg_marquardt::minimise_normal`]).
//! - [`apply`]: the refinement of an OKID + ERA identification and the report it replaces.
//! - [`select`]: candidates (orders, starts, integrator or not) scored on the held-out tail,
//!   and the ERA model's own score there ([`select::tail_score_abcd`]).
//!
//! # Model (output-error form, Ljung, *System Identification*, 2nd ed., §4.2 and §7.2)
//!
//! One input `u`, `q` outputs, `v_k = u_k − ū` (ū the record's mean):
//!
//! ```text
//!   x_{k+1} = A x_k + B v_k,     ŷ_k = y_off + r·k/N + C x_k + D v_k + Σ_s w_s φ_s(k)
//! ```
//!
//! with `A` block-diagonal in real modal form: a real pole `p` is a 1 × 1 block (`B` entry 1);
//! a complex pair `σ ± jω` the block `[[σ, ω], [−ω, σ]]` (`B` entries `[1, 0]`); with
//! `integrator`, one more block fixed at `p = 1` (the pole at `z = 1` is structural, never
//! moved by the fit and never given a DC gain). `B` is fixed, so `(poles, C, D)` is a minimal
//! parameterisation of the transfer function (one numerator coefficient per pole per
//! output). The initial state enters through the free responses `φ_s(k)` (`A_mᵏ e₁` of each
//! mode, both components for a pair) with coefficients `w`, linear in `ŷ`; `y_off` is the output
//! offset and `r` a ramp (only with the integrator: a constant input offset integrated, so
//! that the saved `u₀ = ū − r/(N c_I)` carries it).
//!
//! # Criterion and Jacobian (Ljung §7.3, §10.2)
//!
//! `V(θ) = Σ_k Σ_i (ŷ_{i,k}(θ) − y_{i,k})²` over the samples with a measured output. The
//! derivative of `ŷ` with respect to a pole parameter is obtained by simulating the
//! sensitivity equations alongside the model (not by finite differences): for a real mode
//! `∂x⁺/∂p = p ∂x/∂p + x`; for a pair `∂x⁺/∂σ = A_m ∂x/∂σ + x` and
//! `∂x⁺/∂ω = A_m ∂x/∂ω + J x` with `J = [[0, 1], [−1, 0]]` (the same for `φ`); the derivatives
//! with respect to `C, D, y_off, w, r` are the regressors themselves. `JᵀJ` and `Jᵀr` are
//! accumulated sample by sample and Levenberg–Marquardt takes the steps. A step that puts a
//! pole on or outside the circle of radius [`MAX_RADIUS`] is refused (and retried shorter):
//! the fit never leaves the stable models (Ljung §10.2, "stability projection").
//!
//! The start: for given poles the criterion is linear in everything else, so the start is
//! the least-squares solution for `(C, D, y_off, w, r)` at the starting poles (the
//! separable structure of Golub & Pereyra 1973, used once), from the poles of the ERA
//! realisation of each order ([`crate::stabilization`]'s diagram) and of an ARX fit
//! ([`select::arx_poles`]).

pub mod apply;
pub mod fit;
pub mod model;
pub mod select;

#[cfg(test)]
mod tests;

pub use apply::{apply, refine, Refinement};
pub use fit::{fit, FitOptions, Fitted};
pub use model::OeModel;
pub use select::{select, Candidate, SelectOptions, Selection};

/// Largest pole radius a fit may reach (the unit circle, less a margin).
pub const MAX_RADIUS: f64 = 1.0 - 1e-9;
