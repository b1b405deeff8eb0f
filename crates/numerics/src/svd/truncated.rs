//! Leading singular triplets of a block Hankel matrix without forming it: Golub–Kahan–Lanczos
//! bidiagonalisation with full reorthogonalisation, on FFT Hankel products ([`HankelOp`]).
//!
//! # Method
//! Golub & Kahan (1965), in the form of Golub & Van Loan, *Matrix Computations* 4th ed.,
//! alg. 10.4.1 ("Lanczos bidiagonalization"): from a unit start vector `v₁`,
//!
//! $$\alpha_j u_j = H v_j - \beta_{j-1} u_{j-1}, \qquad
//!   \beta_j v_{j+1} = H^T u_j - \alpha_j v_j ,$$
//!
//! each new vector reorthogonalised against all previous ones (classical Gram–Schmidt, with a
//! second pass when Kahan's criterion asks for it: "twice is enough", Giraud et al. 2005), so
//! that after `m` steps
//!
//! $$H V_m = U_m B_m, \qquad H^T U_m = V_m B_m^T + \beta_m v_{m+1} e_m^T$$
//!
//! with `B_m` upper bidiagonal (diagonal `α`, superdiagonal `β`). With `B_m = P Σ Qᵀ` (small
//! SVD, [`SmallJacobi`]) the Ritz triplets `(σ_i, U_m p_i, V_m q_i)` satisfy `H v = σ u`
//! exactly and
//!
//! $$\| H^T u_i - \sigma_i v_i \| = \beta_m\, |e_m^T p_i| ,$$
//!
//! the residual used as the convergence test: the leading `k` triplets are accepted when every
//! residual is at most `tol · σ₁` (default `tol` = [`DEFAULT_TOLERANCE`]). By the standard
//! perturbation bounds (Golub & Van Loan §8.6) the singular value errors are then at most
//! `residual² / gap` and the subspace angles at most `residual / gap`, `gap` being the
//! distance from `σ_i` to the singular values not captured. Breakdowns (`α_j` or `β_j` at
//! rounding level relative to the largest coefficient seen: the Krylov space is invariant, e.g.
//! a noise-free Hankel of rank `n` after `n` steps) continue with a fresh pseudo-random
//! vector orthogonal to the basis and a zero coefficient, which keeps both relations exact.
//!
//! # Accuracy (tested in `tests/svd_accuracy.rs` against nalgebra's dense SVD)
//! Where the requested `k` lies inside a spectral gap (model order on data with noise), the
//! singular values agree to ~1e-13 relative to σ₁ and the subspaces to ~1e-10 or better within
//! a few dozen steps. When `k` reaches into a cluster of noise singular values the residual
//! test may fail within the step budget: then [`TruncatedError::NotConverged`] is returned (with the
//! number of leading triplets that did converge), never unconverged vectors. The Ritz values of
//! the last small SVD ([`TruncatedSvd::ritz_values`]) remain available as lower estimates of
//! the leading singular values.
//!
//! # Cost and memory
//! Each step costs one product with `H` and one with `Hᵀ` (`p + q` FFTs each, see
//! [`HankelOp`]) plus `O((rq + cp) m)` for the reorthogonalisation. Memory is the two Lanczos
//! bases, `(r q + c p) × (max_steps + 1)` values, plus the FFT buffers: `O(N)` in the record
//! length for a fixed step budget. Everything is allocated in [`TruncatedSvd::new`];
//! `compute`, `apply`, `apply_t` and `project` allocate nothing.

pub mod eigen_svd;
pub mod error;
pub mod ritz_check;
pub mod small_jacobi;

mod lanczos;
mod ritz;

pub use error::TruncatedError;

use super::hankel_op::HankelOp;
use super::kernels::dot;
use super::Triplets;
use crate::hankel::{Hankel, HankelDims};
use eigen_svd::EigenSvd;
use ritz_check::RitzCheck;
use small_jacobi::SmallJacobi;

