//! Baselines and output noise, the width deconvolution `Y_k = P_k − P_{k−1} + Y_{k−w}`, the
//! amplitude-weighted average `Σ a_i² Y_i / Σ a_i²` and its noise growth (formulas in the
//! module doc of [`super`]).

use super::{contributes, missing, Pulse, PulseEnsemble, PulseInput};
use crate::{IdentError, MarkovSeq};

impl PulseEnsemble {
    pub(super) fn baselines_and_noise(&mut self, input: &PulseInput<'_>) {
        let (q, mq) = (self.q, self.max_outputs);
        let ss = &mut self.noise[..q];
        ss.fill(0.0);
        let mut dof = 0usize;
        for (pi, p) in self.pulses[..self.count].iter().enumerate() {
            if !p.kept {
                continue;
            }
            let base = p.base_start..p.start;
            let nb = base.clone().filter(|&k| !missing(input, k)).count();
            for (c, ch) in input.y.iter().enumerate() {
                let w = &ch[p.base_start..p.start];
                let measured = || {
                    w.iter()
                        .zip(base.clone())
                        .filter(|(_, k)| !missing(input, *k))
                        .map(|(v, _)| *v)
                };
                let mean = measured().sum::<f64>() / nb as f64;
                self.baselines[pi * mq + c] = mean;
                ss[c] += measured().map(|v| (v - mean) * (v - mean)).sum::<f64>();
            }
            dof += nb - 1;
        }
        for v in ss.iter_mut() {
            *v = if dof > 0 {
                (*v / dof as f64).sqrt()
            } else {
                f64::NAN
            };
        }
    }

    /// Deconvolved, amplitude-weighted average over the kept pulses; keeps the weighted sum.
    pub(super) fn average(
        &mut self,
        input: &PulseInput<'_>,
        markov: &mut MarkovSeq,
    ) -> Result<(), IdentError> {
        let (q, len, mq) = (self.q, self.len, self.max_outputs);
        markov.set_len(q, 1, len)?;
        let sum = &mut self.sum[..len * q];
        sum.fill(0.0);
        let lag_w = &mut self.lag_weight[..len];
        lag_w.fill(0.0);
        let mut weight = 0.0;
        for (pi, p) in self.pulses[..self.count].iter().enumerate() {
            if !p.kept {
                continue;
            }
            let one = &mut self.one[..len * q];
            deconvolve(input, p, &self.baselines[pi * mq..pi * mq + q], len, one);
            let w = p.amplitude * p.amplitude;
            for (k, (s, y)) in sum.chunks_mut(q).zip(one.chunks(q)).enumerate() {
                if contributes(input, p, k) {
                    for (s, y) in s.iter_mut().zip(y) {
                        *s += w * y;
                    }
                    lag_w[k] += w;
                }
            }
            weight += w;
        }
        for (k, (m, s)) in markov
            .as_mut_slice()
            .chunks_mut(q)
            .zip(sum.chunks(q))
            .enumerate()
        {
            for (m, s) in m.iter_mut().zip(s) {
                *m = s / lag_w[k];
            }
        }
        self.weight = weight;
        self.noise_growth(input);
        Ok(())
    }

    /// `g_k = √(W · Σ_(i∈k) a_i² g_i,k²) / W_k` (`= √(Σ a_i² g_i,k² / W)` when every pulse
    /// has lag `k`): the noise of lag `k` relative to `σ/√W`.
    fn noise_growth(&mut self, input: &PulseInput<'_>) {
        let g = &mut self.growth[..self.len];
        g.fill(0.0);
        for p in self.pulses[..self.count].iter().filter(|p| p.kept) {
            let a2 = p.amplitude * p.amplitude;
            for (k, gk) in g.iter_mut().enumerate() {
                if !contributes(input, p, k) {
                    continue;
                }
                let amp = if p.width == 1 {
                    1.0
                } else {
                    2.0 * (k / p.width + 1) as f64
                };
                *gk += a2 * amp;
            }
        }
        for (gk, wk) in g.iter_mut().zip(&self.lag_weight[..self.len]) {
            *gk = (*gk * (self.weight / wk) / wk).sqrt();
        }
    }
}

/// Per-unit-amplitude, width-deconvolved response of one pulse into `out` (`len × q`,
/// sample-major: `out[k*q + c]`), by `Y_k = P_k − P_{k−1} + Y_{k−w}`.
pub(super) fn deconvolve(
    input: &PulseInput<'_>,
    p: &Pulse,
    base: &[f64],
    len: usize,
    out: &mut [f64],
) {
    let q = base.len();
    for (c, ch) in input.y.iter().enumerate() {
        let mut prev = 0.0;
        for k in 0..len {
            let pk = (ch[p.start + k] - base[c]) / p.amplitude;
            out[k * q + c] = if p.width == 1 {
                pk
            } else {
                let back = if k >= p.width {
                    out[(k - p.width) * q + c]
                } else {
                    0.0
                };
                pk - prev + back
            };
            prev = pk;
        }
    }
}
