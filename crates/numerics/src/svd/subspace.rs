//! Warm-started subspace iteration for the leading singular triplets of a Hankel matrix that
//! differs only a little from one already decomposed (the jackknife's leave-one-out Hankel
//! matrices).
//!
//! Starting from the previous right singular vectors `V₀` (`cols × b`, orthonormal), each
//! iteration does `Z = H V`, `Z = Q R` (modified Gram–Schmidt), `W = Hᵀ Q`, `V = orth(W)`. The
//! subspace error shrinks by `(σ_{b+1}/σ_k)²` per iteration. A final Rayleigh–Ritz step
//! (`H V = Q R`, `R = U_R Σ V_Rᵀ` by [`DenseSvd`], `U = Q U_R`, `V ← V V_R`) gives the triplets.
//! No allocation after [`SubspaceSvd::new`].

use super::dense::DenseSvd;
use super::{SvdError, Triplets};
use crate::hankel::HankelDims;

/// Preallocated subspace iteration for blocks of up to `max_b` vectors.
#[derive(Debug, Clone)]
pub struct SubspaceSvd {
    max_b: usize,
    z: Vec<f64>,
    w: Vec<f64>,
    r: Vec<f64>,
    ur: Vec<f64>,
    vr: Vec<f64>,
    sr: Vec<f64>,
    small: DenseSvd,
}

impl SubspaceSvd {
    /// Storage for Hankel matrices up to `max_rows × max_cols` and blocks of `max_b` vectors.
    pub fn new(max_rows: usize, max_cols: usize, max_b: usize) -> Self {
        Self {
            max_b,
            z: vec![0.0; max_rows * max_b],
            w: vec![0.0; max_cols * max_b],
            r: vec![0.0; max_b * max_b],
            ur: vec![0.0; max_b * max_b],
            vr: vec![0.0; max_b * max_b],
            sr: vec![0.0; max_b],
            small: DenseSvd::new(max_b, max_b),
        }
    }

    /// Leading `b` triplets of `H(0)` of `markov`, starting from `v0` (`cols × b`, orthonormal).
    /// Writes `sigma[..b]`, `u` (`rows × b`) and `v` (`cols × b`) of `out`.
    pub fn compute(
        &mut self,
        markov: &[f64],
        dims: HankelDims,
        b: usize,
        iters: usize,
        v0: &[f64],
        out: Triplets<'_>,
    ) -> Result<(), SvdError> {
        let Triplets { sigma, u, v } = out;
        let (rows, cols) = (dims.rows(), dims.cols());
        if b == 0 || b > self.max_b || b > rows.min(cols) {
            return Err(SvdError::Dimensions("subspace block size out of range"));
        }
        if rows * b > self.z.len() || cols * b > self.w.len() {
            return Err(SvdError::Dimensions(
                "Hankel larger than the subspace storage",
            ));
        }
        if v0.len() < cols * b || v.len() < cols * b || u.len() < rows * b || sigma.len() < b {
            return Err(SvdError::Dimensions("subspace buffers too small"));
        }
        self.w[..cols * b].copy_from_slice(&v0[..cols * b]);
        for _ in 0..iters {
            for l in 0..b {
                let (wl, zl) = (
                    &self.w[l * cols..(l + 1) * cols],
                    &mut self.z[l * rows..(l + 1) * rows],
                );
                dims.apply(markov, 0, wl, zl);
            }
            mgs(&mut self.z, rows, b, &mut self.r);
            for l in 0..b {
                let (zl, wl) = (
                    &self.z[l * rows..(l + 1) * rows],
                    &mut self.w[l * cols..(l + 1) * cols],
                );
                dims.apply_t(markov, 0, zl, wl);
            }
            mgs(&mut self.w, cols, b, &mut self.r);
        }
        for l in 0..b {
            let (wl, zl) = (
                &self.w[l * cols..(l + 1) * cols],
                &mut self.z[l * rows..(l + 1) * rows],
            );
            dims.apply(markov, 0, wl, zl);
        }
        mgs(&mut self.z, rows, b, &mut self.r);
        // R (b × b, column-major, upper triangular) = U_R Σ V_Rᵀ.
        let small = Triplets::new(&mut self.sr, &mut self.ur, &mut self.vr);
        self.small.compute(&self.r[..b * b], b, b, b, small)?;
        sigma[..b].copy_from_slice(&self.sr[..b]);
        matmul(&self.z, rows, b, &self.ur, b, u);
        matmul(&self.w, cols, b, &self.vr, b, v);
        Ok(())
    }
}

