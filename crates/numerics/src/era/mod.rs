//! The Eigensystem Realization Algorithm (Juang & Pappa 1985, "An Eigensystem Realization
//! Algorithm for Modal Parameter Identification and Model Reduction", J. Guidance 8(5),
//! 620–627), on preallocated buffers: [`Era`].
//!
//! From Markov parameters `Y_0 = D`, `Y_k = C A^(k-1) B` ([`crate::markov`]):
//!
//! 1. **Hankel matrices** `H(0)`, `H(1)` of `r × c` blocks, block (a, b) of `H(s)` is
//!    `Y_{a+b+1+s}` (eq. 4, [`crate::hankel`]); their size comes from [`crate::order`].
//! 2. **SVD** `H(0) = U Σ Vᵀ` (eq. 29, [`Era::decompose`]): every singular value by one-sided
//!    Jacobi on the formed matrix ([`crate::svd::dense`]), or the leading ones by FFT products
//!    and Lanczos without forming it ([`crate::svd::truncated`]).
//! 3. **Truncation** to the order `n`, the count of singular values above the noise
//!    ([`crate::order::model_order`]).
//! 4. **Realisation** (eqs. 33–36, [`realize()`], [`Era::realize`]):
//!
//!    ```text
//!    A = Σ_n^-½ U_nᵀ H(1) V_n Σ_n^-½
//!    B = first p columns of Σ_n^½ V_nᵀ
//!    C = first q rows of U_n Σ_n^½
//!    D = Y_0
//!    ```
//!
//! The jackknife ([`crate::uncertainty`]) re-realises leave-one-out sequences at the same
//! order and size ([`Era::decompose_loo`], [`Era::realize_loo`]): warm-started subspace
//! iteration from the model's `V` on the dense path, sign-free Lanczos on the truncated one.

pub mod realize;

pub use realize::{h1_times_v, realize, Factors};

use crate::hankel::{Hankel, HankelDims};
use crate::statespace::AbcdMut;
use crate::svd::dense::DenseSvd;
use crate::svd::subspace::SubspaceSvd;
use crate::svd::truncated::TruncatedSvd;
use crate::svd::{self, SvdChoice, SvdError, SvdPath, Triplets};
use crate::{IdentError, MarkovSeq};

/// Extra singular triplets beyond the largest order, for the order choice and the jackknife's
/// subspace iteration (dense path).
pub const EXTRA_TRIPLETS: usize = 4;

/// Subspace iterations per jackknife re-realisation.
pub const JACKKNIFE_ITERS: usize = 4;

/// What [`Era::decompose`] delivered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Decomposed {
    /// Singular values written (all of `H(0)` on the dense path, `k` on the truncated one).
    pub n_sigma: usize,
    /// Leading triplets converged (all `k` on the dense path).
    pub converged: usize,
}

/// The SVD engines, singular vectors and `H(1) V_n` of ERA, allocated once.
#[derive(Debug)]
pub struct Era {
    kmax: usize,
    dense_rows: usize,
    dense_cols: usize,
    /// `H(0)` formed for the dense path.
    hbuf: Vec<f64>,
    dense: DenseSvd,
    trunc: TruncatedSvd,
    sub: SubspaceSvd,
    /// Leading singular vectors of the model's `H(0)`.
    u: Vec<f64>,
    v: Vec<f64>,
    /// Leading triplets of a leave-one-out `H(0)`.
    loo_sigma: Vec<f64>,
    loo_u: Vec<f64>,
    loo_v: Vec<f64>,
    /// `T = H(1) V_n`.
    t: Vec<f64>,
}

impl Era {
    /// Buffers for Hankel matrices up to `max` (largest `q`, `p`, block rows and columns) and
    /// orders up to `max_order`.
    pub fn new(max: HankelDims, max_order: usize) -> Self {
        let (rows, cols) = (max.rows(), max.cols());
        let wide = rows.min(cols);
        let (dense_rows, dense_cols) = (rows.min(svd::DENSE_MAX_DIM), cols.min(svd::DENSE_MAX_DIM));
        let kmax = (max_order + EXTRA_TRIPLETS).min(wide).max(1);
        Self {
            kmax,
            dense_rows,
            dense_cols,
            hbuf: vec![0.0; dense_rows * dense_cols],
            dense: DenseSvd::new(dense_rows, dense_cols),
            trunc: TruncatedSvd::new(max.r, max.c, max.q, max.p, kmax),
            sub: SubspaceSvd::new(rows, cols, kmax),
            u: vec![0.0; rows * kmax],
            v: vec![0.0; cols * kmax],
            loo_sigma: vec![0.0; kmax],
            loo_u: vec![0.0; rows * kmax],
            loo_v: vec![0.0; cols * kmax],
            t: vec![0.0; rows * max_order],
        }
    }

    /// Most singular triplets computed (`max_order +` [`EXTRA_TRIPLETS`], at most the smaller
    /// Hankel dimension).
    pub fn kmax(&self) -> usize {
        self.kmax
    }

