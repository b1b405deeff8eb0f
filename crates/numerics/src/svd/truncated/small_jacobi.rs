//! SVD of a small square matrix (the Lanczos bidiagonal) by one-sided Jacobi rotations, on
//! storage allocated once.
//!
//! Hestenes' method: rotate pairs of columns of `W = B` (and the same pairs of `Q = I`) until
//! all columns are mutually orthogonal; then `B Q = W = P Σ` with `σ_i = ‖w_i‖` and
//! `p_i = w_i / σ_i`. For columns `w_i, w_j` with `α = ‖w_i‖²`, `β = ‖w_j‖²`, `γ = w_iᵀ w_j`
//! the rotation angle annihilating `γ` is (Demmel & Veselić 1992, "Jacobi's method is more
//! accurate than QR", SIAM J. Matrix Anal. Appl. 13(4), alg. 4.1)
//!
//! $$\zeta = \frac{\beta - \alpha}{2\gamma},\quad
//!   t = \frac{\operatorname{sign}\zeta}{|\zeta| + \sqrt{1 + \zeta^2}},\quad
//!   c = \frac{1}{\sqrt{1+t^2}},\; s = c\,t .$$
//!
//! A pair counts as orthogonal when `|γ| ≤ ε √(αβ)` with `ε = 4·2⁻⁵²`, or when one of the
//! columns has norm below `2⁻⁵² ‖B‖_F` (numerically zero; rank-deficient matrices would
//! otherwise rotate rounding noise forever); a sweep without any rotation ends the iteration. Jacobi gives singular values with small *relative* error and
//! quadratic convergence (typically 5–10 sweeps); the matrices here are at most a few dozen
//! columns wide, so `O(m³)` per sweep is negligible next to the Hankel products.

mod sweep;

/// Largest number of sweeps before giving up (never reached in practice: Jacobi converges
/// quadratically once the off-diagonal mass is small).
const MAX_SWEEPS: usize = 60;

/// In [`SmallJacobi::decompose_leading`], the smallest `σ_i / σ₁` of a requested triplet for
/// which `q_i = Bᵀ p_i / σ_i` is used (error `~ε σ₁ / σ_i ≤ 2e-10`).
pub const RIGHT_FROM_LEFT_MIN: f64 = 1e-6;

/// Workspace for the SVD of square matrices of order up to `max_n`.
#[derive(Debug, Clone)]
pub struct SmallJacobi {
    max_n: usize,
    n: usize,
    /// `W`, column-major `n × n`, becomes `P Σ`, then `P` (sorted).
    w: Vec<f64>,
    /// `Q`, column-major `n × n` (sorted).
    q: Vec<f64>,
    sigma: Vec<f64>,
    order: Vec<usize>,
    tmp: Vec<f64>,
    /// The loaded matrix, kept for [`decompose_leading`](SmallJacobi::decompose_leading).
    orig: Vec<f64>,
    /// Squared column norms of `W`, updated by every rotation.
    norms: Vec<f64>,
    /// Rotation clock of the last rotation of each column (see `sweep`).
    touched: Vec<u64>,
    /// Rotation clock at which pair `(i, j)` (at `i + j n`) was last found orthogonal (0: never).
    checked: Vec<u64>,
}

impl SmallJacobi {
    /// Allocates for matrices of order up to `max_n`.
    pub fn new(max_n: usize) -> Self {
        let max_n = max_n.max(1);
        SmallJacobi {
            max_n,
            n: 0,
            w: vec![0.0; max_n * max_n],
            q: vec![0.0; max_n * max_n],
            sigma: vec![0.0; max_n],
            order: vec![0; max_n],
            tmp: vec![0.0; max_n * max_n],
            orig: vec![0.0; max_n * max_n],
            norms: vec![0.0; max_n],
            touched: vec![0; max_n],
            checked: vec![0; max_n * max_n],
        }
    }

    /// Largest order accepted.
    pub fn max_n(&self) -> usize {
        self.max_n
    }

