//! The realisation step of ERA (Juang & Pappa 1985, J. Guidance 8(5), eqs. 29–36).
//!
//! With `H(0) = U Σ Vᵀ` truncated to the order `n` (`U_n`: `rq × n`, `V_n`: `cp × n`),
//! `P = U_n Σ_n^½` is the realised observability matrix and `Q = Σ_n^½ V_nᵀ` the realised
//! controllability matrix, `H(0) ≈ P Q`. Since `H(1) = P A Q` for exact data,
//!
//! ```text
//! A = Σ^-½ U_nᵀ H(1) V_n Σ^-½
//! B = first p columns of Σ^½ V_nᵀ
//! C = first q rows of U_n Σ^½
//! D = Y_0
//! ```
//!
//! `H(1) V_n` is computed by Hankel products ([`h1_times_v`], or FFT products on the
//! truncated path), `H(1)` is never formed.
//! Storage: `a` (`n × n`), `b` (`n × p`), `c` (`q × n`), `d` (`q × p`), all column-major.

use crate::hankel::HankelDims;
use crate::statespace::AbcdMut;

/// `T = H(1) V_n` (`rows × n`, column-major) by direct products with the Markov parameters,
/// `O(rows · cols · n)`; the truncated path uses FFT products instead.
pub fn h1_times_v(markov: &[f64], dims: &HankelDims, n: usize, v: &[f64], t: &mut [f64]) {
    let (rows, cols) = (dims.rows(), dims.cols());
    for l in 0..n {
        dims.apply(
            markov,
            1,
            &v[l * cols..(l + 1) * cols],
            &mut t[l * rows..(l + 1) * rows],
        );
    }
}

/// The leading singular triplets of `H(0)` (`sigma`, `u`: `rows × k`, `v`: `cols × k`,
/// column-major, `k >= n`), borrowed.
#[derive(Debug, Clone, Copy)]
pub struct Factors<'a> {
    /// Singular values, descending.
    pub sigma: &'a [f64],
    /// Left singular vectors.
    pub u: &'a [f64],
    /// Right singular vectors.
    pub v: &'a [f64],
}

/// Realises `(A, B, C, D)` of order `n` into `out` from the leading triplets `f` of `H(0)` and
/// `t = H(1) V_n` (`rows × n`).
pub fn realize(
    markov: &[f64],
    dims: &HankelDims,
    n: usize,
    f: Factors<'_>,
    t: &[f64],
    out: AbcdMut<'_>,
) {
    let Factors { sigma, u, v } = f;
    let AbcdMut { a, b, c, d } = out;
    let (rows, cols, q, p) = (dims.rows(), dims.cols(), dims.q, dims.p);
    for i in 0..n {
        let ui = &u[i * rows..(i + 1) * rows];
        for j in 0..n {
            let tj = &t[j * rows..(j + 1) * rows];
            let dot: f64 = ui.iter().zip(tj).map(|(x, y)| x * y).sum();
            a[i + j * n] = dot / (sigma[i] * sigma[j]).sqrt();
        }
    }
    for l in 0..n {
        let s = sigma[l].sqrt();
        for j in 0..p {
            b[l + j * n] = s * v[j + l * cols];
        }
        for i in 0..q {
            c[i + l * q] = u[i + l * rows] * s;
        }
    }
    d[..q * p].copy_from_slice(&markov[..q * p]);
}
