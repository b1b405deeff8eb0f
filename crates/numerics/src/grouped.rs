//! Pulse responses grouped by width: the sequence ERA runs on, free of deconvolution noise.
//!
//! The width deconvolution of [`crate::pulses`] is exact but marginally stable: with
//! noise, wide pulses leave a random walk at the frequencies `m·fs/w` where a `w`-sample
//! pulse carries no energy. ERA does not need it. For a pulse of width `w` the per-unit
//! response is `P_k = Σ_{i<w} Y_{k−i}`, and for `k >= w`
//!
//! ```text
//! P_k = Σ_{i<w} C A^(k−i−1) B = C A^(k−w) B̃_w,     B̃_w = (I + A + … + A^(w−1)) B
//! ```
//!
//! so the tail of every pulse response is itself a Markov sequence of the same `(A, C)` with
//! input matrix `B̃_w`. With `G` distinct widths, the block sequence `M_k` (`q × G`) whose column
//! `g` is `P^(g)_{k + w_g − 1}` (the amplitude-weighted average of that width's pulses) is the
//! Markov sequence of `(A, [B̃_1 … B̃_G], C)`: ERA on `M` (multi-input, `p = G`) identifies `A`,
//! `C` and the `B̃_g` with white, un-amplified noise. `B` follows from the weighted least
//! squares `min Σ_g W_g ‖S_g B − B̃_g‖²`, `S_g = Σ_{i<w_g} A^i` (Horner: `S ← I + A S`), through
//! its normal equations; `D = P_0` averaged over all pulses. For one-sample pulses only,
//! `M = Y` and `B = B̃`. `S_g` is singular only if `A` has an eigenvalue at a `w_g`-th root of
//! unity other than 1, the frequencies that pulse width cannot excite at all.

use super::linalg::solve_real;
use super::pulses::{PulseEnsemble, PulseInput};
use super::{IdentError, MarkovSeq};

/// Most distinct pulse widths in one record.
pub const MAX_GROUPS: usize = 4;

/// Preallocated per-width sums of pulse responses.
#[derive(Debug, Clone)]
pub struct WidthGroups {
    max_samples: usize,
    max_outputs: usize,
    widths: [usize; MAX_GROUPS],
    weights: [f64; MAX_GROUPS],
    count: usize,
    sums: Vec<f64>,
    one: Vec<f64>,
    d: Vec<f64>,
    group_of: Vec<usize>,
    q: usize,
    len: usize,
}

impl WidthGroups {
    /// Storage for `max_samples`, `max_outputs` and `max_pulses`.
    pub fn new(max_samples: usize, max_outputs: usize, max_pulses: usize) -> Self {
        Self {
            max_samples,
            max_outputs,
            widths: [0; MAX_GROUPS],
            weights: [0.0; MAX_GROUPS],
            count: 0,
            sums: vec![0.0; MAX_GROUPS * max_samples * max_outputs],
            one: vec![0.0; max_samples * max_outputs],
            d: vec![0.0; max_outputs],
            group_of: vec![0; max_pulses],
            q: 0,
            len: 0,
        }
    }

    /// Number of width groups `G`.
    pub fn groups(&self) -> usize {
        self.count
    }

    /// Width of each group.
    pub fn widths(&self) -> &[usize] {
        &self.widths[..self.count]
    }

    /// Total squared amplitude `W_g` of each group.
    pub fn weights(&self) -> &[f64] {
        &self.weights[..self.count]
    }

    /// `D = P_0`, the amplitude-weighted average over all pulses, per output.
    pub fn d(&self) -> &[f64] {
        &self.d[..self.q]
    }