/// Modified Gram–Schmidt with one re-orthogonalisation pass ("twice is enough") on the `k`
/// columns of `x` (`n × k`): `x ← Q`, `r ← R` (`k × k`). A column that is numerically in the
/// span of the previous ones (rank-deficient `H`) becomes zero with `R_jj = 0`, so `Q` never
/// carries rounding noise blown up to unit length.
fn mgs(x: &mut [f64], n: usize, k: usize, r: &mut [f64]) {
    r[..k * k].fill(0.0);
    for j in 0..k {
        let before = x[j * n..(j + 1) * n]
            .iter()
            .map(|a| a * a)
            .sum::<f64>()
            .sqrt();
        for _pass in 0..2 {
            for i in 0..j {
                let (head, tail) = x.split_at_mut(j * n);
                let qi = &head[i * n..(i + 1) * n];
                let xj = &mut tail[..n];
                let dot: f64 = qi.iter().zip(xj.iter()).map(|(a, b)| a * b).sum();
                for (a, b) in xj.iter_mut().zip(qi) {
                    *a -= dot * b;
                }
                r[i + j * k] += dot;
            }
        }
        let xj = &mut x[j * n..(j + 1) * n];
        let norm = xj.iter().map(|a| a * a).sum::<f64>().sqrt();
        if norm > 1e-13 * before && norm > 0.0 {
            r[j + j * k] = norm;
            xj.iter_mut().for_each(|a| *a /= norm);
        } else {
            xj.fill(0.0);
        }
    }
}

/// `out (n × k) = x (n × m) · y (m × k)`, all column-major.
fn matmul(x: &[f64], n: usize, m: usize, y: &[f64], k: usize, out: &mut [f64]) {
    for c in 0..k {
        let dst = &mut out[c * n..(c + 1) * n];
        dst.fill(0.0);
        for l in 0..m {
            let f = y[l + c * m];
            for (d, s) in dst.iter_mut().zip(&x[l * n..(l + 1) * n]) {
                *d += f * s;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_dense_from_a_perturbed_start() {
        // Y_k = 0.9^k cos(0.3k) + 0.5 (0.6)^k, SISO, 12 × 12 Hankel.
        let markov: Vec<f64> = (0..26)
            .map(|k| {
                let k = k as f64;
                0.9f64.powf(k) * (0.3 * k).cos() + 0.5 * 0.6f64.powf(k)
            })
            .collect();
        let dims = HankelDims {
            q: 1,
            p: 1,
            r: 12,
            c: 12,
        };
        let mut h = vec![0.0; 144];
        dims.fill(&markov, 0, &mut h);
        let mut dense = DenseSvd::new(12, 12);
        let (mut s, mut u, mut v) = (vec![0.0; 12], vec![0.0; 144], vec![0.0; 144]);
        dense
            .compute(&h, 12, 12, 12, Triplets::new(&mut s, &mut u, &mut v))
            .unwrap();
        // Start from V with a perturbation, re-orthonormalised.
        let b = 4;
        let mut v0: Vec<f64> = v[..12 * b]
            .iter()
            .enumerate()
            .map(|(i, x)| x + 1e-3 * ((i % 5) as f64 - 2.0))
            .collect();
        let mut r = vec![0.0; b * b];
        mgs(&mut v0, 12, b, &mut r);
        let mut sub = SubspaceSvd::new(12, 12, b);
        let (mut s2, mut u2, mut v2) = (vec![0.0; b], vec![0.0; 12 * b], vec![0.0; 12 * b]);
        let out = Triplets::new(&mut s2, &mut u2, &mut v2);
        sub.compute(&markov, dims, b, 6, &v0, out).unwrap();
        for l in 0..3 {
            assert!(
                (s2[l] - s[l]).abs() < 1e-9 * s[0],
                "sigma {l}: {} vs {}",
                s2[l],
                s[l]
            );
        }
    }
}
