//! Markov parameters from pulse experiments: segmentation, baselines, amplitude scaling,
//! ensemble average and pulse-width deconvolution.
//!
//! **Segmentation.** The pulses are those of [`crate::segment`] (a run of `w` samples,
//! `1 <= w <= max_width`, at level `L0 + a` between two samples at the same level `L0`; any
//! other level change is an operating-point step), under [`SegmentRules::DEFAULT`] with
//! `max_pulse_samples = max_width`. With device events (EVENT IMPULSE_START) the pulse starts
//! are taken from the events and checked by [`segment::pulse_at`]. A pulse's
//! *window* runs from its first sample to the next level change of `u` (the next pulse or
//! step), so each pulse is referenced to its own level: several operating points in one record
//! are fine. Its *baseline* is the mean of each output over the last half (at most
//! [`MAX_BASELINE`] samples) of the run before the pulse, where the previous response has
//! decayed most. Missing samples carry the previous throttle level; a pulse whose baseline or
//! response window holds a missing sample is left out and counted.
//!
//! **Common length.** All pulses are averaged over the same `L` samples, the window length that
//! maximises `L × (pulses whose window is at least L)`; shorter ones are left out and counted.
//!
//! **Scaling and average.** With `P_i,k = (y(s_i + k) − b_i) / a_i` the pulse response of pulse
//! `i` per unit amplitude, `y_i = a_i P + noise` is a linear model in `a_i`, whose least-squares
//! estimate is the amplitude-weighted average `Σ a_i² P_i / Σ a_i²` (positive and negative
//! pulses and several amplitudes combine; a large pulse counts more). Its noise standard
//! deviation is `σ / √(Σ a_i²)` for white output noise of standard deviation `σ`.
//!
//! **Width.** A pulse held `w` samples is the sum of `w` one-sample pulses, so
//! `P_k = Σ_{i<w} Y_{k−i}` (terms with negative index are zero). Differencing gives
//! `P_k − P_{k−1} = Y_k − Y_{k−w}`, hence the exact recursion
//!
//! ```text
//! Y_k = P_k − P_{k−1} + Y_{k−w}        (P_{−1} = 0, Y_{<0} = 0)
//! ```
//!
//! It is marginally stable (the roots of `1 + z^-1 + … + z^-(w-1)` lie on the unit circle):
//! rounding and noise do not grow exponentially but accumulate like a random walk over `k/w`
//! steps, because a `w`-sample pulse carries no energy at multiples of `fs/w`. That is why
//! one-sample pulses are preferred and why the Hankel matrix only uses the response up to where
//! it sinks into the noise ([`crate::sizing`]). For `w = 1`, `Y_k = P_k`.
//!
//! **No `1/dt`.** `Y_k` is the response to a unit input held for one sample; a unit-area
//! impulse would be `1/dt` high and make DC gains off by the sample rate.

use super::segment::{self, Command, PulseRun, SegmentRules};
use super::{IdentError, MarkovSeq};

/// Most samples of a baseline window.
pub const MAX_BASELINE: usize = 64;

/// One record of a pulse experiment, borrowed.
#[derive(Debug, Clone, Copy)]
pub struct PulseInput<'a> {
    /// Sample period, seconds.
    pub dt_s: f64,
    /// Throttle, fraction 0..1, one per sample.
    pub u: &'a [f64],
    /// Output channels (thrust, torque, rpm …), each as long as `u`.
    pub y: &'a [&'a [f64]],
    /// `missing[k]` marks sample `k` not measured; empty means none missing.
    pub missing: &'a [bool],
    /// Device pulse starts (EVENT IMPULSE_START sample indices), if the record has them.
    pub pulse_starts: Option<&'a [usize]>,
}

/// One pulse found in the record.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pulse {
    /// First sample of the pulse.
    pub start: usize,
    /// Width `w` in samples.
    pub width: usize,
    /// Amplitude `a` (throttle above the pre-pulse level; negative for a dip).
    pub amplitude: f64,
    /// First sample of the baseline window (it ends at `start`).
    pub base_start: usize,
    /// Samples from `start` to the next level change.
    pub window: usize,
    /// Whether the pulse is used (false: left out and counted).
    pub kept: bool,
}

