//! Markov parameters from pulse experiments: segmentation, baselines, amplitude scaling,
//! ensemble average and pulse-width deconvolution.
//!
//! **Segmentation.** The pulses are those of [`crate::segment`] (a run of `w` samples,
//! `1 <= w <= max_width`, at level `L0 + a` between two samples at the same level `L0`; any
//! other level change is an operating-point step), under
//! [`SegmentRules::DEFAULT`](crate::segment::SegmentRules::DEFAULT) with
//! `max_pulse_samples = max_width`. With device events (EVENT IMPULSE_START) the pulse starts
//! are taken from the events and checked by [`segment::pulse_at`](crate::segment::pulse_at).
//! A pulse's *window* runs from its first sample to the next level change of `u` (the next
//! pulse or step), so each pulse is referenced to its own level: several operating points in
//! one record are fine. Its *baseline* is the mean of each output over the last half (at most
//! [`MAX_BASELINE`] samples) of the run before the pulse, where the previous response has
//! decayed most, over its measured samples. Missing samples carry the previous throttle level
//! for the segmentation.
//!
//! **Missing samples are missing, not fatal.** A pulse whose response window holds missing
//! samples still contributes at every lag it has: the average at lag `k` is taken over the
//! pulses measured there, `Σ_(i∈k) a_i² P_i,k / W_k` with `W_k = Σ_(i∈k) a_i²`, and its noise
//! standard deviation is `σ/√W_k`, larger than the `σ/√W` of a lag every pulse has (the
//! per-lag count and weight are kept, [`PulseEnsemble::lag_counts`], and carried into the
//! Hankel sizing and the jackknife: [`crate::grouped`]). Nothing is interpolated. For a pulse
//! wider than one sample the deconvolution below needs every earlier lag, so such a pulse
//! contributes to the deconvolved average only up to its first missing sample (the per-width
//! responses ERA runs on need no deconvolution and use every measured lag). A pulse is left
//! out (and counted) only when its baseline has no measured sample or a sample of the pulse
//! itself is missing (the carried level makes its width, the input, unknown); the common
//! length stops before the first lag that no pulse has.
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
//! it sinks into the noise ([`crate::order`]). For `w = 1`, `Y_k = P_k`.
//!
//! **No `1/dt`.** `Y_k` is the response to a unit input held for one sample; a unit-area
//! impulse would be `1/dt` high and make DC gains off by the sample rate.

// The types live here; their operations by responsibility: `ensemble.rs` (storage, build,
// accessors, leave-one-out), `validate.rs` (input checks), `find.rs` (which pulses, their
// windows, the common length), `average.rs` (baselines, deconvolution, weighted average).
mod average;
mod ensemble;
mod find;
mod validate;

#[cfg(test)]
mod tests;

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
    /// Missing samples in its response window `start .. start + L` (set for kept pulses).
    pub missing: usize,
    /// Lag of its first missing sample within `0 .. L` (`L` when none is missing).
    pub first_missing: usize,
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
    /// `W_k`: squared amplitudes of the kept pulses that contribute to the average at lag `k`.
    lag_weight: Vec<f64>,
    /// Kept pulses that contribute to the average at lag `k`.
    lag_count: Vec<usize>,
    growth: Vec<f64>,
    noise: Vec<f64>,
    len: usize,
    q: usize,
    kept: usize,
}

/// Whether sample `k` is marked missing (an empty mask marks none).
fn missing(input: &PulseInput<'_>, k: usize) -> bool {
    input.missing.get(k).copied().unwrap_or(false)
}

/// Whether pulse `p` contributes to the width-deconvolved average at lag `k`: a one-sample
/// pulse wherever its sample `start + k` is measured, a wider one up to its first missing
/// sample (the recursion `Y_k = P_k − P_(k−1) + Y_(k−w)` needs every earlier lag).
fn contributes(input: &PulseInput<'_>, p: &Pulse, k: usize) -> bool {
    if p.missing == 0 {
        return true;
    }
    if p.width == 1 {
        !missing(input, p.start + k)
    } else {
        k < p.first_missing
    }
}