    /// Groups the kept pulses of `ens` by width and writes `M` (`q × G` blocks) into `out`.
    pub fn build(
        &mut self,
        ens: &PulseEnsemble,
        input: &PulseInput<'_>,
        out: &mut MarkovSeq,
    ) -> Result<(), IdentError> {
        let (q, len) = (ens.outputs(), ens.len());
        self.q = q;
        self.len = len;
        self.count = 0;
        for (pi, p) in ens.pulses().iter().enumerate() {
            if !p.kept {
                continue;
            }
            let g = match self.widths[..self.count].iter().position(|w| *w == p.width) {
                Some(g) => g,
                None if self.count < MAX_GROUPS => {
                    self.widths[self.count] = p.width;
                    self.count += 1;
                    self.count - 1
                }
                None => {
                    return Err(IdentError::LimitsExceeded {
                        what: "distinct pulse widths",
                        value: self.count + 1,
                        limit: MAX_GROUPS,
                    })
                }
            };
            self.group_of[pi] = g;
        }
        let stride = self.max_samples * self.max_outputs;
        for g in 0..self.count {
            self.sums[g * stride..g * stride + len * q].fill(0.0);
            self.weights[g] = 0.0;
        }
        self.d[..q].fill(0.0);
        let mut total = 0.0;
        for (pi, p) in ens.pulses().iter().enumerate() {
            if !p.kept {
                continue;
            }
            let g = self.group_of[pi];
            let one = &mut self.one[..len * q];
            response(input, p.start, p.amplitude, ens.baseline(pi), len, one);
            let w = p.amplitude * p.amplitude;
            for (s, v) in self.sums[g * stride..g * stride + len * q]
                .iter_mut()
                .zip(one.iter())
            {
                *s += w * v;
            }
            for i in 0..q {
                self.d[i] += w * one[i];
            }
            self.weights[g] += w;
            total += w;
        }
        for v in &mut self.d[..q] {
            *v /= total;
        }
        self.write(out, None)
    }

    /// `M` without pulse `i` (kept, an index into the ensemble's pulses), for the jackknife;
    /// `weights_out` receives the groups' weights without it (0 for a group it emptied).
    pub fn leave_one_out(
        &mut self,
        ens: &PulseEnsemble,
        input: &PulseInput<'_>,
        i: usize,
        out: &mut MarkovSeq,
        weights_out: &mut [f64; MAX_GROUPS],
    ) -> Result<(), IdentError> {
        let p = ens.pulses()[i];
        let (q, len) = (self.q, self.len);
        let one = &mut self.one[..len * q];
        response(input, p.start, p.amplitude, ens.baseline(i), len, one);
        self.write(out, Some((self.group_of[i], p.amplitude * p.amplitude)))?;
        weights_out[..self.count].copy_from_slice(&self.weights[..self.count]);
        let g = self.group_of[i];
        let w = p.amplitude * p.amplitude;
        let rest = self.weights[g] - w;
        weights_out[g] = if rest > 1e-12 * self.weights[g] {
            rest
        } else {
            0.0
        };
        Ok(())
    }

    /// Writes `M_k(i, g) = P^(g)_{k + w_g − 1}`, optionally with one pulse (in `self.one`)
    /// removed from group `g`.
    fn write(&self, out: &mut MarkovSeq, remove: Option<(usize, f64)>) -> Result<(), IdentError> {
        let (q, gcount) = (self.q, self.count);
        let wmax = self.widths[..gcount].iter().copied().max().unwrap_or(1);
        let blocks = (self.len + 1).saturating_sub(wmax);
        out.set_len(q, gcount, blocks)?;
        let stride = self.max_samples * self.max_outputs;
        for g in 0..gcount {
            let shift = self.widths[g] - 1;
            let sums = &self.sums[g * stride..];
            let (w_rm, scale) = match remove {
                Some((rg, w)) if rg == g => {
                    let rest = self.weights[g] - w;
                    (
                        w,
                        if rest > 1e-12 * self.weights[g] {
                            1.0 / rest
                        } else {
                            0.0
                        },
                    )
                }
                _ => (0.0, 1.0 / self.weights[g]),
            };
            for k in 0..blocks {
                let src = (k + shift) * q;
                let blk = out.block_mut(k);
                for i in 0..q {
                    blk[i + g * q] = (sums[src + i] - w_rm * self.one[src + i]) * scale;
                }
            }
        }
        Ok(())
    }
}

