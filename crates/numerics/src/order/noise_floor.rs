//! The noise floor of Markov parameters and how far a response stands above it.
//!
//! **Noise floor.** `σ_i`, the noise standard deviation of the Markov parameters of output
//! `i`, comes from where the data allow an independent estimate: on the pulse path from the
//! pre-pulse baselines ([`crate::pulses`]) divided by `√w_min` for the averaged responses
//! ([`pulse_noise`]); for given Markov parameters it is the RMS of the last quarter of the
//! sequence ([`tail_noise`]); on the OKID path the split-half or regression estimate
//! ([`crate::identify`]).
//!
//! **Signal length.** `e_k = mean_(i,j) (Y_k(i,j)/σ_i)²` is ~1 where `Y_k` is noise. The
//! response is *above the noise* up to the last `k` whose moving mean of `e` over
//! [`THRESHOLDS`]`.window` = 8 samples exceeds `above_noise_energy` = 4 (RMS above 2σ; a
//! false alarm needs a ~6σ excursion of the windowed mean). A noise floor of zero (noise-free
//! data) is replaced by `relative_floor` = `1e-8` of the peak, which leaves exact data exact.
//! On the pulse path the Hankel matrix spans `tail_factor` = 2 times that length (plus the
//! window, [`pulse_span`]): below `2σ` a decaying response still carries information through
//! its correlation along the Hankel anti-diagonals, and cutting it at the crossing biased
//! low-SNR damping (sim-stand plant, fn 12 Hz, ζ 0.7, 1 kHz, 4 pulses: ζ +12 % bias / 28 %
//! scatter cut at the crossing, +2 % / 11 % spanned twice; regression test
//! `hankel_cut_at_the_2_sigma_crossing_biases_low_snr_damping`). Much further, the Hankel
//! matrix would only add noise: a wide Hankel matrix over a long noise tail biases damping
//! upward.

use super::THRESHOLDS;
use crate::MarkovSeq;

/// Last Markov index `k >= 1` at which the response is above the noise, plus the window.
/// `noise[i]` is the Markov-parameter noise of output `i` (NaN or 0: unknown/none), scaled by
/// `growth[k]` at index `k` when `growth` is not empty (the width deconvolution's noise growth).
pub fn signal_length(markov: &MarkovSeq, noise: &[f64], growth: &[f64]) -> usize {
    let t = &THRESHOLDS;
    let (q, p, len) = (markov.outputs(), markov.inputs(), markov.len());
    if len < 2 {
        return 0;
    }
    let mut floor = [0.0f64; 64];
    for i in 0..q.min(64) {
        let peak = (1..len)
            .flat_map(|k| (0..p).map(move |j| (k, j)))
            .fold(0.0f64, |m, (k, j)| m.max(markov.get(k, i, j).abs()));
        let nz = noise
            .get(i)
            .copied()
            .filter(|v| v.is_finite())
            .unwrap_or(0.0);
        floor[i] = nz.max(t.relative_floor * peak).max(f64::MIN_POSITIVE);
    }
    let energy = |k: usize| -> f64 {
        let mut e = 0.0;
        for i in 0..q.min(64) {
            for j in 0..p {
                let g = growth.get(k).copied().unwrap_or(1.0).max(1.0);
                let z = markov.get(k, i, j) / (floor[i] * g);
                e += z * z;
            }
        }
        e / (q * p) as f64
    };
    let mut last = 0;
    for k in 1..len {
        let end = (k + t.window).min(len);
        let mean = (k..end).map(energy).sum::<f64>() / (end - k) as f64;
        if mean > t.above_noise_energy {
            last = k;
        }
    }
    if last == 0 {
        0
    } else {
        (last + t.window).min(len - 1)
    }
}

/// Markov blocks the pulse path's Hankel matrix spans for an above-noise length `signal`
/// (from [`signal_length`], which includes the window): `tail_factor` × the last index above
/// the noise, plus the window, at most `len − 1`; 0 stays 0 (no signal).
///
/// Only the pulse path stretches the span: there `σ` is measured independently of the response
/// (pre-pulse baselines) and the noise is white, so the stretch adds signal-bearing samples.
/// For given Markov parameters (OKID) the floor is the sequence's own tail RMS, which holds
/// unmodelled dynamics as well as noise, and a longer span raises the order instead.
pub fn pulse_span(signal: usize, len: usize) -> usize {
    let t = &THRESHOLDS;
    if signal == 0 {
        return 0;
    }
    let last = signal.saturating_sub(t.window).max(1);
    (t.tail_factor * last + t.window).min(len.saturating_sub(1))
}

/// Noise of given Markov parameters per output: RMS over the last quarter of the sequence.
pub fn tail_noise(markov: &MarkovSeq, out: &mut [f64]) {
    let (q, p, len) = (markov.outputs(), markov.inputs(), markov.len());
    let from = (3 * len / 4).max(1).min(len);
    for (i, o) in out.iter_mut().enumerate().take(q) {
        let mut ss = 0.0;
        let mut n = 0;
        for k in from..len {
            for j in 0..p {
                ss += markov.get(k, i, j).powi(2);
                n += 1;
            }
        }
        *o = if n > 0 {
            (ss / n as f64).sqrt()
        } else {
            f64::NAN
        };
    }
}

/// Noise of the pulse path's per-width averaged responses per output (`out`, one per output):
/// the output noise of the pre-pulse baselines `out_noise[i]` over `√w_min`, `w_min` the
/// smallest group weight (the noisiest averaged response, [`crate::grouped`]). Where that is
/// not finite (too few baselines), the tail RMS of `grouped` instead ([`tail_noise`]).
pub fn pulse_noise(out_noise: &[f64], weights: &[f64], grouped: &MarkovSeq, out: &mut [f64]) {
    let wmin = weights.iter().copied().fold(f64::INFINITY, f64::min);
    for c in 0..out.len() {
        out[c] = out_noise[c] / wmin.sqrt();
    }
    if out.iter().any(|v| !v.is_finite()) {
        tail_noise(grouped, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signal_length_stops_at_the_noise() {
        // 0.8^k above a noise floor of 1e-3: 0.8^k = 2e-3 at k ≈ 28.
        let data: Vec<f64> = (0..200).map(|k| 0.8f64.powi(k)).collect();
        let m = MarkovSeq::from_data(1, 1, data).unwrap();
        let n = signal_length(&m, &[1e-3], &[]);
        assert!((25..=40).contains(&n), "{n}");
        // Noise-free: down to 1e-8 of the peak, 0.8^k = 1e-8 at k ≈ 82.
        let n = signal_length(&m, &[0.0], &[]);
        assert!((80..=95).contains(&n), "{n}");
        // The pulse path spans it twice, never past the sequence.
        assert_eq!(pulse_span(30, 200), 2 * 30 - THRESHOLDS.window);
        assert_eq!(pulse_span(30, 50), 49);
        assert_eq!(pulse_span(0, 50), 0);
    }

    #[test]
    fn pulse_noise_falls_back_to_the_tail() {
        let data: Vec<f64> = (0..8).map(|k| if k >= 6 { 0.5 } else { 1.0 }).collect();
        let m = MarkovSeq::from_data(1, 1, data).unwrap();
        let mut out = [0.0];
        pulse_noise(&[0.4], &[4.0, 16.0], &m, &mut out);
        assert_eq!(out[0], 0.2);
        pulse_noise(&[f64::NAN], &[4.0], &m, &mut out);
        assert_eq!(out[0], 0.5);
    }
}