/// Default acceptance threshold for the residual `‖Hᵀu − σv‖ / σ₁` of every requested triplet.
pub const DEFAULT_TOLERANCE: f64 = 1e-12;

/// In [`TruncatedSvd::compute_at_least`], Ritz values past the converged ones count as
/// settled when none moved by more than this fraction of `σ₁` between two checks: enough to
/// place them against a noise floor (order choice), far from converged vectors.
pub const RITZ_STABLE: f64 = 1e-3;

/// The default step budget for `max_k` requested triplets: `max(4 max_k, max_k + 30)`.
pub fn default_max_steps(max_k: usize) -> usize {
    (4 * max_k).max(max_k + 30)
}

/// Truncated SVD of block Hankel matrices; see the module documentation.
#[derive(Debug)]
pub struct TruncatedSvd {
    op: HankelOp,
    max_q: usize,
    max_p: usize,
    max_k: usize,
    max_steps: usize,
    tolerance: f64,
    /// Left basis `U`, column-major, `max_rows × max_steps`, column stride `row_stride`.
    ub: Vec<f64>,
    /// Right basis `V`, column-major, `max_cols × (max_steps + 1)`.
    vb: Vec<f64>,
    row_stride: usize,
    col_stride: usize,
    alpha: Vec<f64>,
    beta: Vec<f64>,
    coef: Vec<f64>,
    small: SmallJacobi,
    cheap: RitzCheck,
    /// The final small SVD when signs are free ([`set_sign_free`](Self::set_sign_free)).
    eig: EigenSvd,
    sign_free: bool,
    /// Whether the last stopping check's triplets come from `eig` (else from `small`).
    from_eig: bool,
    /// Scratch for one right Ritz vector of `B_m` (`max_steps`).
    qbuf: Vec<f64>,
    residuals: Vec<f64>,
    /// Last components of the leading left Ritz vectors (`max_k`).
    last: Vec<f64>,
    ritz: Vec<f64>,
    n_ritz: usize,
    ritz_prev: Vec<f64>,
    n_prev: usize,
    steps: usize,
    /// Scratch of length `max_rows` for [`project`](Self::project).
    tmp_rows: Vec<f64>,
    rng: u64,
}

impl TruncatedSvd {
    /// Allocates everything for Hankel matrices of up to `max_block_rows × max_block_cols`
    /// blocks of `q × p` (at most), and up to `max_k` triplets, with the default step budget
    /// [`default_max_steps`].
    pub fn new(
        max_block_rows: usize,
        max_block_cols: usize,
        q: usize,
        p: usize,
        max_k: usize,
    ) -> Self {
        Self::with_max_steps(
            max_block_rows,
            max_block_cols,
            q,
            p,
            max_k,
            default_max_steps(max_k.max(1)),
        )
    }

    /// As [`new`](Self::new) with an explicit Lanczos step budget (memory grows with it).
    pub fn with_max_steps(
        max_block_rows: usize,
        max_block_cols: usize,
        q: usize,
        p: usize,
        max_k: usize,
        max_steps: usize,
    ) -> Self {
        let op = HankelOp::new(max_block_rows, max_block_cols, q, p);
        let (max_q, max_p) = (q.max(1), p.max(1));
        let max_k = max_k.max(1);
        let row_stride = op.max_block_rows() * max_q;
        let col_stride = op.max_block_cols() * max_p;
        let max_steps = max_steps.max(max_k).min(row_stride.min(col_stride));
        let max_k = max_k.min(max_steps);
        TruncatedSvd {
            op,
            max_q,
            max_p,
            max_k,
            max_steps,
            tolerance: DEFAULT_TOLERANCE,
            ub: vec![0.0; row_stride * max_steps],
            vb: vec![0.0; col_stride * (max_steps + 1)],
            row_stride,
            col_stride,
            alpha: vec![0.0; max_steps],
            beta: vec![0.0; max_steps],
            coef: vec![0.0; max_steps + 1],
            small: SmallJacobi::new(max_steps),
            cheap: RitzCheck::new(max_steps),
            eig: EigenSvd::new(max_steps),
            sign_free: false,
            from_eig: false,
            qbuf: vec![0.0; max_steps],
            residuals: vec![0.0; max_k],
            last: vec![0.0; max_k],
            ritz: vec![0.0; max_steps],
            n_ritz: 0,
            ritz_prev: vec![0.0; max_steps],
            n_prev: 0,
            steps: 0,
            tmp_rows: vec![0.0; row_stride],
            rng: 0,
        }
    }

