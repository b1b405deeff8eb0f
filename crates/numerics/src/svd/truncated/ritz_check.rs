//! Cheap Ritz values and convergence residuals of the Lanczos bidiagonal, for the intermediate
//! convergence checks of [`super::TruncatedSvd`] (the accepted triplets still come from the
//! one-sided Jacobi SVD, [`super::small_jacobi`]).
//!
//! A check needs, of the `m × m` upper bidiagonal `B` (diagonal `α`, superdiagonal `β`), only
//! the singular values `σ_i` and the *last* component of each left singular vector `p_i`: the
//! residual of Ritz triplet `i` is `β_m |e_mᵀ p_i|`. The `p_i` are the eigenvectors of the
//! symmetric tridiagonal `T = B Bᵀ`,
//!
//! $$T_{ii} = \alpha_i^2 + \beta_i^2 \;(i < m),\quad T_{mm} = \alpha_m^2,\quad
//!   T_{i,i+1} = \beta_i\,\alpha_{i+1},$$
//!
//! whose eigenvalues are `σ_i²`. The implicit QL iteration with Wilkinson shifts (EISPACK
//! `tql2`; Bowdler, Martin, Reinsch & Wilkinson 1968, *Numer. Math.* 11, 293–306) diagonalises
//! `T` by plane rotations `Z = G_1 G_2 ⋯`; the eigenvectors are the columns of `Z`, and, as
//! Golub & Welsch (1969, *Math. Comp.* 23, 221–230) do for the first components in Gauss
//! quadrature, applying the rotations to the last row of `Z` only yields every eigenvector's
//! last component at `O(m)` cost per rotation: `O(m²)` in all, against `O(m³)` per Jacobi sweep.
//!
//! Accuracy: the eigenvalues of `T` carry an absolute error of a few `ε ‖T‖ = ε σ₁²` and the
//! last components an absolute error of a few `ε` (orthogonal rotations), so each residual
//! relative to `σ₁` is within ~`1e-15` of the Jacobi one: the convergence decisions (threshold
//! `1e-12`) and the Ritz-value stability test (threshold `1e-3 σ₁`) are the same as with the
//! Jacobi SVD except within rounding of a threshold. Small singular values lose relative
//! accuracy through the squaring (`δσ ≈ ε σ₁² / σ`), which is why the values handed out as
//! results are always the Jacobi ones.

/// Largest number of QL iterations per eigenvalue (EISPACK uses 30; never reached here).
const MAX_ITER: usize = 60;

/// Workspace for [`RitzCheck::compute`] on bidiagonals of order up to `max_n`.
#[derive(Debug, Clone)]
pub struct RitzCheck {
    n: usize,
    /// Diagonal of `T`, then its eigenvalues (unsorted).
    d: Vec<f64>,
    /// Off-diagonal of `T` (`e[i] = T[i, i+1]`, `e[n-1] = 0`).
    e: Vec<f64>,
    /// Last row of the eigenvector matrix `Z`.
    z: Vec<f64>,
    /// Permutation sorting the eigenvalues descending.
    order: Vec<usize>,
}

impl RitzCheck {
    /// Allocates for bidiagonals of order up to `max_n`.
    pub fn new(max_n: usize) -> Self {
        let max_n = max_n.max(1);
        RitzCheck {
            n: 0,
            d: vec![0.0; max_n],
            e: vec![0.0; max_n],
            z: vec![0.0; max_n],
            order: vec![0; max_n],
        }
    }

