//! Noise floor, Hankel size and model order.
//!
//! **Signal length.** With `σ_i` the noise standard deviation of the averaged Markov parameters
//! of output `i` (from the pre-pulse baselines, [`crate::pulses`]; for given Markov
//! parameters, the RMS of the last quarter of the sequence), `e_k = mean_(i,j) (Y_k(i,j)/σ_i)²`
//! is ~1 where `Y_k` is noise. The response is *above the noise* up to the last `k` whose
//! moving mean of `e` over [`WINDOW`] samples exceeds 4 (RMS above 2σ; a false alarm needs a
//! ~6σ excursion of the windowed mean). A noise floor of zero (noise-free data) is replaced by
//! `1e-8` of the peak, which leaves exact data exact. On the pulse path the Hankel matrix
//! spans [`TAIL_FACTOR`] = 2 times that length (plus the window, [`pulse_span`]): below `2σ` a decaying response
//! still carries information through its correlation along the Hankel anti-diagonals, and
//! cutting it at the crossing biased low-SNR damping (sim-stand plant, fn 12 Hz, ζ 0.7,
//! 1 kHz, 4 pulses: ζ +12 % bias / 28 % scatter cut at the crossing, +2 % / 11 % spanned
//! twice; regression test `hankel_cut_at_the_2_sigma_crossing_biases_low_snr_damping`).
//! Much further, the Hankel matrix would only add noise: a wide Hankel matrix over a long
//! noise tail biases damping upward.
//!
//! **Hankel size.** `H(1)` reaches `Y_{r+c}`, so `r + c` blocks are split near-square
//! (`r q ≈ c p`) over the signal length, at least the minimum the order needs and at most
//! what the record and the workspace hold. A 4 × 4 Hankel matrix is useless on noisy data:
//! the SVD's noise averaging grows with the matrix size.
//!
//! **Order.** A random `m × n` matrix of independent entries of standard deviation `σ` has
//! largest singular value about `σ(√m + √n)`; singular values of `H(0)` above
//! `NOISE_SV_FACTOR · σ(√m + √n)` (and above `1e-9 σ_1` for rounding) carry signal. The order is
//! their count, capped at the workspace's maximum order.

use super::hankel::HankelDims;
use super::{IdentError, MarkovSeq};

/// Moving window (samples) for the signal-length test.
pub const WINDOW: usize = 8;

/// On the pulse path the Hankel matrix spans this multiple of the above-noise length.
pub const TAIL_FACTOR: usize = 2;

/// Relative floor replacing a zero noise estimate.
pub const RELATIVE_FLOOR: f64 = 1e-8;

/// Margin on the random-matrix noise singular value `σ(√m + √n)`.
pub const NOISE_SV_FACTOR: f64 = 1.5;

/// Singular values below this fraction of `σ_1` are rounding.
pub const RANK_TOL: f64 = 1e-9;

/// Last Markov index `k >= 1` at which the response is above the noise, plus the window.
/// `noise[i]` is the Markov-parameter noise of output `i` (NaN or 0: unknown/none), scaled by
/// `growth[k]` at index `k` when `growth` is not empty (the width deconvolution's noise growth).
pub fn signal_length(markov: &MarkovSeq, noise: &[f64], growth: &[f64]) -> usize {
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
        floor[i] = nz.max(RELATIVE_FLOOR * peak).max(f64::MIN_POSITIVE);
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
        let end = (k + WINDOW).min(len);
        let mean = (k..end).map(energy).sum::<f64>() / (end - k) as f64;
        if mean > 4.0 {
            last = k;
        }
    }
    if last == 0 {
        0
    } else {
        (last + WINDOW).min(len - 1)
    }
}