    /// Sets the acceptance threshold for `‖Hᵀu − σv‖ / σ₁` (positive and finite; otherwise the
    /// current value is kept and `false` returned).
    pub fn set_tolerance(&mut self, tolerance: f64) -> bool {
        if tolerance.is_finite() && tolerance > 0.0 {
            self.tolerance = tolerance;
            true
        } else {
            false
        }
    }

    /// The acceptance threshold in use.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// With `true`, the stopping check decomposes the Lanczos bidiagonal through the eigenvectors
    /// of `B Bᵀ` ([`eigen_svd`], several times faster than the Jacobi SVD) whenever the
    /// requested singular values are at least [`eigen_svd::MIN_RATIO`]` · σ₁`: values and
    /// subspaces agree with the Jacobi ones to rounding, but the sign of each triplet
    /// `(u_i, v_i)` is arbitrary. For callers that use only sign-invariant results (poles, DC
    /// gains: the jackknife). Default `false`: Jacobi, whose signs are reproducible.
    pub fn set_sign_free(&mut self, sign_free: bool) {
        self.sign_free = sign_free;
    }

    /// Largest number of triplets `compute` accepts.
    pub fn max_k(&self) -> usize {
        self.max_k
    }

    /// Lanczos step budget.
    pub fn max_steps(&self) -> usize {
        self.max_steps
    }

    /// Lanczos steps taken by the last `compute`.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Relative residuals `‖Hᵀu_i − σ_i v_i‖ / σ₁` of the triplets of the last `compute`
    /// (also after a [`TruncatedError::NotConverged`]).
    pub fn residuals(&self) -> &[f64] {
        &self.residuals[..self.residuals.len().min(self.last_k())]
    }

    /// All Ritz values of the last `compute` (descending): the leading ones are the converged
    /// singular values, the rest lower estimates of the following singular values.
    pub fn ritz_values(&self) -> &[f64] {
        &self.ritz[..self.n_ritz]
    }

    fn last_k(&self) -> usize {
        self.n_ritz.min(self.max_k)
    }

    /// The leading `k` singular triplets of `H(shift)` ([`Hankel`]: `r × c` blocks of `q × p`
    /// from `markov`, layout in `docs/ARCHITECTURE.md`) into `out`: `sigma[..k]` descending, `u`
    /// (`r q × k`, column-major), `v` (`c p × k`, column-major), every triplet converged to
    /// [`tolerance`](Self::tolerance). Allocates nothing.
    pub fn compute(
        &mut self,
        h: Hankel<'_>,
        k: usize,
        out: Triplets<'_>,
    ) -> Result<(), TruncatedError> {
        self.compute_at_least(h, k, k, out).map(|_| ())
    }