    /// Singular values and last left-vector components of the `n × n` upper bidiagonal with
    /// diagonal `diag[..n]` and superdiagonal `sup[..n-1]`. Returns `false` if `n` is zero or
    /// exceeds the capacity, a value is not finite, or the iteration does not converge.
    pub fn compute(&mut self, diag: &[f64], sup: &[f64]) -> bool {
        let n = diag.len();
        if n == 0 || n > self.d.len() || sup.len() + 1 < n {
            return false;
        }
        self.n = n;
        // Scale to unit largest coefficient: the squares neither overflow nor underflow.
        let scale = diag
            .iter()
            .chain(&sup[..n - 1])
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if !scale.is_finite() {
            return false;
        }
        let inv = if scale > 0.0 { 1.0 / scale } else { 1.0 };
        bbt_tridiagonal(diag, sup, inv, &mut self.d[..n], &mut self.e[..n]);
        self.z[..n].fill(0.0);
        self.z[n - 1] = 1.0;
        if !ql_implicit(&mut self.d[..n], &mut self.e[..n], &mut self.z[..n], 1) {
            return false;
        }
        for v in &mut self.d[..n] {
            *v = v.max(0.0).sqrt() * scale;
        }
        let order = &mut self.order[..n];
        for (i, o) in order.iter_mut().enumerate() {
            *o = i;
        }
        let d = &self.d;
        order.sort_unstable_by(|&a, &b| d[b].total_cmp(&d[a]));
        true
    }

    /// Singular value `i` (descending) of the last computed bidiagonal.
    pub fn sigma(&self, i: usize) -> f64 {
        self.d[self.order[i]]
    }

    /// Last component of left singular vector `i` (descending order; sign arbitrary).
    pub fn last(&self, i: usize) -> f64 {
        self.z[self.order[i]]
    }

    /// Order of the last computed bidiagonal.
    pub fn n(&self) -> usize {
        self.n
    }
}

/// The symmetric tridiagonal `B Bᵀ / scale²` of the upper bidiagonal `B` (`diag[..n]`,
/// `sup[..n-1]`), `inv = 1 / scale`: diagonal `d_i = a_i² + b_i²`, off-diagonal
/// `e_i = b_i a_{i+1}` (`a = diag · inv`, `b = sup · inv`, `b_{n-1} = 0`, `e_{n-1} = 0`).
pub(crate) fn bbt_tridiagonal(diag: &[f64], sup: &[f64], inv: f64, d: &mut [f64], e: &mut [f64]) {
    let n = d.len();
    for i in 0..n {
        let a = diag[i] * inv;
        let b = if i + 1 < n { sup[i] * inv } else { 0.0 };
        d[i] = a * a + b * b;
        e[i] = if i + 1 < n {
            b * diag[i + 1] * inv
        } else {
            0.0
        };
    }
}

