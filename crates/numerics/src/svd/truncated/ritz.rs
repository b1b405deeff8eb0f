//! When the Lanczos iteration of [`TruncatedSvd`] stops, and the Ritz triplets it hands out.
//!
//! With `B_m = P Σ Qᵀ` (the small SVD of the bidiagonal) the Ritz triplets
//! `(σ_i, U_m p_i, V_m q_i)` satisfy `H v = σ u` exactly and
//! `‖Hᵀ u_i − σ_i v_i‖ = β_m |e_mᵀ p_i|`: the residual test against `tol · σ₁`.

use super::lanczos::axpy;
use super::{TruncatedError, TruncatedSvd, RITZ_STABLE};

impl TruncatedSvd {
    /// Number of leading triplets (of `k`) whose residual passes the tolerance.
    pub(super) fn converged(&self, k: usize) -> usize {
        self.residuals[..k]
            .iter()
            .take_while(|&&res| res <= self.tolerance)
            .count()
    }

    /// Convergence check at `m` steps: `true` when the leading `k` Ritz triplets pass the
    /// residual test, or when the leading `need < k` pass and the leading `k` Ritz values
    /// moved by at most [`RITZ_STABLE`]` · σ₁` since the previous check. The test runs first on
    /// the `O(m²)` values and last components of [`RitzCheck`]; only a check that stops the
    /// iteration (it passes, or `last`: the step budget is spent) runs the `O(m³)` Jacobi SVD
    /// whose triplets are handed out, and decides again on its values.
    pub(super) fn check(
        &mut self,
        k: usize,
        need: usize,
        last: bool,
    ) -> Result<bool, TruncatedError> {
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
    pub(super) fn write_triplets(
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
}