    /// As [`compute`](Self::compute), but requires only the leading `need ≤ k` triplets to
    /// converge: it stops when all `k` have converged, or when the leading `need` have and
    /// the `k` leading Ritz values have settled (moved by at most [`RITZ_STABLE`]` · σ₁`
    /// between two checks), or at the step budget; it fails only if fewer than `need`
    /// converged. Returns how many leading triplets converged (`need ..= k`). Triplets past
    /// that count are Ritz approximations (lower estimates of the singular values; residuals
    /// in [`residuals`](Self::residuals)): for ERA this gives the order-`n` factors to full
    /// accuracy plus estimates of the following singular values for the order choice, without
    /// iterating into the noise cluster. Allocates nothing.
    pub fn compute_at_least(
        &mut self,
        h: Hankel<'_>,
        k: usize,
        need: usize,
        out: Triplets<'_>,
    ) -> Result<usize, TruncatedError> {
        let Hankel {
            markov,
            dims: HankelDims { q, p, r, c },
            shift,
        } = h;
        let Triplets { sigma, u, v } = out;
        self.steps = 0;
        self.n_ritz = 0;
        self.op.prepare(h)?;
        let (rows, cols) = (r * q, c * p);
        if k == 0 || k > self.max_k {
            return Err(TruncatedError::Dimension {
                what: "k",
                got: k,
                max: self.max_k,
            });
        }
        if need == 0 || need > k {
            return Err(TruncatedError::Dimension {
                what: "need",
                got: need,
                max: k,
            });
        }
        if k > rows.min(cols) {
            return Err(TruncatedError::TooManyTriplets { k, rows, cols });
        }
        check_len("sigma", sigma.len(), k)?;
        check_len("u", u.len(), rows * k)?;
        check_len("v", v.len(), cols * k)?;
        let first = (1 + shift) * q * p;
        let last = (r + c + shift) * q * p;
        if markov[first..last].iter().all(|&x| x == 0.0) {
            return Err(TruncatedError::ZeroMatrix);
        }
        self.rng = 0x9E37_79B9_7F4A_7C15;
        self.lanczos(rows, cols, k, need)?;
        let converged = self.converged(k);
        if converged < need {
            return Err(TruncatedError::NotConverged {
                k: need,
                converged,
                steps: self.steps,
                residual: self.residuals[..need]
                    .iter()
                    .fold(0.0, |a: f64, &b| a.max(b)),
                tolerance: self.tolerance,
            });
        }
        self.write_triplets(rows, cols, k, sigma, u, v);
        Ok(converged)
    }

    /// `y = H(shift) x` (agreed API; allocation-free).
    pub fn apply(&mut self, h: Hankel<'_>, x: &[f64], y: &mut [f64]) -> Result<(), TruncatedError> {
        self.op.apply(h, x, y)
    }

    /// `y = H(shift)ᵀ x` (agreed API; allocation-free).
    pub fn apply_t(
        &mut self,
        h: Hankel<'_>,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), TruncatedError> {
        self.op.apply_t(h, x, y)
    }

    /// `out = Uᵀ H(shift) V` (`k × k`, column-major) for `u` (`r q × k`) and `v` (`c p × k`),
    /// column-major: what ERA needs from `H(1)`. One spectrum computation and `k` products.
    pub fn project(
        &mut self,
        h: Hankel<'_>,
        k: usize,
        u: &[f64],
        v: &[f64],
        out: &mut [f64],
    ) -> Result<(), TruncatedError> {
        self.op.prepare(h)?;
        let (rows, cols) = (h.dims.rows(), h.dims.cols());
        check_len("u", u.len(), rows * k)?;
        check_len("v", v.len(), cols * k)?;
        check_len("out", out.len(), k * k)?;
        for b in 0..k {
            let hv = &mut self.tmp_rows[..rows];
            self.op.apply_prepared(&v[b * cols..(b + 1) * cols], hv)?;
            for a in 0..k {
                out[a + b * k] = dot(&u[a * rows..(a + 1) * rows], hv);
            }
        }
        Ok(())
    }

    /// Largest `q` and `p` accepted.
    pub fn max_channels(&self) -> (usize, usize) {
        (self.max_q, self.max_p)
    }
}

fn check_len(what: &'static str, got: usize, expected: usize) -> Result<(), TruncatedError> {
    if got < expected {
        return Err(TruncatedError::SliceLength {
            what,
            got,
            expected,
        });
    }
    Ok(())
}