    /// Loads the `n × n` upper bidiagonal matrix with diagonal `diag[..n]` and superdiagonal
    /// `sup[..n-1]` (`B[i, i+1] = sup[i]`). Returns `false` if `n` exceeds the capacity.
    pub fn load_bidiagonal(&mut self, diag: &[f64], sup: &[f64]) -> bool {
        let n = diag.len();
        if n == 0 || n > self.max_n || sup.len() + 1 < n {
            return false;
        }
        self.n = n;
        let w = &mut self.w[..n * n];
        w.fill(0.0);
        for i in 0..n {
            w[i + i * n] = diag[i];
            if i + 1 < n {
                w[i + (i + 1) * n] = sup[i];
            }
        }
        self.orig[..n * n].copy_from_slice(&self.w[..n * n]);
        true
    }

    /// Loads a general `n × n` column-major matrix. Returns `false` if `n` exceeds the
    /// capacity or `a` is too short.
    pub fn load(&mut self, a: &[f64], n: usize) -> bool {
        if n == 0 || n > self.max_n || a.len() < n * n {
            return false;
        }
        self.n = n;
        self.w[..n * n].copy_from_slice(&a[..n * n]);
        self.orig[..n * n].copy_from_slice(&a[..n * n]);
        true
    }

    /// Decomposes the loaded matrix. Returns `false` if the sweeps did not converge (or the
    /// matrix holds non-finite values).
    pub fn decompose(&mut self) -> bool {
        self.iterate(true)
    }

    /// Decomposes the loaded matrix for its leading `k` triplets: the sweeps rotate `W` only,
    /// and the leading right vectors follow from `Bᵀ p_i = σ_i q_i` (exact for the SVD
    /// `B = P Σ Qᵀ`; error `~ε σ₁/σ_i`), at `O(n²)` each instead of rotating `Q` in every
    /// sweep. The rotations, hence the values, left vectors and signs, are those of
    /// [`decompose`](Self::decompose). If one of the leading `k` singular values is below
    /// [`RIGHT_FROM_LEFT_MIN`]` · σ₁` (where that error would grow), the decomposition is
    /// repeated with `Q` accumulated. [`right`](Self::right) is valid for `i < k` only.
    pub fn decompose_leading(&mut self, k: usize) -> bool {
        let n = self.n;
        if n == 0 || k == 0 || k > n {
            return false;
        }
        if !self.iterate(false) {
            return false;
        }
        let s1 = self.sigma[0];
        if self.sigma[k - 1] < RIGHT_FROM_LEFT_MIN * s1 || s1 <= 0.0 {
            self.w[..n * n].copy_from_slice(&self.orig[..n * n]);
            return self.iterate(true);
        }
        for i in 0..k {
            let inv = 1.0 / self.sigma[i];
            let p = &self.w[i * n..(i + 1) * n];
            for j in 0..n {
                let col = &self.orig[j * n..(j + 1) * n];
                let bp: f64 = col.iter().zip(p).map(|(a, b)| a * b).sum();
                self.q[i * n + j] = bp * inv;
            }
        }
        true
    }

    /// The Jacobi sweeps (rotating `Q` too when `with_q`), then [`finish`](Self::finish).
    /// `W` is first scaled by the power of two `2^-e` that brings its largest entry into
    /// `[½, 1)`: exact in floating point, so every rotation is the one of the unscaled matrix,
    /// and the squares in `sweep` can neither overflow nor underflow; `σ` is scaled back.
    fn iterate(&mut self, with_q: bool) -> bool {
        let n = self.n;
        if n == 0 || self.w[..n * n].iter().any(|v| !v.is_finite()) {
            return false;
        }
        if with_q {
            let q = &mut self.q[..n * n];
            q.fill(0.0);
            for i in 0..n {
                q[i + i * n] = 1.0;
            }
        }
        let big = self.w[..n * n].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let e = if big > 0.0 {
            (big.log2().floor() as i32 + 1).clamp(-1000, 1000)
        } else {
            0
        };
        let down = 2f64.powi(-e);
        self.w[..n * n].iter_mut().for_each(|v| *v *= down);
        let fro2: f64 = self.w[..n * n].iter().map(|v| v * v).sum();
        let negligible = fro2 * f64::EPSILON * f64::EPSILON;
        self.touched[..n].fill(1);
        self.checked[..n * n].fill(0);
        let mut clock = 1u64;
        let mut converged = false;
        for _ in 0..MAX_SWEEPS {
            if !self.sweep(negligible, with_q, &mut clock) {
                converged = true;
                break;
            }
        }
        if !converged {
            return false;
        }
        self.finish(negligible.sqrt(), with_q);
        let up = 2f64.powi(e);
        self.sigma[..n].iter_mut().for_each(|s| *s *= up);
        true
    }

