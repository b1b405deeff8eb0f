//! Dense SVD by one-sided Jacobi rotations (Hestenes 1958; Demmel & Veselić 1992) on storage
//! allocated once.
//!
//! For `M` (`m × n`, `m >= n`; a wide matrix is transposed first) plane rotations `J` are applied
//! from the right until the columns of `W = M V` are mutually orthogonal; then `σ_j = ‖w_j‖`,
//! `u_j = w_j / σ_j` and `M = U Σ Vᵀ`. For a pair of columns with `α = ‖w_i‖²`, `β = ‖w_j‖²`,
//! `γ = w_i·w_j` the rotation that zeroes `γ` is
//!
//! ```text
//! ζ = (β − α) / (2γ),   t = sign(ζ) / (|ζ| + √(1 + ζ²)),   c = 1/√(1 + t²),   s = c t
//! w_i ← c w_i − s w_j,  w_j ← s w_i + c w_j   (the same on the columns of V)
//! ```
//!
//! A sweep visits every pair; the iteration stops when no pair has `|γ| > tol √(αβ)`.
//! One-sided Jacobi computes singular values to high *relative* accuracy, which is why it is
//! used here: the noise-free tests need the small second singular value of a 2nd-order Hankel
//! matrix to 1e-10 and better. No heap allocation after [`DenseSvd::new`]. Cost per sweep is
//! about `3 m n²` flops; 6–12 sweeps are typical.

use super::{SvdError, Triplets};

/// Most sweeps before [`SvdError::NotConverged`].
const MAX_SWEEPS: usize = 60;

/// Preallocated one-sided Jacobi SVD for matrices up to `max_rows × max_cols`.
#[derive(Debug, Clone)]
pub struct DenseSvd {
    max_rows: usize,
    max_cols: usize,
    /// Working columns `W`, `tall × wide` column-major, `tall = max(m, n)`, `wide = min(m, n)`.
    w: Vec<f64>,
    /// Accumulated right rotations, `wide × wide` column-major.
    v: Vec<f64>,
    /// Column order by descending norm.
    idx: Vec<usize>,
    /// Column norms.
    norms: Vec<f64>,
}

impl DenseSvd {
    /// Storage for any `m × n` with `m <= max_rows`, `n <= max_cols`.
    pub fn new(max_rows: usize, max_cols: usize) -> Self {
        let small = max_rows.min(max_cols);
        Self {
            max_rows,
            max_cols,
            w: vec![0.0; max_rows * max_cols],
            v: vec![0.0; small * small],
            idx: vec![0; small],
            norms: vec![0.0; small],
        }
    }

    /// SVD of `m` (`rows × cols`, column-major). Writes all `min(rows, cols)` singular values
    /// (descending) into `out.sigma`, the leading `k` left singular vectors into `out.u`
    /// (`rows × k`, column-major) and right ones into `out.v` (`cols × k`).
    pub fn compute(
        &mut self,
        m: &[f64],
        rows: usize,
        cols: usize,
        k: usize,
        out: Triplets<'_>,
    ) -> Result<(), SvdError> {
        let Triplets { sigma, u, v } = out;
        let (tall, wide) = (rows.max(cols), rows.min(cols));
        if rows > self.max_rows || cols > self.max_cols {
            return Err(SvdError::Dimensions(
                "matrix larger than the preallocated storage",
            ));
        }
        if m.len() < rows * cols || sigma.len() < wide || k > wide {
            return Err(SvdError::Dimensions(
                "input or sigma buffer too small, or k > min(m, n)",
            ));
        }
        if u.len() < rows * k || v.len() < cols * k {
            return Err(SvdError::Dimensions("u or v buffer too small"));
        }
        let transposed = rows < cols;
        self.load(m, rows, cols, transposed);
        self.sweep(tall, wide)?;
        self.sort(tall, wide, sigma);
        // Not transposed: W = U Σ, V = V. Transposed (Mᵀ = V Σ Uᵀ): W = V Σ, rotations = U.
        let (left, right) = if transposed { (v, u) } else { (u, v) };
        for (out, &j) in self.idx[..k].iter().enumerate() {
            let s = self.norms[j];
            let col = &self.w[j * tall..(j + 1) * tall];
            let dst = &mut left[out * tall..(out + 1) * tall];
            for (d, x) in dst.iter_mut().zip(col) {
                *d = if s > 0.0 { x / s } else { 0.0 };
            }
            let rot = &self.v[j * wide..(j + 1) * wide];
            right[out * wide..(out + 1) * wide].copy_from_slice(rot);
        }
        Ok(())
    }

    fn load(&mut self, m: &[f64], rows: usize, cols: usize, transposed: bool) {
        if transposed {
            // W (cols × rows) = Mᵀ.
            for i in 0..rows {
                for j in 0..cols {
                    self.w[j + i * cols] = m[i + j * rows];
                }
            }
        } else {
            self.w[..rows * cols].copy_from_slice(&m[..rows * cols]);
        }
        let wide = rows.min(cols);
        let v = &mut self.v[..wide * wide];
        v.fill(0.0);
        for i in 0..wide {
            v[i + i * wide] = 1.0;
        }
    }

