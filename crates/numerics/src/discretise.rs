//! Exact zero-order-hold discretisation of a continuous 2nd-order system.
//!
//! ```text
//!   T'' + 2 ζ ωn T' + ωn² T = ωn² k u,     ωn = 2π fn_hz
//! ```
//!
//! With the state `x = [T, T']` the continuous system is `x' = Ac x + Bc u`,
//! `Ac = [[0, 1], [−ωn², −2ζωn]]`, `Bc = [0, ωn² k]ᵀ`. For an input held constant over each
//! sample (zero-order hold) the exact discrete system `x_{k+1} = A x_k + B u_k` has
//! `A = e^{Ac dt}` and `B = ∫₀^dt e^{Ac s} ds · Bc`; both are read off one matrix exponential
//! of the augmented matrix (Van Loan 1978, "Computing integrals involving the matrix
//! exponential", IEEE TAC 23(3), 395–404):
//!
//! ```text
//!   exp([[Ac, Bc], [0, 0]] dt) = [[A, B], [0, 1]]
//! ```
//!
//! The simulated plant (`propid-sim`) and the models `propid diagnose` fits use this one
//! function, so a clean simulated plant and the fitted model with its parameters agree to
//! rounding.

use nalgebra::{Matrix2, Matrix3, Vector2};

/// Exact zero-order-hold discretisation of `T'' + 2ζωn T' + ωn² T = ωn² k u` with state
/// `[T, T']`, sampled every `dt_s` seconds; returns `(A, B)` (see the module doc). A
/// non-finite parameter (an infinite `ωn`: a fit that drove a time scale to 0) gives NaN
/// matrices at once: nalgebra's exponential scales by the norm and never ends on an
/// infinite one.
pub fn discretise_second_order(
    fn_hz: f64,
    zeta: f64,
    k: f64,
    dt_s: f64,
) -> (Matrix2<f64>, Vector2<f64>) {
    let wn = 2.0 * std::f64::consts::PI * fn_hz;
    let m = Matrix3::new(
        0.0,
        1.0,
        0.0,
        -wn * wn,
        -2.0 * zeta * wn,
        wn * wn * k,
        0.0,
        0.0,
        0.0,
    ) * dt_s;
    if !m.iter().all(|v| v.is_finite()) {
        return (Matrix2::repeat(f64::NAN), Vector2::repeat(f64::NAN));
    }
    let e = m.exp();
    let a = Matrix2::new(e[(0, 0)], e[(0, 1)], e[(1, 0)], e[(1, 1)]);
    let b = Vector2::new(e[(0, 2)], e[(1, 2)]);
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_non_finite_parameter_gives_nan_at_once() {
        for (f, z, k, dt) in [
            (f64::INFINITY, 0.7, 1.0, 1e-3),
            (5.0, f64::NAN, 1.0, 1e-3),
            (5.0, 0.7, f64::INFINITY, 1e-3),
        ] {
            let (a, b) = discretise_second_order(f, z, k, dt);
            assert!(a.iter().chain(b.iter()).all(|v| v.is_nan()), "{a} {b}");
        }
        // A zero step is the identity (a lead of a whole sample leaves no first part).
        let (a, b) = discretise_second_order(5.0, 0.7, 1.0, 0.0);
        assert_eq!(a, Matrix2::identity());
        assert_eq!(b, Vector2::zeros());
    }

    #[test]
    fn step_response_settles_at_the_static_gain() {
        // x_{k+1} = A x_k + B u with u = 1 converges to [k, 0].
        let (a, b) = discretise_second_order(5.0, 0.7, 3.0, 1e-3);
        let mut x = Vector2::zeros();
        for _ in 0..5000 {
            x = a * x + b;
        }
        assert!((x[0] - 3.0).abs() < 1e-9 && x[1].abs() < 1e-9, "{x}");
    }

    #[test]
    fn state_matrix_is_the_exponential_of_the_continuous_one() {
        // Eigenvalues of A are e^{s dt} for the continuous poles s = −ζωn ± iωn√(1−ζ²):
        // trace A = 2 e^{−ζωn dt} cos(ωd dt), det A = e^{−2ζωn dt}.
        let (fn_hz, zeta, dt) = (8.0, 0.3, 2e-3);
        let (a, _) = discretise_second_order(fn_hz, zeta, 1.0, dt);
        let wn = 2.0 * std::f64::consts::PI * fn_hz;
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        let decay = (-zeta * wn * dt).exp();
        assert!((a.trace() - 2.0 * decay * (wd * dt).cos()).abs() < 1e-12);
        assert!((a.determinant() - decay * decay).abs() < 1e-12);
    }
}