    /// Column norms into `sigma`, normalise `W` into `P`, sort descending, complete `P` to
    /// an orthonormal basis where `σ ≤ zero` (numerically zero columns have no direction).
    fn finish(&mut self, zero: f64, with_q: bool) {
        let n = self.n;
        for i in 0..n {
            let col = &mut self.w[i * n..(i + 1) * n];
            let norm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
            self.sigma[i] = norm;
            if norm > 0.0 {
                col.iter_mut().for_each(|v| *v /= norm);
            }
        }
        let order = &mut self.order[..n];
        for (i, o) in order.iter_mut().enumerate() {
            *o = i;
        }
        let sigma = &self.sigma;
        // Insertion sort (n is a few dozen): descending singular values, stable.
        for i in 1..n {
            let mut j = i;
            while j > 0 && sigma[order[j]] > sigma[order[j - 1]] {
                order.swap(j, j - 1);
                j -= 1;
            }
        }
        permute_cols(&mut self.w, &mut self.tmp, order, n);
        if with_q {
            permute_cols(&mut self.q, &mut self.tmp, order, n);
        }
        for (t, &o) in self.tmp[..n].iter_mut().zip(order.iter()) {
            *t = self.sigma[o];
        }
        self.sigma[..n].copy_from_slice(&self.tmp[..n]);
        let first_zero = self.sigma[..n].iter().position(|&s| s <= zero).unwrap_or(n);
        for i in first_zero..n {
            complete_column(&mut self.w, n, i);
        }
    }

    /// Order of the last decomposed matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Singular values, descending.
    pub fn sigma(&self) -> &[f64] {
        &self.sigma[..self.n]
    }

    /// Left singular vector `i` (of the descending order).
    pub fn left(&self, i: usize) -> &[f64] {
        &self.w[i * self.n..(i + 1) * self.n]
    }

    /// Right singular vector `i` (of the descending order).
    pub fn right(&self, i: usize) -> &[f64] {
        &self.q[i * self.n..(i + 1) * self.n]
    }
}

/// Replaces column `i` of the `n × n` matrix `m` by a unit vector orthogonal to columns
/// `0..i` (assumed orthonormal): the first coordinate vector that keeps a norm above 1/2 after
/// two Gram–Schmidt passes (one always does, as `i < n`).
fn complete_column(m: &mut [f64], n: usize, i: usize) {
    let (prev, cur) = m.split_at_mut(i * n);
    let col = &mut cur[..n];
    for l in 0..n {
        col.fill(0.0);
        col[l] = 1.0;
        for _ in 0..2 {
            for c in 0..i {
                let pc = &prev[c * n..(c + 1) * n];
                let d: f64 = pc.iter().zip(col.iter()).map(|(a, b)| a * b).sum();
                col.iter_mut().zip(pc).for_each(|(x, y)| *x -= d * y);
            }
        }
        let norm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm > 0.5 {
            col.iter_mut().for_each(|v| *v /= norm);
            return;
        }
    }
}

