//! How many block rows `r` and block columns `c` ERA's Hankel matrix `H(0)` gets.
//!
//! `H(0)` and `H(1)` use `Y_1 .. Y_{r+c}` (Juang & Pappa 1985, eq. 4; [`crate::hankel`]), so a
//! sequence `Y_0 .. Y_{L−1}` allows `r + c ≤ L − 1`. The rank bound `min(r q, c p)` is largest
//! for the near-square split `r q ≈ c p`, `r = round(n_use p / (p + q))`, and square Hankel
//! matrices give the least biased and least scattered damping under noise (issue 6).
//!
//! - **Automatic** ([`auto_dims`]): `r + c` blocks split near-square over the above-noise
//!   length ([`super::noise_floor`]; how far past the noise crossing: [`Span`]), at least the
//!   minimum the order needs (`min_hankel_size` scalar rows and columns, `n + 1` for a given
//!   order `n`) and at most what the record and the workspace hold. A 4 × 4 Hankel matrix is
//!   useless on noisy data: the SVD's noise averaging grows with the matrix size.
//! - **Square** ([`square_blocks`]): the largest near-square Hankel the whole sequence allows.
//! - **Explicit** ([`explicit_dims`]): given block counts, checked.

use super::noise_floor::{pulse_span, signal_length};
use super::THRESHOLDS;
use crate::hankel::HankelDims;
use crate::{IdentError, MarkovSeq};

/// How ERA's Hankel matrix is sized (`propid identify --hankel auto|square|RxC`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HankelSize {
    /// From the noise floor ([`auto_dims`]), at most the default
    /// [`crate::workspace::Limits`] blocks.
    #[default]
    Auto,
    /// The largest near-square Hankel the Markov sequence `Y_0 .. Y_{L−1}` allows
    /// ([`square_blocks`]): `r = c = ⌊(L − 1)/2⌋` blocks for one input and one output.
    Square,
    /// Explicit block rows and columns `(r, c)`.
    Blocks(usize, usize),
}

/// How far the automatic Hankel span reaches, by where the noise floor came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Span {
    /// Pulse path: `σ` measured independently (pre-pulse baselines), white noise: the span is
    /// stretched past the noise crossing ([`pulse_span`]).
    PulseTail,
    /// Given Markov parameters: up to the noise crossing; none above the noise is an error.
    AboveNoise,
    /// OKID path: up to the noise crossing, at least `okid_min_span` blocks.
    OkidFloor,
}

/// Automatic Hankel dimensions of `markov` against the noise `noise` (per output; `growth` as
/// in [`signal_length`]), for a given `order` (or `None`: chosen later), within `max`
/// `(block rows, block cols)`.
pub fn auto_dims(
    markov: &MarkovSeq,
    noise: &[f64],
    growth: &[f64],
    span: Span,
    order: Option<usize>,
    max: (usize, usize),
) -> Result<HankelDims, IdentError> {
    let (q, p, len) = (markov.outputs(), markov.inputs(), markov.len());
    let avail = len.saturating_sub(1);
    let signal = signal_length(markov, noise, growth);
    let signal = match span {
        Span::PulseTail => pulse_span(signal, len),
        Span::AboveNoise => signal,
        Span::OkidFloor => signal.max(THRESHOLDS.okid_min_span),
    };
    if signal == 0 {
        return Err(IdentError::RankDeficient {
            rank: 0,
            order: order.unwrap_or(0),
        });
    }
    let min_size = order.map_or(THRESHOLDS.min_hankel_size, |n| n + 1);
    hankel_dims(q, p, avail, signal, min_size, max.0, max.1)
}

/// Near-square Hankel dimensions over `signal` blocks, at least `min_size` scalar rows and
/// columns, within `avail` usable blocks (`Y_1 .. Y_avail`) and the workspace's maxima.
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

/// Checks explicit block counts `(r, c)` against the `avail` usable blocks and the workspace's
/// maxima.
pub fn explicit_dims(
    q: usize,
    p: usize,
    (r, c): (usize, usize),
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

/// Block counts `(r, c)` of the largest near-square Hankel from `len` Markov blocks with `q`
/// outputs and `p` inputs: `H(0)` and `H(1)` use `Y_1 .. Y_{r+c}`, so `r + c = L − 1`, and
/// `r q ≈ c p` (the split that maximises the rank bound `min(r q, c p)`), i.e.
/// `r = round((L − 1) p / (p + q))`. Every dimension is at least one block.
pub fn square_blocks(len: usize, q: usize, p: usize) -> Result<(usize, usize), IdentError> {
    let avail = len.saturating_sub(1);
    let (q, p) = (q.max(1), p.max(1));
    if avail < 2 {
        return Err(IdentError::RecordTooShort {
            needed: 3,
            available: len,
        });
    }
    let r = ((avail * p) as f64 / (p + q) as f64).round() as usize;
    let r = r.clamp(1, avail - 1);
    Ok((r, avail - r))
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!(matches!(
            explicit_dims(1, 1, (3, 3), 5, 64, 64),
            Err(IdentError::RecordTooShort { .. })
        ));
        assert!(matches!(
            explicit_dims(1, 1, (0, 3), 50, 64, 64),
            Err(IdentError::InvalidInput(_))
        ));
        assert_eq!(square_blocks(101, 1, 1).unwrap(), (50, 50));
        assert_eq!(square_blocks(91, 2, 1).unwrap(), (30, 60));
        assert!(square_blocks(2, 1, 1).is_err());
    }

    #[test]
    fn spans_differ_only_past_the_noise_crossing() {
        // 0.8^k over a noise floor of 1e-3: above the noise up to k ≈ 28 (+ window).
        let data: Vec<f64> = (0..400).map(|k| 0.8f64.powi(k)).collect();
        let m = MarkovSeq::from_data(1, 1, data).unwrap();
        let at = |span| auto_dims(&m, &[1e-3], &[], span, None, (128, 128)).unwrap();
        let (plain, okid, pulse) = (
            at(Span::AboveNoise),
            at(Span::OkidFloor),
            at(Span::PulseTail),
        );
        assert_eq!(plain, okid);
        assert!(pulse.r + pulse.c > plain.r + plain.c, "{pulse:?} {plain:?}");
        // Nothing above a huge floor: an error, except on the OKID path's minimum span.
        let none = auto_dims(&m, &[1e3], &[], Span::AboveNoise, None, (128, 128));
        assert!(matches!(none, Err(IdentError::RankDeficient { .. })));
        let okid = auto_dims(&m, &[1e3], &[], Span::OkidFloor, None, (128, 128)).unwrap();
        assert_eq!(okid.r + okid.c, THRESHOLDS.okid_min_span);
    }
}
