//! The Golub–Kahan–Lanczos recurrence of [`TruncatedSvd`] (Golub & Van Loan, *Matrix
//! Computations* 4th ed., alg. 10.4.1): from a unit start vector `v₁`,
//!
//! $$\alpha_j u_j = H v_j - \beta_{j-1} u_{j-1}, \qquad
//!   \beta_j v_{j+1} = H^T u_j - \alpha_j v_j ,$$
//!
//! each new vector reorthogonalised against all previous ones (classical Gram–Schmidt, a
//! second pass only when Kahan's criterion asks for it), breakdowns continued with a fresh
//! pseudo-random vector orthogonal to the basis.

use super::{TruncatedError, TruncatedSvd};
use crate::svd::kernels::dot;

/// Kahan's criterion for a second Gram–Schmidt pass (see `reorthonormalise`).
const KAHAN_KAPPA: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// A Lanczos coefficient at or below this fraction of the largest coefficient seen so far
/// is a breakdown (rounding-level: the Krylov space is invariant).
const BREAKDOWN: f64 = 1e-13;

impl TruncatedSvd {
    /// The Lanczos iteration proper: runs until the leading `k` Ritz triplets converge (or,
    /// with `need < k`, the leading `need` converged and the `k` leading Ritz values are
    /// stable, see [`super::RITZ_STABLE`]), or the step budget is spent; either way the small SVD of
    /// the last check (and `residuals`) hold the Ritz triplets. Checks (a small SVD each) come
    /// at `k + 2` steps and then every half as many steps again as taken so far.
    pub(super) fn lanczos(
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
}

/// `y += a x`.
#[inline(always)]
pub(super) fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
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