/// Markov blocks the pulse path's Hankel matrix spans for an above-noise length `signal`
/// (from [`signal_length`], which includes the window): [`TAIL_FACTOR`] × the last index above
/// the noise, plus the window, at most `len − 1`; 0 stays 0 (no signal).
///
/// Only the pulse path stretches the span: there `σ` is measured independently of the response
/// (pre-pulse baselines) and the noise is white, so the stretch adds signal-bearing samples.
/// For given Markov parameters (OKID) the floor is the sequence's own tail RMS, which holds
/// unmodelled dynamics as well as noise, and a longer span raises the order instead.
pub fn pulse_span(signal: usize, len: usize) -> usize {
    if signal == 0 {
        return 0;
    }
    let last = signal.saturating_sub(WINDOW).max(1);
    (TAIL_FACTOR * last + WINDOW).min(len.saturating_sub(1))
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

/// Near-square Hankel dimensions over `signal` blocks, at least `min_rows × min_cols`
/// (scalar), within `avail` usable blocks (`Y_1 .. Y_avail`) and the workspace's maxima.
pub fn hankel_dims(
    q: usize,
    p: usize,
    avail: usize,
    signal: usize,
    min_size: usize,
    max_r: usize,
    max_c: usize,
) -> Result<HankelDims, IdentError> {
    let r_min = min_size.div_ceil(q).max(1);
    let c_min = min_size.div_ceil(p).max(1);
    if r_min > max_r || c_min > max_c {
        return Err(IdentError::LimitsExceeded {
            what: "Hankel block rows/columns for this order",
            value: r_min.max(c_min),
            limit: max_r.min(max_c),
        });
    }
    if avail < r_min + c_min {
        return Err(IdentError::RecordTooShort {
            needed: r_min + c_min + 1,
            available: avail + 1,
        });
    }
    let n_use = signal.clamp(r_min + c_min, avail);
    let r = ((n_use * p) as f64 / (p + q) as f64).round() as usize;
    let r = r.clamp(r_min, n_use - c_min).min(max_r);
    let c = (n_use - r).min(max_c);
    Ok(HankelDims { q, p, r, c })
}

/// Checks explicit block counts against the data and the workspace.
pub fn explicit_dims(
    q: usize,
    p: usize,
    r: usize,
    c: usize,
    avail: usize,
    max_r: usize,
    max_c: usize,
) -> Result<HankelDims, IdentError> {
    if r == 0 || c == 0 {
        return Err(IdentError::InvalidInput(
            "Hankel block rows and columns must be >= 1",
        ));
    }
    if r > max_r || c > max_c {
        return Err(IdentError::LimitsExceeded {
            what: "Hankel block rows/columns",
            value: r.max(c),
            limit: max_r.min(max_c),
        });
    }
    if r + c > avail {
        return Err(IdentError::RecordTooShort {
            needed: r + c + 1,
            available: avail + 1,
        });
    }
    Ok(HankelDims { q, p, r, c })
}

/// The largest singular value expected from noise alone. For white Markov noise (one-sample
/// pulses, `growth` empty or all ones) `NOISE_SV_FACTOR · σ (√rows + √cols)`. After the
/// deconvolution of wider pulses the noise is a random walk (strongly correlated), whose
/// Hankel matrix concentrates its energy in a few singular values; then the bound is the
/// Frobenius norm of the noise Hankel, `σ √(Σ_(a,b) q p g²_{a+b+1})`.
pub fn noise_singular_value(sigma_markov: f64, dims: &HankelDims, growth: &[f64]) -> f64 {
    let white = NOISE_SV_FACTOR
        * sigma_markov
        * ((dims.rows() as f64).sqrt() + (dims.cols() as f64).sqrt());
    if growth.iter().all(|g| *g <= 1.0 + 1e-12) {
        return white;
    }
    let mut fro2 = 0.0;
    for a in 0..dims.r {
        for b in 0..dims.c {
            let g = growth.get(a + b + 1).copied().unwrap_or(1.0);
            fro2 += g * g;
        }
    }
    white.max(sigma_markov * (fro2 * (dims.q * dims.p) as f64).sqrt())
}

/// Count of singular values above the noise and rounding floors, capped at `max_order`.
pub fn auto_order(sigma: &[f64], noise_sv: f64, max_order: usize) -> usize {
    let first = sigma.first().copied().unwrap_or(0.0);
    let floor = noise_sv.max(RANK_TOL * first);
    sigma
        .iter()
        .take_while(|s| **s > floor)
        .count()
        .min(max_order)
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
        assert_eq!(pulse_span(30, 200), 2 * 30 - WINDOW);
        assert_eq!(pulse_span(30, 50), 49);
        assert_eq!(pulse_span(0, 50), 0);
    }

    #[test]
    fn dims_are_near_square_and_checked() {
        let d = hankel_dims(1, 1, 500, 100, 3, 64, 64).unwrap();
        assert_eq!((d.r, d.c), (50, 50));
        let d = hankel_dims(2, 1, 500, 90, 3, 64, 64).unwrap();
        assert_eq!((d.r, d.c), (30, 60));
        let d = hankel_dims(1, 1, 500, 400, 3, 64, 64).unwrap();
        assert_eq!((d.r, d.c), (64, 64));
        assert!(matches!(
            hankel_dims(1, 1, 4, 4, 3, 64, 64),
            Err(IdentError::RecordTooShort { .. })
        ));
        assert_eq!(auto_order(&[10.0, 5.0, 0.01, 0.009], 0.1, 8), 2);
        assert_eq!(auto_order(&[10.0, 5.0, 1e-12], 0.0, 8), 2);
    }
}
