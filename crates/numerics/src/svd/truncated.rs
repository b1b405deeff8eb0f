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

pub use error::TruncatedError;

use super::hankel_op::HankelOp;
use super::kernels::dot;
use super::Triplets;
use crate::hankel::{Hankel, HankelDims};
use eigen_svd::EigenSvd;
use ritz_check::RitzCheck;
use small_jacobi::SmallJacobi;

/// Kahan's criterion for a second Gram–Schmidt pass (see `reorthonormalise`).
const KAHAN_KAPPA: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Default acceptance threshold for the residual `‖Hᵀu − σv‖ / σ₁` of every requested triplet.
pub const DEFAULT_TOLERANCE: f64 = 1e-12;

/// A Lanczos coefficient at or below this fraction of the largest coefficient seen so far
/// is a breakdown (rounding-level: the Krylov space is invariant).
const BREAKDOWN: f64 = 1e-13;

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

    /// Number of leading triplets (of `k`) whose residual passes the tolerance.
    fn converged(&self, k: usize) -> usize {
        self.residuals[..k]
            .iter()
            .take_while(|&&res| res <= self.tolerance)
            .count()
    }

    /// The Lanczos iteration proper: runs until the leading `k` Ritz triplets converge (or,
    /// with `need < k`, the leading `need` converged and the `k` leading Ritz values are
    /// stable, see [`RITZ_STABLE`]), or the step budget is spent; either way the small SVD of
    /// the last check (and `residuals`) hold the Ritz triplets. Checks (a small SVD each) come
    /// at `k + 2` steps and then every half as many steps again as taken so far.
    fn lanczos(
        &mut self,
        rows: usize,
        cols: usize,
        k: usize,
        need: usize,
    ) -> Result<(), TruncatedError> {
        let m_max = self.max_steps.min(rows.min(cols));
        let (rs, cs) = (self.row_stride, self.col_stride);
        self.random_unit(false, 0, cols);
        let mut norm_est = 0.0f64;
        let mut next_check = (k + 2).min(m_max);
        self.n_prev = 0;
        for j in 0..m_max {
            // α_j u_j = H v_j − β_{j−1} u_{j−1}
            {
                let (vj, uj) = (
                    &self.vb[j * cs..j * cs + cols],
                    &mut self.ub[j * rs..j * rs + rows],
                );
                self.op.apply_prepared(vj, uj)?;
            }
            if j > 0 {
                let b = self.beta[j - 1];
                let (prev, cur) = self.ub.split_at_mut(j * rs);
                axpy(
                    -b,
                    &prev[(j - 1) * rs..(j - 1) * rs + rows],
                    &mut cur[..rows],
                );
            }
            let a = self.reorthonormalise(true, j, rows);
            norm_est = norm_est.max(a);
            self.alpha[j] = if a > BREAKDOWN * norm_est {
                a
            } else {
                self.random_unit(true, j, rows);
                0.0
            };
            // β_j v_{j+1} = Hᵀ u_j − α_j v_j
            {
                let (uj, rest) = (&self.ub[j * rs..j * rs + rows], &mut self.vb[..]);
                let (done, next) = rest.split_at_mut((j + 1) * cs);
                self.op.apply_t_prepared(uj, &mut next[..cols])?;
                axpy(
                    -self.alpha[j],
                    &done[j * cs..j * cs + cols],
                    &mut next[..cols],
                );
            }
            let invariant = j + 1 >= cols;
            let b = if invariant {
                0.0
            } else {
                self.reorthonormalise(false, j + 1, cols)
            };
            norm_est = norm_est.max(b);
            let breakdown = invariant || b <= BREAKDOWN * norm_est;
            self.beta[j] = if breakdown { 0.0 } else { b };
            if breakdown && !invariant {
                self.random_unit(false, j + 1, cols);
            }
            self.steps = j + 1;
            let last = self.steps == m_max;
            if self.steps >= k && (self.steps >= next_check || breakdown || last) {
                if self.check(k, need, last)? {
                    return Ok(());
                }
                next_check = self.steps + (self.steps / 2).max(2);
            }
        }
        // The budget is spent; the last check (forced at `m_max`) holds the Ritz triplets.
        Ok(())
    }

    /// Convergence check at `m` steps: `true` when the leading `k` Ritz triplets pass the
    /// residual test, or when the leading `need < k` pass and the leading `k` Ritz values
    /// moved by at most [`RITZ_STABLE`]` · σ₁` since the previous check. The test runs first on
    /// the `O(m²)` values and last components of [`RitzCheck`]; only a check that stops the
    /// iteration (it passes, or `last`: the step budget is spent) runs the `O(m³)` Jacobi SVD
    /// whose triplets are handed out, and decides again on its values.
    fn check(&mut self, k: usize, need: usize, last: bool) -> Result<bool, TruncatedError> {
        let m = self.steps;
        let n_prev = self.n_ritz;
        self.ritz_prev[..n_prev].copy_from_slice(&self.ritz[..n_prev]);
        self.n_prev = n_prev;
        if !last {
            if !self.cheap.compute(&self.alpha[..m], &self.beta[..m]) {
                return Err(self.failed(k));
            }
            for i in 0..m {
                self.ritz[i] = self.cheap.sigma(i);
            }
            for i in 0..k {
                self.last[i] = self.cheap.last(i);
            }
            if !self.decide(k, need)? {
                return Ok(false);
            }
        }
        self.from_eig = self.sign_free && self.eig.compute(&self.alpha[..m], &self.beta[..m], need);
        if self.from_eig {
            for i in 0..m {
                self.ritz[i] = self.eig.sigma(i);
            }
            for i in 0..k {
                self.last[i] = self.eig.left(i)[m - 1];
            }
            return self.decide(k, need);
        }
        if !self
            .small
            .load_bidiagonal(&self.alpha[..m], &self.beta[..m])
            || !self.small.decompose_leading(k)
        {
            return Err(self.failed(k));
        }
        self.ritz[..m].copy_from_slice(self.small.sigma());
        for i in 0..k {
            self.last[i] = self.small.left(i)[m - 1];
        }
        self.decide(k, need)
    }

    /// From the Ritz values in `ritz[..m]` and the last components `last[..k]` of the leading
    /// left vectors: the residuals `β_m |last_i| / σ₁`, and the stopping rule of
    /// [`check`](Self::check).
    fn decide(&mut self, k: usize, need: usize) -> Result<bool, TruncatedError> {
        let m = self.steps;
        self.n_ritz = m;
        let s1 = self.ritz[0];
        if s1 <= 0.0 {
            return Err(TruncatedError::ZeroMatrix);
        }
        let beta_m = self.beta[m - 1];
        for i in 0..k {
            self.residuals[i] = (beta_m * self.last[i]).abs() / s1;
        }
        let converged = self.converged(k);
        if converged == k {
            return Ok(true);
        }
        let stable = self.n_prev >= k
            && (0..k).all(|i| (self.ritz[i] - self.ritz_prev[i]).abs() <= RITZ_STABLE * s1);
        Ok(need < k && converged >= need && stable)
    }

    fn failed(&self, k: usize) -> TruncatedError {
        TruncatedError::NotConverged {
            k,
            converged: 0,
            steps: self.steps,
            residual: f64::INFINITY,
            tolerance: self.tolerance,
        }
    }

    /// `u_i = U_m p_i`, `v_i = V_m q_i` for the leading `k` Ritz triplets of the last check.
    fn write_triplets(
        &mut self,
        rows: usize,
        cols: usize,
        k: usize,
        sigma: &mut [f64],
        u: &mut [f64],
        v: &mut [f64],
    ) {
        let m = self.steps;
        sigma[..k].copy_from_slice(&self.ritz[..k]);
        for i in 0..k {
            let p = if self.from_eig {
                self.eig.left(i)
            } else {
                self.small.left(i)
            };
            let ui = &mut u[i * rows..(i + 1) * rows];
            ui.fill(0.0);
            for (l, &w) in p.iter().enumerate().take(m) {
                axpy(
                    w,
                    &self.ub[l * self.row_stride..l * self.row_stride + rows],
                    ui,
                );
            }
            let qv = if self.from_eig {
                self.eig.right_into(i, &mut self.qbuf[..m]);
                &self.qbuf[..m]
            } else {
                self.small.right(i)
            };
            let vi = &mut v[i * cols..(i + 1) * cols];
            vi.fill(0.0);
            for (l, &w) in qv.iter().enumerate().take(m) {
                axpy(
                    w,
                    &self.vb[l * self.col_stride..l * self.col_stride + cols],
                    vi,
                );
            }
        }
    }

    /// Orthogonalises basis vector `idx` (of `U` if `left`, else `V`) against vectors
    /// `0..idx` by classical Gram–Schmidt, normalises it if nonzero and returns its norm
    /// before normalisation. The second pass runs only when the first removed more than a
    /// fraction of the norm (`‖w'‖ < κ ‖w‖`, [`KAHAN_KAPPA`]): otherwise `w'` is already
    /// orthogonal to working precision (Kahan's "twice is enough" criterion, Parlett, *The
    /// Symmetric Eigenvalue Problem*, §6.9; Giraud, Langou & Rozložník 2005). In Lanczos the
    /// recurrence has removed the large components already, so one pass usually suffices.
    fn reorthonormalise(&mut self, left: bool, idx: usize, len: usize) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor supports AVX2 (checked just above).
            return unsafe { self.reorthonormalise_avx2(left, idx, len) };
        }
        self.reorthonormalise_body(left, idx, len)
    }

    /// [`reorthonormalise`](Self::reorthonormalise) compiled with AVX2: the same operations
    /// in the same order on wider registers, so the same bits (see [`super::kernels`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn reorthonormalise_avx2(&mut self, left: bool, idx: usize, len: usize) -> f64 {
        self.reorthonormalise_body(left, idx, len)
    }

    #[inline(always)]
    fn reorthonormalise_body(&mut self, left: bool, idx: usize, len: usize) -> f64 {
        let (basis, stride) = if left {
            (&mut self.ub, self.row_stride)
        } else {
            (&mut self.vb, self.col_stride)
        };
        let (prev, cur) = basis.split_at_mut(idx * stride);
        let w = &mut cur[..len];
        let mut norm = dot(w, w).sqrt();
        for _ in 0..2 {
            for (l, c) in self.coef[..idx].iter_mut().enumerate() {
                *c = dot(&prev[l * stride..l * stride + len], w);
            }
            for (l, &c) in self.coef[..idx].iter().enumerate() {
                axpy(-c, &prev[l * stride..l * stride + len], w);
            }
            let before = norm;
            norm = dot(w, w).sqrt();
            if norm >= KAHAN_KAPPA * before {
                break;
            }
        }
        if norm > 0.0 {
            w.iter_mut().for_each(|x| *x /= norm);
        }
        norm
    }

    /// Fills basis vector `idx` with a pseudo-random unit vector orthogonal to `0..idx`.
    fn random_unit(&mut self, left: bool, idx: usize, len: usize) {
        for _ in 0..4 {
            let stride = if left {
                self.row_stride
            } else {
                self.col_stride
            };
            for i in 0..len {
                let x = next_uniform(&mut self.rng);
                if left {
                    self.ub[idx * stride + i] = x;
                } else {
                    self.vb[idx * stride + i] = x;
                }
            }
            // Start vectors of dimension > idx always keep a component outside the basis.
            if self.reorthonormalise(left, idx, len) > 1e-3 {
                return;
            }
        }
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

/// `y += a x`.
#[inline(always)]
fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// Uniform in `[-0.5, 0.5)` from a SplitMix64 state (deterministic, allocation-free).
fn next_uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}
