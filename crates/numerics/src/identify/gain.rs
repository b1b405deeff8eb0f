//! The DC gain of an OKID model: the realisation's must be its own Markov sequence's.
//!
//! OKID's recovered sequence `Y_0 .. Y_{L−1}` is the pulse response of the fitted observer
//! (ARX) model, and its sum `G = Σ_k Y_k` is that model's DC gain (to the truncation at `L`).
//! On a record excited by a few steps (a staircase, random steps of a pump) `G` is what the
//! regression determines best: inside each hold all input lags are equal, so only their sum is
//! seen, while the single `Y_k` are known only from the few samples after each step and carry
//! large alternating errors. ERA sizes its Hankel and picks its order where the sequence stands
//! above the noise *sample by sample*: it realises those alternating early terms (a pole near
//! `z = −1`) and drops a slow tail whose terms are each below the noise though their sum is the
//! gain, or it keeps a pole so near `z = 1` that `C (I − A)⁻¹ B` amplifies its error. Measured:
//! cascaded tanks (first two thirds) `Σ Y_k = +4.14`, the order-2 realisation `−2.99`; noahcurtiss
//! robbe `+585`, the realisation `−5978`; simulated staircases through `T = 10·u³` with
//! `fn = 0.1 Hz` `+9.7`, the realisation `−1.2`.
//!
//! **Rule.** When the realised gain `G_r = D + C (I − A)⁻¹ B` differs from `G` in sign, is not
//! finite, or is off by more than [`GAIN_MISMATCH`]` · |G|` (any output/input pair), `A` and `C`
//! (the poles and mode shapes) are kept and `B`, `D` are re-fitted to the sequence by least
//! squares under the constraint that the model's DC gain is `G`:
//!
//! ```text
//! min_{B,D} Σ_k ‖Y_k − Ŷ_k‖²,   Ŷ_0 = D,  Ŷ_k = C A^(k−1) B,   s.t.  D + M B = G,  M = C (I − A)⁻¹
//! ```
//!
//! Eliminating `D = G − M B` leaves an ordinary least-squares problem per input column `j`:
//! rows `−M b_j = Y_0 e_j − G e_j` and `C A^(k−1) b_j = Y_k e_j` (`k = 1 .. L−1`), solved by SVD;
//! then `d_j = G e_j − M b_j`. (The same split as the `B`, `D` step of subspace identification,
//! Verhaegen & Verdult, *Filtering and System Identification*, 2007, §9.2.4, here fitted to the
//! Markov sequence with the gain held.) A pole at `z = 1` (singular `I − A`) has no DC gain to
//! hold: the model is left as realised and the quality checks judge it.
//!
//! **Scope: one input, one output** (a stand's thrust, torque or speed against its command). With
//! several outputs the outputs share each column of `B`, and an output whose gain is near zero
//! by nature (an accelerometer) makes the relative test one of noise (measured on the F-16 GVT
//! sweep, level 1: realised gains 0.006, −0.009, −0.010, sums 0.003, 0.001, 0.007): several
//! outputs keep the realisation's gain.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::modal::mass_spring_damper;
use crate::report::{Gain, MassSpringDamper};
use crate::{MarkovSeq, ModelReport};

/// Largest relative difference `|G_r − G| / |G|` between the realised DC gain and the
/// sequence's own before `B`, `D` are re-fitted. `0.5`: ERA's truncation of a resolved
/// sequence changes its gain by a few percent (measured: Silverbox 0.982 of `Σ Y_k` 0.98); the
/// failures this rule repairs are off by the sign or by factors.
pub const GAIN_MISMATCH: f64 = 0.5;

/// A DC gain replaced by the sequence's (published in `source.okid`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GainRepair {
    /// The realisation's DC gain, input 0 to output 0, before the re-fit.
    pub realised: f64,
    /// `Σ Y_k`, input 0 to output 0: the model's DC gain after it.
    pub sequence: f64,
}