/// Per-unit-amplitude response `(y(s + k) − b) / a`, `len × q` sample-major.
fn response(
    input: &PulseInput<'_>,
    start: usize,
    amp: f64,
    base: &[f64],
    len: usize,
    out: &mut [f64],
) {
    let q = base.len();
    for (c, ch) in input.y.iter().enumerate() {
        for k in 0..len {
            out[k * q + c] = (ch[start + k] - base[c]) / amp;
        }
    }
}

/// Scratch of [`input_matrix`]: three `n × n` matrices.
#[derive(Debug)]
pub struct InputScratch<'a> {
    /// `S_g = Σ_{i<w} A^i`.
    pub s: &'a mut [f64],
    /// Product scratch.
    pub t: &'a mut [f64],
    /// The normal-equation matrix.
    pub nrm: &'a mut [f64],
}

/// `B` (`n × 1`) from the group input matrices `B̃` (`n × G`, column-major) of the groups
/// `(widths, weights)` by the weighted normal equations
/// `(Σ W_g S_gᵀ S_g) B = Σ W_g S_gᵀ B̃_g`, `S_g = Σ_{i<w_g} A^i`. Returns false when the system
/// is singular.
pub fn input_matrix(
    a: &[f64],
    n: usize,
    btilde: &[f64],
    (widths, weights): (&[usize], &[f64]),
    scratch: InputScratch<'_>,
    b_out: &mut [f64],
) -> bool {
    let InputScratch { s, t, nrm } = scratch;
    nrm[..n * n].fill(0.0);
    b_out[..n].fill(0.0);
    for (g, (&w, &wt)) in widths.iter().zip(weights).enumerate() {
        if wt <= 0.0 {
            continue;
        }
        // S = I; repeat w−1 times: S ← I + A S.
        identity(s, n);
        for _ in 1..w {
            for j in 0..n {
                for i in 0..n {
                    let mut acc = if i == j { 1.0 } else { 0.0 };
                    for l in 0..n {
                        acc += a[i + l * n] * s[l + j * n];
                    }
                    t[i + j * n] = acc;
                }
            }
            s[..n * n].copy_from_slice(&t[..n * n]);
        }
        let bg = &btilde[g * n..(g + 1) * n];
        for j in 0..n {
            for i in 0..n {
                let dot: f64 = (0..n).map(|l| s[l + i * n] * s[l + j * n]).sum();
                nrm[i + j * n] += wt * dot;
            }
            let dot: f64 = (0..n).map(|l| s[l + j * n] * bg[l]).sum();
            b_out[j] += wt * dot;
        }
    }
    solve_real(nrm, n, b_out, 1)
}

fn identity(m: &mut [f64], n: usize) {
    m[..n * n].fill(0.0);
    for i in 0..n {
        m[i + i * n] = 1.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_matrix_undoes_the_width_sum() {
        // A = [[0.9, 0.1], [-0.2, 0.7]] (column-major), B = [1, 2].
        let a = [0.9, -0.2, 0.1, 0.7];
        let b = [1.0, 2.0];
        // B̃_3 = (I + A + A²) B.
        let ab = [a[0] * b[0] + a[2] * b[1], a[1] * b[0] + a[3] * b[1]];
        let aab = [a[0] * ab[0] + a[2] * ab[1], a[1] * ab[0] + a[3] * ab[1]];
        let bt = [b[0] + ab[0] + aab[0], b[1] + ab[1] + aab[1], b[0], b[1]];
        let (mut s, mut t, mut nrm, mut out) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 2]);
        let scratch = InputScratch {
            s: &mut s,
            t: &mut t,
            nrm: &mut nrm,
        };
        let groups = (&[3, 1][..], &[1.0, 0.5][..]);
        assert!(input_matrix(&a, 2, &bt, groups, scratch, &mut out));
        assert!(
            (out[0] - 1.0).abs() < 1e-13 && (out[1] - 2.0).abs() < 1e-13,
            "{out:?}"
        );
    }
}
