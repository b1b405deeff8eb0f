//! The ensemble's public face: storage, what the last build found, the build itself (validate,
//! find, choose the common length, baselines, average) and the jackknife's leave-one-out.

use super::average::deconvolve;
use super::validate::validate;
use super::{contributes, Pulse, PulseEnsemble, PulseInput};
use crate::{IdentError, MarkovSeq};

impl PulseEnsemble {
    /// Storage for records up to `max_samples`, `max_outputs` channels, `max_pulses` pulses.
    pub fn new(max_samples: usize, max_outputs: usize, max_pulses: usize) -> Self {
        Self {
            max_samples,
            max_outputs,
            pulses: vec![Pulse::default(); max_pulses],
            count: 0,
            baselines: vec![0.0; max_pulses * max_outputs],
            sum: vec![0.0; max_samples * max_outputs],
            one: vec![0.0; max_samples * max_outputs],
            weight: 0.0,
            lag_weight: vec![0.0; max_samples],
            lag_count: vec![0; max_samples],
            growth: vec![0.0; max_samples],
            noise: vec![0.0; max_outputs],
            len: 0,
            q: 0,
            kept: 0,
        }
    }

    /// All pulses found by the last [`PulseEnsemble::build`] (kept and left out).
    pub fn pulses(&self) -> &[Pulse] {
        &self.pulses[..self.count]
    }

    /// Per-output baselines of pulse `i` (an index into [`PulseEnsemble::pulses`]).
    pub fn baseline(&self, i: usize) -> &[f64] {
        &self.baselines[i * self.max_outputs..i * self.max_outputs + self.q]
    }

    /// Number of output channels of the last build.
    pub fn outputs(&self) -> usize {
        self.q
    }

    /// Pulses averaged.
    pub fn kept(&self) -> usize {
        self.kept
    }

    /// Per lag `k < L`: how many kept pulses the average at lag `k` is over (all of them
    /// where no pulse misses that lag; see the module doc on missing samples).
    pub fn lag_counts(&self) -> &[usize] {
        &self.lag_count[..self.len]
    }

    /// Missing samples in the response windows (`0 .. L`) of the kept pulses.
    pub fn missing_in_windows(&self) -> usize {
        self.pulses[..self.count]
            .iter()
            .filter(|p| p.kept)
            .map(|p| p.missing)
            .sum()
    }

    /// Pulses found but left out.
    pub fn skipped(&self) -> usize {
        self.count - self.kept
    }

    /// Common response length `L` (Markov blocks `Y_0 .. Y_{L-1}`).
    pub fn len(&self) -> usize {
        self.len
    }

    /// True before a successful build.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Output noise standard deviation per channel from the baselines (NaN when no baseline
    /// had two samples).
    pub fn output_noise(&self) -> &[f64] {
        &self.noise[..self.q]
    }

    /// Noise standard deviation of the averaged Markov parameters, channel `c`, before the
    /// width deconvolution: `σ_c/√Σa²`. Multiply by [`PulseEnsemble::growth`] for `Y_k`.
    pub fn markov_noise(&self, c: usize) -> f64 {
        self.noise[c] / self.weight.sqrt()
    }

    /// Noise growth of the width deconvolution per Markov index `k` (length `L`):
    /// `√(Σ_i a_i² g_i,k² / Σ_i a_i²)` with `g² = 1` for one-sample pulses and
    /// `g² = 2(⌊k/w⌋ + 1)` for width `w > 1` (the recursion sums `⌊k/w⌋ + 1` differences of
    /// independent noise samples).
    pub fn growth(&self) -> &[f64] {
        &self.growth[..self.len]
    }

    /// Widest kept pulse.
    pub fn max_width(&self) -> usize {
        self.pulses[..self.count]
            .iter()
            .filter(|p| p.kept)
            .map(|p| p.width)
            .max()
            .unwrap_or(0)
    }

    /// Validates the input, segments the pulses, averages them into `markov` (`q × 1` blocks).
    pub fn build(
        &mut self,
        input: &PulseInput<'_>,
        max_width: usize,
        markov: &mut MarkovSeq,
    ) -> Result<(), IdentError> {
        self.len = 0;
        self.count = 0;
        self.kept = 0;
        validate(input, self.max_samples, self.max_outputs)?;
        self.q = input.y.len();
        self.find(input, max_width)?;
        self.choose_length(input);
        if self.kept == 0 {
            return Err(if self.count == 0 {
                IdentError::NoPulse
            } else {
                IdentError::AllPulsesSkipped {
                    skipped: self.count,
                }
            });
        }
        self.baselines_and_noise(input);
        self.average(input, markov)
    }

    /// The leave-one-out average without pulse `i` (an index into [`PulseEnsemble::pulses`];
    /// must be kept) into `markov`, for the jackknife.
    pub fn leave_one_out(
        &mut self,
        input: &PulseInput<'_>,
        i: usize,
        markov: &mut MarkovSeq,
    ) -> Result<(), IdentError> {
        if self.kept < 2 || i >= self.count || !self.pulses[i].kept {
            return Err(IdentError::InvalidInput(
                "leave-one-out needs a kept pulse and two or more pulses",
            ));
        }
        // (Σ a² Y − a_i² Y_i) / (W_k − a_i²) at the lags pulse i has; where it is the only
        // pulse measured there, the lag keeps the full average (it cannot be left out).
        let (q, len, mq) = (self.q, self.len, self.max_outputs);
        markov.set_len(q, 1, len)?;
        let p = self.pulses[i];
        let one = &mut self.one[..len * q];
        deconvolve(input, &p, &self.baselines[i * mq..i * mq + q], len, one);
        let w = p.amplitude * p.amplitude;
        for (k, ((m, s), y)) in markov
            .as_mut_slice()
            .chunks_mut(q)
            .zip(self.sum[..len * q].chunks(q))
            .zip(one.chunks(q))
            .enumerate()
        {
            let wk = self.lag_weight[k];
            let rest = wk - w;
            let has = contributes(input, &p, k) && rest > 1e-12 * wk;
            for ((m, s), y) in m.iter_mut().zip(s).zip(y) {
                *m = if has { (s - w * y) / rest } else { s / wk };
            }
        }
        Ok(())
    }
}