/// `Σ_k Y_k` of `markov` (`q × p`).
pub fn sequence_gain(markov: &MarkovSeq) -> DMatrix<f64> {
    let (q, p) = (markov.outputs(), markov.inputs());
    let mut g = DMatrix::<f64>::zeros(q, p);
    for block in markov.as_slice().chunks_exact(q * p) {
        g += DMatrix::from_column_slice(q, p, block);
    }
    g
}

/// Applies the rule of the module doc to `report` (realised from `markov`): `Some` with both
/// gains when `B`, `D` (and the DC gain, the mass–spring–damper equivalent) were re-fitted,
/// `None` when the realisation's gain stands.
pub fn impose_sequence_gain(report: &mut ModelReport, markov: &MarkovSeq) -> Option<GainRepair> {
    let (n, q, p) = (report.order, markov.outputs(), markov.inputs());
    if n == 0 || q != 1 || p != 1 || markov.len() < 2 {
        return None;
    }
    let mat = |m: &[Vec<f64>], r: usize, c: usize| {
        DMatrix::from_fn(r, c, |i, j| {
            m.get(i)
                .and_then(|row| row.get(j))
                .copied()
                .unwrap_or(f64::NAN)
        })
    };
    let (a, b, c, d) = (
        mat(&report.a, n, n),
        mat(&report.b, n, p),
        mat(&report.c, q, n),
        mat(&report.d, q, p),
    );
    let g = sequence_gain(markov);
    if g.iter().any(|v| !v.is_finite() || *v == 0.0) {
        return None;
    }
    let i_minus_a = DMatrix::<f64>::identity(n, n) - &a;
    // M = C (I − A)⁻¹, from (I − A)ᵀ Mᵀ = Cᵀ.
    let m = i_minus_a
        .transpose()
        .lu()
        .solve(&c.transpose())?
        .transpose();
    if m.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let realised = &d + &m * &b;
    let off =
        |r: f64, s: f64| !r.is_finite() || r * s <= 0.0 || (r - s).abs() > GAIN_MISMATCH * s.abs();
    if !realised.iter().zip(g.iter()).any(|(r, s)| off(*r, *s)) {
        return None;
    }
    // Rows: block 0 is −M, block k ≥ 1 is C A^(k−1).
    let len = markov.len();
    let mut phi = DMatrix::<f64>::zeros(len * q, n);
    phi.rows_mut(0, q).copy_from(&(-&m));
    let mut ca = c.clone();
    for k in 1..len {
        phi.rows_mut(k * q, q).copy_from(&ca);
        ca = &ca * &a;
    }
    let svd = phi.svd(true, true);
    let data = markov.as_slice();
    let mut b_new = DMatrix::<f64>::zeros(n, p);
    let mut d_new = DMatrix::<f64>::zeros(q, p);
    for j in 0..p {
        let t = DVector::from_fn(len * q, |row, _| {
            let (k, i) = (row / q, row % q);
            let y = data[k * q * p + i + j * q];
            if k == 0 {
                y - g[(i, j)]
            } else {
                y
            }
        });
        let bj = svd.solve(&t, 1e-12).ok()?;
        let dj = g.column(j) - &m * &bj;
        b_new.set_column(j, &bj);
        d_new.set_column(j, &dj);
    }
    if b_new.iter().chain(d_new.iter()).any(|v| !v.is_finite()) {
        return None;
    }
    let rows = |x: &DMatrix<f64>| -> Vec<Vec<f64>> {
        (0..x.nrows())
            .map(|i| x.row(i).iter().copied().collect())
            .collect()
    };
    report.b = rows(&b_new);
    report.d = rows(&d_new);
    report.dc_gain = Gain::from_block(g.as_slice(), q, p);
    let g0 = g[(0, 0)];
    let (mm, dd, kk) = if report.fn_hz.is_finite() {
        mass_spring_damper(report.fn_hz, report.zeta, g0)
    } else {
        (f64::NAN, f64::NAN, 1.0 / g0)
    };
    report.mass_spring_damper = MassSpringDamper {
        m: mm,
        d: dd,
        k: kk,
    };
    Some(GainRepair {
        realised: realised[(0, 0)],
        sequence: g0,
    })
}

#[cfg(test)]
mod tests;