/// Implicit QL with Wilkinson shifts on the symmetric tridiagonal (`d` diagonal, `e[i]` =
/// `T[i, i+1]`, `e[n-1] = 0`), applying every rotation to the `zrows` rows of the column-major
/// `zrows × n` matrix `z` (start from the identity for the eigenvectors, from `e_nᵀ` for their
/// last components only). On return `d` holds the eigenvalues (unsorted) and column `j` of `z`
/// the rows of eigenvector `j`. `tql2` in the 0-based form of Press et al., *Numerical Recipes*
/// §11.3 (`tqli`). The entries must be scaled to order one: plane rotations use
/// `√(f² + g²)`, which neither overflows nor (below the `ε`-level convergence threshold)
/// matters when it underflows.
pub(crate) fn ql_implicit(d: &mut [f64], e: &mut [f64], z: &mut [f64], zrows: usize) -> bool {
    let n = d.len();
    for l in 0..n {
        let mut iter = 0;
        loop {
            let mut m = l;
            while m + 1 < n {
                let dd = d[m].abs() + d[m + 1].abs();
                if e[m].abs() <= f64::EPSILON * dd {
                    break;
                }
                m += 1;
            }
            if m == l {
                break;
            }
            iter += 1;
            if iter > MAX_ITER {
                return false;
            }
            let mut g = (d[l + 1] - d[l]) / (2.0 * e[l]);
            let mut r = (g * g + 1.0).sqrt();
            g = d[m] - d[l] + e[l] / (g + r.copysign(g));
            let (mut s, mut c, mut p) = (1.0f64, 1.0f64, 0.0f64);
            let mut underflow = false;
            let mut i = m;
            while i > l {
                i -= 1;
                let f = s * e[i];
                let b = c * e[i];
                r = (f * f + g * g).sqrt();
                e[i + 1] = r;
                if r == 0.0 {
                    d[i + 1] -= p;
                    e[m] = 0.0;
                    underflow = true;
                    break;
                }
                let inv = 1.0 / r;
                s = f * inv;
                c = g * inv;
                g = d[i + 1] - p;
                r = (d[i] - g) * s + 2.0 * c * b;
                p = s * r;
                d[i + 1] = g + p;
                g = c * r - b;
                let (lo, hi) = z.split_at_mut((i + 1) * zrows);
                let (zi, zj) = (&mut lo[i * zrows..], &mut hi[..zrows]);
                for (a, b) in zi.iter_mut().zip(zj.iter_mut()) {
                    let f = *b;
                    *b = s * *a + c * f;
                    *a = c * *a - s * f;
                }
            }
            if underflow {
                continue;
            }
            d[l] -= p;
            e[l] = g;
            e[m] = 0.0;
        }
    }
    d.iter().chain(z[..n * zrows].iter()).all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::super::small_jacobi::SmallJacobi;
    use super::*;

    /// Against the Jacobi SVD: every singular value, and |last component| of every left vector
    /// whose singular value is separated from the others.
    fn check(diag: &[f64], sup: &[f64]) {
        let n = diag.len();
        let mut jac = SmallJacobi::new(n);
        assert!(jac.load_bidiagonal(diag, sup) && jac.decompose());
        let mut rc = RitzCheck::new(n + 3);
        assert!(rc.compute(diag, sup));
        assert_eq!(rc.n(), n);
        let s1 = jac.sigma()[0];
        for i in 0..n {
            let (a, b) = (rc.sigma(i), jac.sigma()[i]);
            // Absolute error ε σ₁² in σ² gives at most ~sqrt(ε) σ₁ near zero.
            let tol = 1e-13 * s1 + 1e-14 * s1 * s1 / b.max(1e-300);
            assert!((a - b).abs() <= tol.min(1e-7 * s1), "sigma {i}: {a} vs {b}");
            let gap = (0..n)
                .filter(|&j| j != i)
                .map(|j| (jac.sigma()[j] - b).abs())
                .fold(f64::INFINITY, f64::min);
            if gap > 1e-3 * s1 {
                let (x, y) = (rc.last(i).abs(), jac.left(i)[n - 1].abs());
                assert!((x - y).abs() < 1e-11, "last {i}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn matches_the_jacobi_svd() {
        check(&[3.0, 1.0, 2.0, 1e-3, 5.0], &[0.5, -0.2, 0.7, 0.1]);
        check(&[2.0], &[]);
        // A Lanczos-like bidiagonal: a few large coefficients, then a noise-level tail.
        let diag: Vec<f64> = (0..40)
            .map(|i| {
                if i < 3 {
                    10.0 / (i + 1) as f64
                } else {
                    0.01 + 1e-3 * ((i * 7 % 11) as f64)
                }
            })
            .collect();
        let sup: Vec<f64> = (0..39)
            .map(|i| {
                if i < 3 {
                    1e-4 * (i + 1) as f64
                } else {
                    5e-3 * ((i * 5 % 13) as f64)
                }
            })
            .collect();
        check(&diag, &sup);
        // Huge and tiny scales (the squares are formed after scaling).
        let big: Vec<f64> = diag.iter().map(|v| v * 1e200).collect();
        let bsup: Vec<f64> = sup.iter().map(|v| v * 1e200).collect();
        let mut rc = RitzCheck::new(40);
        assert!(rc.compute(&big, &bsup));
        assert!((rc.sigma(0) / 1e200 - 10.0).abs() < 1e-9);
    }

    #[test]
    fn zero_matrix_and_bad_input() {
        let mut rc = RitzCheck::new(3);
        assert!(rc.compute(&[0.0, 0.0, 0.0], &[0.0, 0.0]));
        assert_eq!(rc.sigma(0), 0.0);
        assert!(!rc.compute(&[1.0; 4], &[0.0; 3]), "over capacity");
        assert!(!rc.compute(&[1.0, f64::NAN], &[0.0]));
        assert!(!rc.compute(&[], &[]));
    }
}
