//! Accuracy indicators per mode (one entry per eigenvalue `λ_i` of `A`; a complex pair gets
//! two equal entries).
//!
//! With `A = Ψ Λ Ψ^-1`, modal input vectors `b̃_i` (row `i` of `Ψ^-1 B`), modal output vectors
//! `c̃_i` (column `i` of `C Ψ`), the realised observability `P = U_n Σ^½` and controllability
//! `Q = Σ^½ V_nᵀ` from the SVD factors:
//!
//! - **MSV** (mode singular value; Juang, *Applied System Identification*, 1994, §5.9):
//!   `MSV_i = √(‖c̃_i‖ ‖b̃_i‖ (1 + |λ_i| + … + |λ_i|^(c−1)))`, the mode's contribution to the
//!   Hankel matrix (`c` block columns).
//! - **MAC** (modal *amplitude* coherence, Juang & Pappa 1985, eq. 41 — not the modal assurance
//!   criterion): the coherence of the realised modal amplitude history `q̄_i` (row `i` of
//!   `Ψ^-1 Q`) with the ideal one `q̂_i = [b̃_i, λ_i b̃_i, …, λ_i^(c−1) b̃_i]`:
//!   `MAC_i = |q̄_i q̂_i*| / (‖q̄_i‖ ‖q̂_i‖)`.
//! - **EMAC** (extended modal amplitude coherence; Pappa, Elliott & Schenk 1993, J. Guidance
//!   16(5)): compares the realised modal observability at the last block row `a` of
//!   `P Ψ` (taken from the SVD factors — the realised matrix, not one rebuilt from `A` and `C`,
//!   which would always agree) with the extrapolation `c̃_i λ_i^a`; per element
//!   `R = min(|x|/|x̂|, |x̂|/|x|)`, phase weight `W = max(0, 1 − |arg(x/x̂)|/(π/4))`, averaged
//!   with weights `|x̂|²`; the same on the input side with the last block column of `Ψ^-1 Q`;
//!   `EMAC = EMAC_out · EMAC_in`. The block used is the last in which `|λ_i|^a >= 1e-8`, so that
//!   a fully decayed mode is not judged on rounding noise.
//! - **MPC** (modal phase collinearity, Pappa's form *without mean-centring*): for
//!   `φ = c̃_i`, `Sxx = Re φ·Re φ`, `Syy = Im φ·Im φ`, `Sxy = Re φ·Im φ`,
//!   `MPC = ((Sxx − Syy)² + 4 Sxy²) / (Sxx + Syy)²` (= 1 for a real-scalable mode shape; with one
//!   output it is always 1).
//! - **CMI** (consistent-mode indicator) `= EMAC · MPC`.

use nalgebra::Complex;

use super::hankel::HankelDims;

/// Indicators of all modes, written into `out_*[..n]`.
pub struct ModalInputs<'a> {
    /// Eigenvalues `λ`.
    pub lambda: &'a [Complex<f64>],
    /// Eigenvectors `Ψ` (`n × n`, column-major).
    pub psi: &'a [Complex<f64>],
    /// `Ψ^-1` (`n × n`, column-major).
    pub psi_inv: &'a [Complex<f64>],
    /// `B` (`n × p`).
    pub b: &'a [f64],
    /// `C` (`q × n`).
    pub c: &'a [f64],
    /// Singular values.
    pub sigma: &'a [f64],
    /// Left singular vectors (`rows × k`).
    pub u: &'a [f64],
    /// Right singular vectors (`cols × k`).
    pub v: &'a [f64],
    /// Hankel shape.
    pub dims: HankelDims,
    /// Order.
    pub n: usize,
}

/// The five indicators of one mode.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Indicators {
    /// Mode singular value.
    pub msv: f64,
    /// Modal amplitude coherence.
    pub mac: f64,
    /// Extended modal amplitude coherence.
    pub emac: f64,
    /// Modal phase collinearity.
    pub mpc: f64,
    /// Consistent-mode indicator.
    pub cmi: f64,
}

type C64 = Complex<f64>;

