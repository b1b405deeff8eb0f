//! SVD of the Lanczos bidiagonal through the eigen-decomposition of `B Bᵀ`: the fast final
//! small SVD for callers that use only sign-invariant results (the jackknife's
//! re-identifications: poles and DC gains do not depend on the signs of singular vectors).
//!
//! The eigenvectors of the tridiagonal `T = B Bᵀ` ([`super::ritz_check`] gives its entries) by
//! the implicit QL iteration with the full rotation product (EISPACK `tql2`, about `6 m³` flops
//! against `~9 m³` per sweep of the one-sided Jacobi SVD, which needs 6–10 sweeps) are the left
//! singular vectors `p_i`, its eigenvalues `σ_i²`; the right vectors follow from
//! `Bᵀ p_i = σ_i q_i` at `O(m)` each.
//!
//! Accuracy (Golub & Van Loan, *Matrix Computations* 4th ed., §8.1 and §8.6): `σ_i²` carries an
//! absolute error of a few `ε σ₁²`, so `σ_i` a relative error of a few `ε (σ₁/σ_i)²`; `p_i` an
//! error of a few `ε σ₁² / gap_i` (`gap_i` the distance from `σ_i²` to the other eigenvalues);
//! `q_i` in addition `ε σ₁ / σ_i`. Unlike Jacobi's, the signs of `(p_i, q_i)` are arbitrary
//! (consistent within a triplet). [`EigenSvd::compute`] therefore refuses (and the caller falls
//! back to Jacobi) when a requested singular value is below [`MIN_RATIO`]` · σ₁`: above it the
//! relative error of every value is below ~`1e-10` and far smaller for the leading ones.

use super::ritz_check::{bbt_tridiagonal, ql_implicit};

/// Smallest `σ_i / σ₁` for which the squared form is accurate enough (see the module docs).
pub const MIN_RATIO: f64 = 1e-3;

/// Workspace for bidiagonals of order up to `max_n`.
#[derive(Debug, Clone)]
pub struct EigenSvd {
    n: usize,
    scale: f64,
    d: Vec<f64>,
    e: Vec<f64>,
    /// Eigenvectors of `T`, column-major `n × n` (column `j` for eigenvalue `d[j]`).
    z: Vec<f64>,
    order: Vec<usize>,
    /// The loaded bidiagonal (unscaled), for `q_i = Bᵀ p_i / σ_i`.
    diag: Vec<f64>,
    sup: Vec<f64>,
}

impl EigenSvd {
    /// Allocates for bidiagonals of order up to `max_n`.
    pub fn new(max_n: usize) -> Self {
        let max_n = max_n.max(1);
        EigenSvd {
            n: 0,
            scale: 1.0,
            d: vec![0.0; max_n],
            e: vec![0.0; max_n],
            z: vec![0.0; max_n * max_n],
            order: vec![0; max_n],
            diag: vec![0.0; max_n],
            sup: vec![0.0; max_n],
        }
    }

    /// Decomposes the `n × n` upper bidiagonal (`diag[..n]`, `sup[..n-1]`). Returns `false` if
    /// the sizes do not fit, a value is not finite, the iteration fails, or `σ_need < MIN_RATIO
    /// σ₁` (`need` ≥ 1 leading values requested; the caller then uses the Jacobi SVD).
    pub fn compute(&mut self, diag: &[f64], sup: &[f64], need: usize) -> bool {
        let n = diag.len();
        if n == 0 || n > self.d.len() || sup.len() + 1 < n || need == 0 || need > n {
            return false;
        }
        self.n = n;
        self.diag[..n].copy_from_slice(diag);
        self.sup[..n - 1].copy_from_slice(&sup[..n - 1]);
        let scale = diag
            .iter()
            .chain(&sup[..n - 1])
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if !(scale.is_finite() && scale > 0.0) {
            return false;
        }
        self.scale = scale;
        let inv = 1.0 / scale;
        bbt_tridiagonal(diag, sup, inv, &mut self.d[..n], &mut self.e[..n]);
        let z = &mut self.z[..n * n];
        z.fill(0.0);
        for i in 0..n {
            z[i + i * n] = 1.0;
        }
        if !ql_implicit(&mut self.d[..n], &mut self.e[..n], z, n) {
            return false;
        }
        let order = &mut self.order[..n];
        for (i, o) in order.iter_mut().enumerate() {
            *o = i;
        }
        let d = &self.d;
        order.sort_unstable_by(|&a, &b| d[b].total_cmp(&d[a]));
        let (l1, ln) = (self.d[self.order[0]], self.d[self.order[need - 1]]);
        l1 > 0.0 && ln >= MIN_RATIO * MIN_RATIO * l1
    }