/// Preallocated pulse segmentation and ensemble average.
#[derive(Debug, Clone)]
pub struct PulseEnsemble {
    max_samples: usize,
    max_outputs: usize,
    pulses: Vec<Pulse>,
    count: usize,
    baselines: Vec<f64>,
    sum: Vec<f64>,
    one: Vec<f64>,
    weight: f64,
    growth: Vec<f64>,
    noise: Vec<f64>,
    len: usize,
    q: usize,
    kept: usize,
}

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
        // (Σ a² Y − a_i² Y_i) / (W − a_i²): one pulse's deconvolution, not all of them.
        let (q, len, mq) = (self.q, self.len, self.max_outputs);
        markov.set_len(q, 1, len)?;
        let p = self.pulses[i];
        let one = &mut self.one[..len * q];
        deconvolve(input, &p, &self.baselines[i * mq..i * mq + q], len, one);
        let w = p.amplitude * p.amplitude;
        let rest = self.weight - w;
        for ((m, s), y) in markov
            .as_mut_slice()
            .iter_mut()
            .zip(&self.sum[..len * q])
            .zip(one.iter())
        {
            *m = (s - w * y) / rest;
        }
        Ok(())
    }

    fn find(&mut self, input: &PulseInput<'_>, max_width: usize) -> Result<(), IdentError> {
        let rules = SegmentRules {
            max_pulse_samples: max_width,
            ..SegmentRules::DEFAULT
        };
        let cmd = Command::with_missing(input.u, input.missing);
        match input.pulse_starts {
            Some(starts) if !starts.is_empty() => {
                for &s in starts {
                    match segment::pulse_at(&cmd, s, &rules) {
                        Some(p) => self.push(pulse(&cmd, &p, &rules))?,
                        // A device pulse we cannot use is still a pulse: count it.
                        None => self.push(Pulse {
                            start: s,
                            ..Pulse::default()
                        })?,
                    }
                }
            }
            _ => {
                for p in segment::pulses(cmd, &rules) {
                    self.push(pulse(&cmd, &p, &rules))?;
                }
            }
        }
        Ok(())
    }

    fn push(&mut self, p: Pulse) -> Result<(), IdentError> {
        if self.count == self.pulses.len() {
            return Err(IdentError::LimitsExceeded {
                what: "pulses",
                value: self.count + 1,
                limit: self.pulses.len(),
            });
        }
        self.pulses[self.count] = p;
        self.count += 1;
        Ok(())
    }

    fn choose_length(&mut self, input: &PulseInput<'_>) {
        let pulses = &mut self.pulses[..self.count];
        // L maximises (pulses with window >= L) * L: many pulses and a long response.
        let mut len = 0;
        let mut best = 0;
        for cand in pulses
            .iter()
            .filter(|p| p.kept)
            .map(|p| p.window.min(self.max_samples))
        {
            let score = pulses.iter().filter(|p| p.kept && p.window >= cand).count() * cand;
            if score > best || (score == best && cand > len) {
                (best, len) = (score, cand);
            }
        }
        for p in pulses.iter_mut() {
            let gap = (p.base_start..p.start + len).any(|k| missing(input, k));
            if p.kept && (p.window < len || gap) {
                p.kept = false;
            }
        }
        self.kept = pulses.iter().filter(|p| p.kept).count();
        self.len = if self.kept > 0 { len } else { 0 };
    }

    fn baselines_and_noise(&mut self, input: &PulseInput<'_>) {
        let (q, mq) = (self.q, self.max_outputs);
        let ss = &mut self.noise[..q];
        ss.fill(0.0);
        let mut dof = 0usize;
        for (pi, p) in self.pulses[..self.count].iter().enumerate() {
            if !p.kept {
                continue;
            }
            let nb = p.start - p.base_start;
            for (c, ch) in input.y.iter().enumerate() {
                let w = &ch[p.base_start..p.start];
                let mean = w.iter().sum::<f64>() / nb as f64;
                self.baselines[pi * mq + c] = mean;
                ss[c] += w.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>();
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
    fn average(
        &mut self,
        input: &PulseInput<'_>,
        markov: &mut MarkovSeq,
    ) -> Result<(), IdentError> {
        let (q, len, mq) = (self.q, self.len, self.max_outputs);
        markov.set_len(q, 1, len)?;
        let sum = &mut self.sum[..len * q];
        sum.fill(0.0);
        let mut weight = 0.0;
        for (pi, p) in self.pulses[..self.count].iter().enumerate() {
            if !p.kept {
                continue;
            }
            let one = &mut self.one[..len * q];
            deconvolve(input, p, &self.baselines[pi * mq..pi * mq + q], len, one);
            let w = p.amplitude * p.amplitude;
            for (s, y) in sum.iter_mut().zip(one.iter()) {
                *s += w * y;
            }
            weight += w;
        }
        for (m, s) in markov.as_mut_slice().iter_mut().zip(sum.iter()) {
            *m = s / weight;
        }
        self.weight = weight;
        self.noise_growth();
        Ok(())
    }
}

impl PulseEnsemble {
    fn noise_growth(&mut self) {
        let g = &mut self.growth[..self.len];
        g.fill(0.0);
        for p in self.pulses[..self.count].iter().filter(|p| p.kept) {
            let a2 = p.amplitude * p.amplitude;
            for (k, gk) in g.iter_mut().enumerate() {
                let amp = if p.width == 1 {
                    1.0
                } else {
                    2.0 * (k / p.width + 1) as f64
                };
                *gk += a2 * amp;
            }
        }
        for gk in g.iter_mut() {
            *gk = (*gk / self.weight).sqrt();
        }
    }
}

/// Per-unit-amplitude, width-deconvolved response of one pulse into `out` (`len × q`,
/// sample-major: `out[k*q + c]`), by `Y_k = P_k − P_{k−1} + Y_{k−w}`.
fn deconvolve(input: &PulseInput<'_>, p: &Pulse, base: &[f64], len: usize, out: &mut [f64]) {
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

fn validate(
    input: &PulseInput<'_>,
    max_samples: usize,
    max_outputs: usize,
) -> Result<(), IdentError> {
    let n = input.u.len();
    if !(input.dt_s.is_finite() && input.dt_s > 0.0) {
        return Err(IdentError::InvalidInput("dt_s must be finite and > 0"));
    }
    if input.y.is_empty() {
        return Err(IdentError::InvalidInput(
            "at least one output channel is needed",
        ));
    }
    if input.y.len() > max_outputs {
        return Err(IdentError::LimitsExceeded {
            what: "outputs",
            value: input.y.len(),
            limit: max_outputs,
        });
    }
    if n > max_samples {
        return Err(IdentError::LimitsExceeded {
            what: "samples",
            value: n,
            limit: max_samples,
        });
    }
    if input.y.iter().any(|c| c.len() != n)
        || !(input.missing.is_empty() || input.missing.len() == n)
    {
        return Err(IdentError::InvalidInput(
            "input, outputs and missing mask must have the same length",
        ));
    }
    for k in 0..n {
        if !missing(input, k) && !input.u[k].is_finite() {
            return Err(IdentError::NonFinite {
                signal: "input",
                channel: 0,
                sample: k,
            });
        }
    }
    for (c, ch) in input.y.iter().enumerate() {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, v) in ch.iter().enumerate() {
            if missing(input, k) {
                continue;
            }
            if !v.is_finite() {
                return Err(IdentError::NonFinite {
                    signal: "output",
                    channel: c,
                    sample: k,
                });
            }
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        if hi <= lo {
            return Err(IdentError::ConstantOutput { channel: c });
        }
    }
    Ok(())
}

fn missing(input: &PulseInput<'_>, k: usize) -> bool {
    input.missing.get(k).copied().unwrap_or(false)
}

/// A pulse of the segmentation with its response window (to the end of the run it returns
/// into) and its baseline window (the last half, at most [`MAX_BASELINE`] samples, of the run
/// before it).
fn pulse(cmd: &Command<'_>, p: &PulseRun, rules: &SegmentRules) -> Pulse {
    let back = p.start + p.width;
    let base_len = p.start - p.before_start;
    let nb = base_len.div_ceil(2).clamp(1, MAX_BASELINE);
    Pulse {
        start: p.start,
        width: p.width,
        amplitude: p.amplitude,
        base_start: p.start - nb,
        window: segment::run_end(cmd, back, rules) - p.start,
        kept: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = 2·(one-sample response h_k = 0.5^k) convolved with the throttle deviation.
    fn simulate(u: &[f64], level: f64) -> Vec<f64> {
        (0..u.len())
            .map(|k| {
                (0..=k)
                    .map(|j| (u[j] - level) * 0.5f64.powi((k - j) as i32))
                    .sum::<f64>()
                    + 3.0
            })
            .collect()
    }

    #[test]
    fn widths_signs_and_amplitudes_average_to_the_one_sample_response() {
        let mut u = vec![0.4; 400];
        for (s, w, a) in [(50, 1, 0.1), (130, 2, -0.05), (210, 5, 0.02), (385, 3, 0.2)] {
            for k in s..s + w {
                u[k] = 0.4 + a;
            }
        }
        let y = simulate(&u, 0.4);
        let chans = [&y[..]];
        let input = PulseInput {
            dt_s: 0.01,
            u: &u,
            y: &chans,
            missing: &[],
            pulse_starts: None,
        };
        let mut ens = PulseEnsemble::new(400, 1, 8);
        let mut m = MarkovSeq::zeros(1, 1, 400);
        ens.build(&input, 16, &mut m).unwrap();
        assert_eq!(
            ens.kept(),
            3,
            "the last pulse's window is too short: {:?}",
            ens.pulses()
        );
        assert_eq!(ens.skipped(), 1);
        for k in 0..m.len() {
            assert!(
                (m.get(k, 0, 0) - 0.5f64.powi(k as i32)).abs() < 1e-12,
                "k={k}"
            );
        }
    }

    #[test]
    fn missing_sample_in_window_is_left_out() {
        let mut u = vec![0.3; 300];
        u[50] = 0.4;
        u[150] = 0.4;
        let mut y = simulate(&u, 0.3);
        let mut miss = vec![false; 300];
        miss[60] = true;
        y[60] = f64::NAN;
        u[60] = f64::NAN;
        let chans = [&y[..]];
        let input = PulseInput {
            dt_s: 0.01,
            u: &u,
            y: &chans,
            missing: &miss,
            pulse_starts: None,
        };
        let mut ens = PulseEnsemble::new(300, 1, 8);
        let mut m = MarkovSeq::zeros(1, 1, 300);
        ens.build(&input, 16, &mut m).unwrap();
        assert_eq!((ens.kept(), ens.skipped()), (1, 1));
    }

    #[test]
    fn bad_inputs() {
        let u = vec![0.3; 50];
        let y = vec![1.0; 50];
        let chans = [&y[..]];
        let input = PulseInput {
            dt_s: 0.01,
            u: &u,
            y: &chans,
            missing: &[],
            pulse_starts: None,
        };
        let mut ens = PulseEnsemble::new(100, 1, 8);
        let mut m = MarkovSeq::zeros(1, 1, 100);
        assert_eq!(
            ens.build(&input, 16, &mut m),
            Err(IdentError::ConstantOutput { channel: 0 })
        );
        let y2: Vec<f64> = (0..50).map(|k| k as f64).collect();
        let chans = [&y2[..]];
        let input = PulseInput { y: &chans, ..input };
        assert_eq!(ens.build(&input, 16, &mut m), Err(IdentError::NoPulse));
        let mut y3 = y2.clone();
        y3[7] = f64::NAN;
        let chans = [&y3[..]];
        let input = PulseInput { y: &chans, ..input };
        assert!(matches!(
            ens.build(&input, 16, &mut m),
            Err(IdentError::NonFinite { sample: 7, .. })
        ));
    }
}