/// Computes the indicators of mode `i`.
pub fn mode(m: &ModalInputs<'_>, i: usize) -> Indicators {
    let (n, q, p, r, c) = (m.n, m.dims.q, m.dims.p, m.dims.r, m.dims.c);
    let (rows, cols) = (m.dims.rows(), m.dims.cols());
    let lam = m.lambda[i];
    let bt = |j: usize| -> C64 { (0..n).map(|l| m.psi_inv[i + l * n] * m.b[l + j * n]).sum() };
    let ct = |o: usize| -> C64 { (0..n).map(|l| m.c[o + l * q] * m.psi[l + i * n]).sum() };
    let bnorm = (0..p).map(|j| bt(j).norm_sqr()).sum::<f64>().sqrt();
    let cnorm = (0..q).map(|o| ct(o).norm_sqr()).sum::<f64>().sqrt();
    let geo: f64 = (0..c).map(|k| lam.norm().powi(k as i32)).sum();
    let msv = (cnorm * bnorm * geo).sqrt();

    // Realised modal amplitudes q̄ (row i of Ψ^-1 Σ^½ Vᵀ) at column `col`.
    let qbar = |col: usize| -> C64 {
        (0..n)
            .map(|l| m.psi_inv[i + l * n] * (m.sigma[l].sqrt() * m.v[col + l * cols]))
            .sum()
    };
    // Realised modal observability (row of U Σ^½ Ψ) at `row`.
    let pbar = |row: usize| -> C64 {
        (0..n)
            .map(|l| m.psi[l + i * n] * (m.u[row + l * rows] * m.sigma[l].sqrt()))
            .sum()
    };

    let (mut dot, mut n1, mut n2) = (C64::new(0.0, 0.0), 0.0, 0.0);
    let mut lk = C64::new(1.0, 0.0);
    for blk in 0..c {
        for j in 0..p {
            let real = qbar(blk * p + j);
            let ideal = lk * bt(j);
            dot += real * ideal.conj();
            n1 += real.norm_sqr();
            n2 += ideal.norm_sqr();
        }
        lk *= lam;
    }
    let mac = dot.norm() / (n1 * n2).sqrt();

    let last = |blocks: usize| -> usize {
        let mut a = blocks - 1;
        while a > 0 && lam.norm().powi(a as i32) < 1e-8 {
            a -= 1;
        }
        a
    };
    let a_out = last(r);
    let emac_out = coherence((0..q).map(|o| (pbar(a_out * q + o), ct(o) * lam.powu(a_out as u32))));
    let b_in = last(c);
    let emac_in = coherence((0..p).map(|j| (qbar(b_in * p + j), bt(j) * lam.powu(b_in as u32))));
    let emac = emac_out * emac_in;

    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for o in 0..q {
        let x = ct(o);
        sxx += x.re * x.re;
        syy += x.im * x.im;
        sxy += x.re * x.im;
    }
    let mpc = ((sxx - syy).powi(2) + 4.0 * sxy * sxy) / (sxx + syy).powi(2);
    Indicators {
        msv,
        mac,
        emac,
        mpc,
        cmi: emac * mpc,
    }
}

/// Pappa's EMAC of (realised, predicted) pairs: magnitude ratio × phase weight, weighted by
/// the predicted magnitude squared.
fn coherence(pairs: impl Iterator<Item = (C64, C64)>) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (real, pred) in pairs {
        let w = pred.norm_sqr();
        if w == 0.0 {
            continue;
        }
        let ratio = real.norm() / pred.norm();
        let r = if ratio > 1.0 { 1.0 / ratio } else { ratio };
        let phase = (real / pred).arg().abs();
        let wphase = (1.0 - phase / std::f64::consts::FRAC_PI_4).max(0.0);
        num += w * r * wphase;
        den += w;
    }
    if den > 0.0 {
        num / den
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coherence_of_equal_and_opposite() {
        let one = C64::new(1.0, 0.0);
        assert_eq!(coherence([(one, one)].into_iter()), 1.0);
        assert_eq!(coherence([(-one, one)].into_iter()), 0.0);
        assert!((coherence([(one * 0.5, one)].into_iter()) - 0.5).abs() < 1e-15);
    }
}