    /// Order of the last decomposed bidiagonal.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Singular value `i` (descending).
    pub fn sigma(&self, i: usize) -> f64 {
        self.d[self.order[i]].max(0.0).sqrt() * self.scale
    }

    /// Left singular vector `i` (descending order).
    pub fn left(&self, i: usize) -> &[f64] {
        let j = self.order[i];
        &self.z[j * self.n..(j + 1) * self.n]
    }

    /// Right singular vector `i` into `q[..n]`: `q = Bᵀ p_i / σ_i` (zero if `σ_i = 0`).
    pub fn right_into(&self, i: usize, q: &mut [f64]) {
        let n = self.n;
        let p = self.left(i);
        let s = self.sigma(i);
        let inv = if s > 0.0 { 1.0 / s } else { 0.0 };
        for j in 0..n {
            // (Bᵀ p)_j = α_j p_j + β_{j−1} p_{j−1}
            let mut v = self.diag[j] * p[j];
            if j > 0 {
                v += self.sup[j - 1] * p[j - 1];
            }
            q[j] = v * inv;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::small_jacobi::SmallJacobi;
    use super::*;

    #[test]
    fn matches_the_jacobi_svd_up_to_signs() {
        let n = 30;
        let diag: Vec<f64> = (0..n)
            .map(|i| {
                if i < 3 {
                    10.0 / (i + 1) as f64
                } else {
                    0.3 + 0.02 * ((i * 7 % 11) as f64)
                }
            })
            .collect();
        let sup: Vec<f64> = (0..n - 1)
            .map(|i| {
                if i < 3 {
                    0.5
                } else {
                    0.05 * ((i * 5 % 13) as f64)
                }
            })
            .collect();
        let mut jac = SmallJacobi::new(n);
        assert!(jac.load_bidiagonal(&diag, &sup) && jac.decompose());
        let mut eig = EigenSvd::new(n);
        assert!(eig.compute(&diag, &sup, 4));
        assert_eq!(eig.n(), n);
        let s1 = jac.sigma()[0];
        let mut q = vec![0.0; n];
        for i in 0..4 {
            let (a, b) = (eig.sigma(i), jac.sigma()[i]);
            assert!((a - b).abs() <= 1e-13 * s1, "sigma {i}: {a} vs {b}");
            let p = eig.left(i);
            let sign = p
                .iter()
                .zip(jac.left(i))
                .map(|(x, y)| x * y)
                .sum::<f64>()
                .signum();
            for (x, y) in p.iter().zip(jac.left(i)) {
                assert!((sign * x - y).abs() < 1e-12, "left {i}");
            }
            eig.right_into(i, &mut q);
            for (x, y) in q.iter().zip(jac.right(i)) {
                assert!((sign * x - y).abs() < 1e-12, "right {i}");
            }
        }
    }

    #[test]
    fn refuses_small_requested_values_and_bad_input() {
        // σ = 1 and 1e-5: the second is below MIN_RATIO.
        let mut eig = EigenSvd::new(4);
        assert!(eig.compute(&[1.0, 1e-5], &[0.0], 1));
        assert!(!eig.compute(&[1.0, 1e-5], &[0.0], 2));
        assert!(!eig.compute(&[0.0, 0.0], &[0.0], 1));
        assert!(!eig.compute(&[1.0, f64::NAN], &[0.0], 1));
        assert!(!eig.compute(&[1.0; 5], &[0.0; 4], 1));
    }
}