/// Reorders the columns of the `n × n` matrix `m` so that new column `i` is old `order[i]`.
fn permute_cols(m: &mut [f64], tmp: &mut [f64], order: &[usize], n: usize) {
    for (i, &o) in order.iter().enumerate() {
        tmp[i * n..(i + 1) * n].copy_from_slice(&m[o * n..(o + 1) * n]);
    }
    m[..n * n].copy_from_slice(&tmp[..n * n]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    fn check_against_nalgebra(a: &[f64], n: usize) {
        let mut j = SmallJacobi::new(n + 2);
        assert!(j.load(a, n));
        assert!(j.decompose());
        let m = DMatrix::from_column_slice(n, n, a);
        let reference = m.clone().svd(false, false).singular_values;
        for (i, s) in j.sigma().iter().enumerate() {
            assert!(
                (s - reference[i]).abs() <= 1e-13 * reference[0],
                "sigma {i}: {s} vs {}",
                reference[i]
            );
        }
        // B q_i = σ_i p_i and orthonormal factors.
        for i in 0..n {
            let (p, q, s) = (j.left(i), j.right(i), j.sigma()[i]);
            for row in 0..n {
                let bq: f64 = (0..n).map(|c| a[row + c * n] * q[c]).sum();
                assert!((bq - s * p[row]).abs() < 1e-12 * reference[0]);
            }
            for k in 0..n {
                let dot: f64 = q.iter().zip(j.right(k)).map(|(x, y)| x * y).sum();
                let want = if i == k { 1.0 } else { 0.0 };
                assert!((dot - want).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn matches_nalgebra_on_general_and_bidiagonal() {
        let n = 9;
        let a: Vec<f64> = (0..n * n)
            .map(|i| ((i * 37 % 17) as f64 - 8.0) / 3.0)
            .collect();
        check_against_nalgebra(&a, n);
        let diag = [3.0, 1.0, 2.0, 1e-3, 5.0];
        let sup = [0.5, -0.2, 0.7, 0.1];
        let mut b = vec![0.0; 25];
        for i in 0..5 {
            b[i + i * 5] = diag[i];
            if i < 4 {
                b[i + (i + 1) * 5] = sup[i];
            }
        }
        check_against_nalgebra(&b, 5);
        let mut j = SmallJacobi::new(5);
        assert!(j.load_bidiagonal(&diag, &sup));
        assert!(j.decompose());
        let mut k = SmallJacobi::new(5);
        assert!(k.load(&b, 5));
        assert!(k.decompose());
        assert_eq!(j.sigma(), k.sigma());
    }

    #[test]
    fn leading_triplets_match_the_full_decomposition() {
        let n = 12;
        let diag: Vec<f64> = (0..n).map(|i| 5.0 / (i + 1) as f64).collect();
        let sup: Vec<f64> = (0..n - 1)
            .map(|i| 0.3 * ((i * 7 % 5) as f64 - 2.0))
            .collect();
        let mut full = SmallJacobi::new(n);
        assert!(full.load_bidiagonal(&diag, &sup) && full.decompose());
        let mut lead = SmallJacobi::new(n);
        assert!(lead.load_bidiagonal(&diag, &sup) && lead.decompose_leading(4));
        for i in 0..4 {
            assert!((full.sigma()[i] - lead.sigma()[i]).abs() < 1e-14 * full.sigma()[0]);
            // Same rotations: same signs.
            for (a, b) in full.left(i).iter().zip(lead.left(i)) {
                assert!((a - b).abs() < 1e-13, "left {i}");
            }
            for (a, b) in full.right(i).iter().zip(lead.right(i)) {
                assert!((a - b).abs() < 1e-13, "right {i}");
            }
        }
        // A leading value below RIGHT_FROM_LEFT_MIN σ₁: Q is accumulated after all.
        let mut tiny = SmallJacobi::new(3);
        assert!(tiny.load_bidiagonal(&[1.0, 1e-9, 0.5], &[0.0, 0.0]) && tiny.decompose_leading(3));
        assert!((tiny.sigma()[2] - 1e-9).abs() < 1e-20);
        assert!((tiny.right(2)[1].abs() - 1.0).abs() < 1e-15);
        assert!(!tiny.decompose_leading(4));
    }

    #[test]
    fn rejects_oversized_and_non_finite() {
        let mut j = SmallJacobi::new(2);
        assert!(!j.load(&[0.0; 9], 3));
        assert!(!j.load_bidiagonal(&[1.0; 3], &[0.0; 2]));
        assert!(j.load(&[1.0, f64::NAN, 0.0, 1.0], 2));
        assert!(!j.decompose());
    }

    #[test]
    fn zero_and_rank_deficient() {
        let mut j = SmallJacobi::new(3);
        assert!(j.load(&[0.0; 9], 3));
        assert!(j.decompose());
        assert_eq!(j.sigma(), &[0.0, 0.0, 0.0]);
        // Rank one: outer product.
        let a = [1.0, 2.0, 3.0, 2.0, 4.0, 6.0, -1.0, -2.0, -3.0];
        assert!(j.load(&a, 3));
        assert!(j.decompose());
        assert!((j.sigma()[0] - 14f64.sqrt() * 6f64.sqrt()).abs() < 1e-12);
        assert!(j.sigma()[1] < 1e-14);
        // The left factor is completed to an orthonormal basis.
        for a in 0..3 {
            for b in 0..3 {
                let d: f64 = j.left(a).iter().zip(j.left(b)).map(|(x, y)| x * y).sum();
                assert!((d - if a == b { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
    }
}