    /// The SVD path for `H(0)` of shape `dims` ([`svd::resolve`] within the dense capacity).
    pub fn path(&self, choice: SvdChoice, dims: &HankelDims) -> Result<SvdPath, SvdError> {
        svd::resolve(
            choice,
            dims.rows(),
            dims.cols(),
            self.dense_rows,
            self.dense_cols,
        )
    }

    /// Left singular vectors of the last [`decompose`](Self::decompose) (`rows × k`).
    pub fn u(&self) -> &[f64] {
        &self.u
    }

    /// Right singular vectors of the last [`decompose`](Self::decompose) (`cols × k`).
    pub fn v(&self) -> &[f64] {
        &self.v
    }

    /// `H(0) = U Σ Vᵀ` of `markov` (shape `dims`): the leading `k` triplets, `sigma` receiving
    /// the singular values. Dense: every singular value, exact to rounding. Truncated: at
    /// least `need` leading triplets converged, the rest of the `k` Ritz estimates for the
    /// order choice.
    pub fn decompose(
        &mut self,
        markov: &MarkovSeq,
        dims: HankelDims,
        path: SvdPath,
        (k, need): (usize, usize),
        sigma: &mut [f64],
    ) -> Result<Decomposed, IdentError> {
        match path {
            SvdPath::Dense => {
                let (rows, cols) = (dims.rows(), dims.cols());
                dims.fill(markov.as_slice(), 0, &mut self.hbuf);
                let out = Triplets::new(sigma, &mut self.u, &mut self.v);
                self.dense.compute(&self.hbuf, rows, cols, k, out)?;
                Ok(Decomposed {
                    n_sigma: rows.min(cols),
                    converged: k,
                })
            }
            SvdPath::Truncated => {
                let h = Hankel::new(markov.as_slice(), dims, 0);
                let out = Triplets::new(&mut sigma[..k], &mut self.u, &mut self.v);
                let converged = self
                    .trunc
                    .compute_at_least(h, k, need.min(k), out)
                    .map_err(SvdError::from)?;
                Ok(Decomposed {
                    n_sigma: k,
                    converged,
                })
            }
        }
    }

    /// Realises `(A, B, C, D)` of order `n` into `out` from the last
    /// [`decompose`](Self::decompose) (`sigma` its singular values): `T = H(1) V_n`, then
    /// [`realize()`].
    pub fn realize(
        &mut self,
        markov: &MarkovSeq,
        dims: HankelDims,
        (n, path): (usize, SvdPath),
        sigma: &[f64],
        out: AbcdMut<'_>,
    ) -> Result<(), IdentError> {
        self.h1v(markov, dims, n, path, false)?;
        let f = Factors {
            sigma,
            u: &self.u,
            v: &self.v,
        };
        realize(markov.as_slice(), &dims, n, f, &self.t, out);
        Ok(())
    }

    /// The leading `n` triplets of a leave-one-out `H(0)` (shape `dims`, near the model's):
    /// on the dense path by [`JACKKNIFE_ITERS`] subspace iterations from the model's `V` with
    /// `n +` [`EXTRA_TRIPLETS`] vectors; on the truncated path only the `n` triplets the
    /// realisation uses, converged to the SVD's tolerance, with the sign-free final small SVD
    /// (fn, ζ and the DC gain do not depend on the signs of the singular vectors).
    pub fn decompose_loo(
        &mut self,
        markov: &MarkovSeq,
        dims: HankelDims,
        n: usize,
        path: SvdPath,
    ) -> Result<(), IdentError> {
        match path {
            SvdPath::Dense => {
                let b = (n + EXTRA_TRIPLETS)
                    .min(self.kmax)
                    .min(dims.rows().min(dims.cols()));
                let out = Triplets::new(&mut self.loo_sigma, &mut self.loo_u, &mut self.loo_v);
                let markov = markov.as_slice();
                self.sub
                    .compute(markov, dims, b, JACKKNIFE_ITERS, &self.v, out)?
            }
            SvdPath::Truncated => {
                self.trunc.set_sign_free(true);
                let h = Hankel::new(markov.as_slice(), dims, 0);
                let out = Triplets::new(&mut self.loo_sigma[..n], &mut self.loo_u, &mut self.loo_v);
                let r = self.trunc.compute_at_least(h, n, n, out);
                self.trunc.set_sign_free(false);
                r.map_err(SvdError::from)?;
            }
        }
        Ok(())
    }

    /// [`realize`](Self::realize) from the last [`decompose_loo`](Self::decompose_loo).
    pub fn realize_loo(
        &mut self,
        markov: &MarkovSeq,
        dims: HankelDims,
        (n, path): (usize, SvdPath),
        out: AbcdMut<'_>,
    ) -> Result<(), IdentError> {
        self.h1v(markov, dims, n, path, true)?;
        let f = Factors {
            sigma: &self.loo_sigma,
            u: &self.loo_u,
            v: &self.loo_v,
        };
        realize(markov.as_slice(), &dims, n, f, &self.t, out);
        Ok(())
    }

