//! The linear part of a model as published ([`LinearPart`]: the core's states, extended by the
//! series terms) and the poles of a 2nd-order core.

use propid_numerics::discretise::discretise_second_order;

pub use propid_numerics::modal::second_order_poles;

/// The linear part of a model as published: the discrete `x_{k+1} = A x_k + B u_k`,
/// `y_k = C x_k` (rows of `A`, `B`, `C`) and the continuous poles, built from the core and
/// extended by the series terms ([`crate::term::Term::extend_linear`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearPart {
    /// `A`, one row per state.
    pub a: Vec<Vec<f64>>,
    /// `B`, one row per state.
    pub b: Vec<Vec<f64>>,
    /// `C`, one row per output.
    pub c: Vec<Vec<f64>>,
    /// Continuous poles `[re, im]`, rad/s.
    pub poles_s: Vec<[f64; 2]>,
}

impl LinearPart {
    /// The core `T'' + 2ζωn T' + ωn² T = ωn² k u` with state `[T, T']`, sampled every `dt_s`.
    pub fn core(fn_hz: f64, zeta: f64, k: f64, dt_s: f64) -> LinearPart {
        let (a2, b2) = discretise_second_order(fn_hz, zeta, 1.0, dt_s);
        LinearPart {
            a: vec![vec![a2[(0, 0)], a2[(0, 1)]], vec![a2[(1, 0)], a2[(1, 1)]]],
            b: vec![vec![b2[0] * k], vec![b2[1] * k]],
            c: vec![vec![1.0, 0.0]],
            poles_s: second_order_poles(fn_hz, zeta).to_vec(),
        }
    }
}
