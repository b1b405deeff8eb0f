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
//!
//! **Missing samples.** Each group's average is per lag over the pulses measured at that lag
//! (`W_g,k`, the squared amplitudes there; [`crate::pulses`]): its noise is `σ/√W_g,k`, i.e.
//! `√(W_g/W_g,k)` times that of a complete lag ([`WidthGroups::growth`], which sizes the Hankel
//! matrix, [`crate::order::noise_floor::signal_length`]), and the leave-one-out removes a
//! pulse only at the lags it has. `M` stops before the first block a group has no pulse for.

use super::linalg::solve_real;
use super::pulses::{Pulse, PulseEnsemble, PulseInput};
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
    /// `W_g,k` per group and lag (stride `max_samples`).
    lag_weights: Vec<f64>,
    /// Noise growth per block of `M` (`max_g √(W_g/W_g,k+w_g−1)`); empty when no lag misses.
    growth: Vec<f64>,
    holes: bool,
    blocks: usize,
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
            lag_weights: vec![0.0; MAX_GROUPS * max_samples],
            growth: vec![0.0; max_samples],
            holes: false,
            blocks: 0,
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

    /// Noise growth of each block of `M` from missing samples, `max_g √(W_g / W_g,k+w_g−1)`
    /// (empty when every pulse has every lag).
    pub fn growth(&self) -> &[f64] {
        if self.holes {
            &self.growth[..self.blocks]
        } else {
            &[]
        }
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
        let ls = self.max_samples;
        for g in 0..self.count {
            self.sums[g * stride..g * stride + len * q].fill(0.0);
            self.lag_weights[g * ls..g * ls + len].fill(0.0);
            self.weights[g] = 0.0;
        }
        self.d[..q].fill(0.0);
        self.holes = false;
        let mut total = 0.0;
        for (pi, p) in ens.pulses().iter().enumerate() {
            if !p.kept {
                continue;
            }
            let g = self.group_of[pi];
            let one = &mut self.one[..len * q];
            response(input, p.start, p.amplitude, ens.baseline(pi), len, one);
            let w = p.amplitude * p.amplitude;
            let lag_w = &mut self.lag_weights[g * ls..g * ls + len];
            for (k, (s, v)) in self.sums[g * stride..g * stride + len * q]
                .chunks_mut(q)
                .zip(one.chunks(q))
                .enumerate()
            {
                if measured(input, p, k) {
                    for (s, v) in s.iter_mut().zip(v) {
                        *s += w * v;
                    }
                    lag_w[k] += w;
                }
            }
            if measured(input, p, 0) {
                for i in 0..q {
                    self.d[i] += w * one[i];
                }
                total += w;
            }
            self.weights[g] += w;
            self.holes |= p.missing > 0;
        }
        for v in &mut self.d[..q] {
            *v /= total;
        }
        self.blocks = self.measured_blocks();
        if self.holes {
            for k in 0..self.blocks {
                let mut gk = 1.0f64;
                for g in 0..self.count {
                    let lag = k + self.widths[g] - 1;
                    gk = gk.max((self.weights[g] / self.lag_weights[g * ls + lag]).sqrt());
                }
                self.growth[k] = gk;
            }
        }
        self.write(out, None, input)
    }

    /// Blocks of `M`: `len + 1 − w_max`, cut before the first block whose lag
    /// `k + w_g − 1` no pulse of group `g` has (never with every lag measured).
    fn measured_blocks(&self) -> usize {
        let wmax = self.widths[..self.count].iter().copied().max().unwrap_or(1);
        let blocks = (self.len + 1).saturating_sub(wmax);
        let ls = self.max_samples;
        (0..blocks)
            .find(|&k| {
                (0..self.count).any(|g| self.lag_weights[g * ls + k + self.widths[g] - 1] <= 0.0)
            })
            .unwrap_or(blocks)
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
        self.write(out, Some((self.group_of[i], p)), input)?;
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
    fn write(
        &self,
        out: &mut MarkovSeq,
        remove: Option<(usize, Pulse)>,
        input: &PulseInput<'_>,
    ) -> Result<(), IdentError> {
        let (q, gcount) = (self.q, self.count);
        let blocks = self.blocks;
        out.set_len(q, gcount, blocks)?;
        let stride = self.max_samples * self.max_outputs;
        let ls = self.max_samples;
        for g in 0..gcount {
            let shift = self.widths[g] - 1;
            let sums = &self.sums[g * stride..];
            let lag_w = &self.lag_weights[g * ls..];
            let removed = match remove {
                Some((rg, p)) if rg == g => Some(p),
                _ => None,
            };
            // A group emptied by the removal is all zeros (its weight goes to 0 as well).
            let emptied = removed.is_some_and(|p| {
                let rest = self.weights[g] - p.amplitude * p.amplitude;
                rest <= 1e-12 * self.weights[g]
            });
            for k in 0..blocks {
                let lag = k + shift;
                let src = lag * q;
                let wk = lag_w[lag];
                let (w_rm, scale) = match removed {
                    _ if emptied => (0.0, 0.0),
                    Some(p) if measured(input, &p, lag) => {
                        let w = p.amplitude * p.amplitude;
                        let rest = wk - w;
                        if rest > 1e-12 * wk {
                            (w, 1.0 / rest)
                        } else {
                            // The only pulse measured at this lag: the lag keeps the average.
                            (0.0, 1.0 / wk)
                        }
                    }
                    _ => (0.0, 1.0 / wk),
                };
                let blk = out.block_mut(k);
                for i in 0..q {
                    // (a missing lag of the removed pulse is NaN in `one`: never touched)
                    let rm = if w_rm == 0.0 {
                        0.0
                    } else {
                        w_rm * self.one[src + i]
                    };
                    blk[i + g * q] = (sums[src + i] - rm) * scale;
                }
            }
        }
        Ok(())
    }
}

/// Whether lag `k` of pulse `p`'s response is measured.
fn measured(input: &PulseInput<'_>, p: &Pulse, k: usize) -> bool {
    p.missing == 0 || !input.missing.get(p.start + k).copied().unwrap_or(false)
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