    fn sweep(&mut self, tall: usize, wide: usize) -> Result<(), SvdError> {
        let tol = f64::EPSILON * (tall as f64).sqrt().max(4.0);
        let fro2: f64 = self.w[..tall * wide].iter().map(|x| x * x).sum();
        // Columns below this squared norm are numerically zero: rotating them is noise.
        let tiny = (f64::EPSILON * f64::EPSILON) * fro2 * 1e-4 + f64::MIN_POSITIVE;
        for _ in 0..MAX_SWEEPS {
            let mut rotated = false;
            for i in 0..wide.saturating_sub(1) {
                for j in i + 1..wide {
                    if self.rotate_pair(tall, wide, i, j, tol, tiny) {
                        rotated = true;
                    }
                }
            }
            if !rotated {
                return Ok(());
            }
        }
        Err(SvdError::NotConverged { sweeps: MAX_SWEEPS })
    }

    /// Orthogonalises columns `i < j`; returns whether a rotation was applied.
    fn rotate_pair(
        &mut self,
        tall: usize,
        wide: usize,
        i: usize,
        j: usize,
        tol: f64,
        tiny: f64,
    ) -> bool {
        let (head, tail) = self.w.split_at_mut(j * tall);
        let wi = &mut head[i * tall..(i + 1) * tall];
        let wj = &mut tail[..tall];
        let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
        for (a, b) in wi.iter().zip(wj.iter()) {
            alpha += a * a;
            beta += b * b;
            gamma += a * b;
        }
        if alpha <= tiny || beta <= tiny || gamma.abs() <= tol * (alpha * beta).sqrt() {
            return false;
        }
        let zeta = (beta - alpha) / (2.0 * gamma);
        let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
        let c = 1.0 / (1.0 + t * t).sqrt();
        let s = c * t;
        rotate(wi, wj, c, s);
        let (vh, vt) = self.v.split_at_mut(j * wide);
        rotate(&mut vh[i * wide..(i + 1) * wide], &mut vt[..wide], c, s);
        true
    }

    fn sort(&mut self, tall: usize, wide: usize, sigma: &mut [f64]) {
        for j in 0..wide {
            let col = &self.w[j * tall..(j + 1) * tall];
            self.norms[j] = col.iter().map(|x| x * x).sum::<f64>().sqrt();
            self.idx[j] = j;
        }
        // Insertion sort by descending norm (no allocation; wide is at most a few hundred).
        for a in 1..wide {
            let mut b = a;
            while b > 0 && self.norms[self.idx[b - 1]] < self.norms[self.idx[b]] {
                self.idx.swap(b - 1, b);
                b -= 1;
            }
        }
        for (s, &j) in sigma.iter_mut().zip(&self.idx[..wide]) {
            *s = self.norms[j];
        }
    }
}

fn rotate(x: &mut [f64], y: &mut [f64], c: f64, s: f64) {
    for (a, b) in x.iter_mut().zip(y.iter_mut()) {
        let (xa, yb) = (*a, *b);
        *a = c * xa - s * yb;
        *b = s * xa + c * yb;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(m: &[f64], rows: usize, cols: usize) -> Vec<f64> {
        let wide = rows.min(cols);
        let mut svd = DenseSvd::new(rows, cols);
        let mut s = vec![0.0; wide];
        let mut u = vec![0.0; rows * wide];
        let mut v = vec![0.0; cols * wide];
        svd.compute(m, rows, cols, wide, Triplets::new(&mut s, &mut u, &mut v))
            .unwrap();
        let scale = s[0].max(1e-300);
        // Reconstruction M = U Σ Vᵀ.
        for i in 0..rows {
            for j in 0..cols {
                let r: f64 = (0..wide)
                    .map(|l| u[i + l * rows] * s[l] * v[j + l * cols])
                    .sum();
                assert!(
                    (r - m[i + j * rows]).abs() < 1e-12 * scale,
                    "reconstruction"
                );
            }
        }
        // Orthonormal V and descending sigma.
        for a in 0..wide {
            for b in 0..wide {
                let d: f64 = (0..cols).map(|j| v[j + a * cols] * v[j + b * cols]).sum();
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((d - want).abs() < 1e-12);
            }
        }
        assert!(s.windows(2).all(|w| w[0] >= w[1]));
        s
    }

    #[test]
    fn diagonal_and_known_values() {
        // [[3,0],[4,5]] has singular values sqrt(45) and sqrt(5).
        let s = check(&[3.0, 4.0, 0.0, 5.0], 2, 2);
        assert!((s[0] - 45f64.sqrt()).abs() < 1e-14);
        assert!((s[1] - 5f64.sqrt()).abs() < 1e-14);
    }

    #[test]
    fn tall_wide_and_rank_deficient() {
        let tall: Vec<f64> = (0..35).map(|i| ((i * 7 % 11) as f64).sin()).collect();
        check(&tall, 7, 5);
        check(&tall, 5, 7);
        // Rank one: outer product.
        let x = [1.0, -2.0, 0.5, 3.0];
        let y = [2.0, 1.0, -1.0];
        let m: Vec<f64> = (0..12).map(|k| x[k % 4] * y[k / 4]).collect();
        let s = check(&m, 4, 3);
        let nx: f64 = x.iter().map(|a| a * a).sum::<f64>().sqrt();
        let ny: f64 = y.iter().map(|a| a * a).sum::<f64>().sqrt();
        assert!((s[0] - nx * ny).abs() < 1e-13 * s[0]);
        assert!(s[1] < 1e-14 * s[0]);
    }

    #[test]
    fn refuses_oversize() {
        let mut svd = DenseSvd::new(2, 2);
        let mut s = [0.0; 3];
        let mut u = [0.0; 9];
        let mut v = [0.0; 9];
        let m = [0.0; 9];
        let out = Triplets::new(&mut s, &mut u, &mut v);
        assert!(svd.compute(&m, 3, 3, 3, out).is_err());
    }
}