    /// `T = H(1) V_n` of the last [`decompose`](Self::decompose) into `t` (`rows × n`,
    /// column-major, `n` at most [`kmax`](Self::kmax)): the realisation's product for every
    /// order up to `n` at once (the first `m` columns are `H(1) V_m`), for the stabilization
    /// diagram ([`crate::stabilization`]).
    pub fn h1_times_v_into(
        &mut self,
        markov: &MarkovSeq,
        dims: HankelDims,
        n: usize,
        path: SvdPath,
        t: &mut [f64],
    ) -> Result<(), IdentError> {
        if n > self.kmax || t.len() < dims.rows() * n {
            return Err(SvdError::Dimensions("H(1) V: more columns than triplets or room").into());
        }
        h1v_into(&mut self.trunc, markov, dims, n, path, &self.v, t)
    }

    /// `t = H(1) V_n` (of the leave-one-out `V` when `loo`), by FFT products on the truncated
    /// path and direct products on the dense one.
    fn h1v(
        &mut self,
        markov: &MarkovSeq,
        dims: HankelDims,
        n: usize,
        path: SvdPath,
        loo: bool,
    ) -> Result<(), IdentError> {
        let v = if loo { &self.loo_v } else { &self.v };
        h1v_into(&mut self.trunc, markov, dims, n, path, v, &mut self.t)
    }
}

/// `t = H(1) V_n` for the `V` given, by FFT products (`trunc`'s operator) on the truncated path
/// and direct products on the dense one.
fn h1v_into(
    trunc: &mut TruncatedSvd,
    markov: &MarkovSeq,
    dims: HankelDims,
    n: usize,
    path: SvdPath,
    v: &[f64],
    t: &mut [f64],
) -> Result<(), IdentError> {
    let (rows, cols) = (dims.rows(), dims.cols());
    match path {
        SvdPath::Dense => h1_times_v(markov.as_slice(), &dims, n, v, t),
        SvdPath::Truncated => {
            let h1 = Hankel::new(markov.as_slice(), dims, 1);
            for l in 0..n {
                trunc
                    .apply(
                        h1,
                        &v[l * cols..(l + 1) * cols],
                        &mut t[l * rows..(l + 1) * rows],
                    )
                    .map_err(SvdError::from)?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Y_k = C A^(k-1) B` of a 2nd-order system with poles `0.9 ± 0.3i`, `D = 0.25`.
    fn exact(len: usize) -> MarkovSeq {
        let a = [[0.9, -0.3], [0.3, 0.9]];
        let (b, c) = ([1.0, 0.5], [0.7, -0.2]);
        let mut x = b;
        let mut data = vec![0.25];
        for _ in 1..len {
            data.push(c[0] * x[0] + c[1] * x[1]);
            x = [
                a[0][0] * x[0] + a[0][1] * x[1],
                a[1][0] * x[0] + a[1][1] * x[1],
            ];
        }
        MarkovSeq::from_data(1, 1, data).unwrap()
    }

    #[test]
    fn exact_data_give_the_system_back_on_both_paths() {
        let markov = exact(81);
        let dims = HankelDims {
            q: 1,
            p: 1,
            r: 40,
            c: 40,
        };
        for path in [SvdPath::Dense, SvdPath::Truncated] {
            let mut era = Era::new(dims, 4);
            let mut sigma = vec![0.0; 40];
            let k = era.kmax();
            let got = era
                .decompose(&markov, dims, path, (k, 2), &mut sigma)
                .unwrap();
            assert!(got.converged >= 2, "{path:?}");
            assert!(sigma[2] < 1e-10 * sigma[0], "{path:?}: rank 2");
            let (mut a, mut b, mut c, mut d) = ([0.0; 4], [0.0; 2], [0.0; 2], [0.0; 1]);
            let out = AbcdMut {
                a: &mut a,
                b: &mut b,
                c: &mut c,
                d: &mut d,
            };
            era.realize(&markov, dims, (2, path), &sigma, out).unwrap();
            // Trace and determinant of A are those of the true A (similarity invariants).
            assert!((a[0] + a[3] - 1.8).abs() < 1e-10, "{path:?}: {a:?}");
            assert!((a[0] * a[3] - a[1] * a[2] - 0.9).abs() < 1e-10, "{path:?}");
            assert_eq!(d[0], 0.25);
            // C A^(k-1) B reproduces the Markov parameters.
            let mut x = b;
            for k in 1..20 {
                let y = c[0] * x[0] + c[1] * x[1];
                assert!((y - markov.get(k, 0, 0)).abs() < 1e-10, "{path:?} Y_{k}");
                x = [a[0] * x[0] + a[2] * x[1], a[1] * x[0] + a[3] * x[1]];
            }
        }
    }
}
