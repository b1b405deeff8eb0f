//! Observer/Kalman filter identification (OKID): Markov parameters from arbitrary input.
//!
//! Juang, Phan, Horta & Longman, "Identification of observer/Kalman filter Markov parameters:
//! theory and experiments", J. Guidance, Control, and Dynamics 16(2), 1993 (and NASA TM-104069).
//!
//! # The observer model
//!
//! For `x_{k+1} = A x_k + B u_k`, `y_k = C x_k + D u_k` (q outputs, p inputs) add and subtract
//! `G y_k` with an observer gain `G`:
//!
//! ```text
//! x_{k+1} = Ā x_k + B̄ v_k,   Ā = A + G C,   B̄ = [B + G D, −G],   v_k = [u_k; y_k]
//! ```
//!
//! If `Ā` is nilpotent after `ℓ` steps (a deadbeat observer, possible whenever `ℓ·q ≥ n` for an
//! observable system), the state is a linear function of the last `ℓ` inputs and outputs and
//!
//! ```text
//! y_k = D u_k + Σ_{i=1..ℓ} Ȳ_i v_{k−i},   Ȳ_i = C Ā^(i−1) B̄ = [Ȳ_i⁽¹⁾, −Ȳ_i⁽²⁾]      (JPHL eq. 7)
//! ```
//!
//! holds exactly for every `k ≥ ℓ`, whatever the initial state. With noise, the least-squares
//! estimate of the observer Markov parameters `Ȳ_i` approaches those of the steady-state Kalman
//! filter as `ℓ` grows (JPHL §IV); the truncation at finite `ℓ` is the source of the bias seen
//! with output noise (tests document its size).
//!
//! # Least squares and recovery
//!
//! One regression row per sample, solved by a streaming QR and a truncated SVD
//! ([`regression`], which also gives the noise of the Markov parameters); the system Markov
//! parameters follow from the observer ones (JPHL eqs. 11–13, [`recovery`]).
//!
//! # Choosing `ℓ`
//!
//! `ℓ_max = clamp(⌊N / (10 (p+q))⌋, 1, 40)` follows from the data length (at least ten rows per
//! parameter). A row needs its whole window of `ℓ` lags: where lost samples leave too few whole
//! windows at that order (fewer than two rows a parameter), the automatic `ℓ_max` falls to the
//! largest order the same rule allows on the rows usable at it ([`gap_observer_order`]); an
//! order the caller gives is kept (and refused when too few rows remain). Because the columns
//! are ordered by lag, the regression with `ℓ ≤ ℓ_max` lags uses a
//! *prefix* of the columns, so one QR serves every `ℓ`: `R_φ` is the leading `m(ℓ) × m(ℓ)` block
//! with `m(ℓ) = 1 + p + (p+q)ℓ`, and `RSS(ℓ) = ‖z_{m(ℓ):}‖² + ‖R_res‖²`. The number used is
//! chosen by output (simulation) error over a set of candidates ([`observer`]). Too many lags are
//! not harmless: with a band-limited input (a chirp, a multisine) the lagged input columns are
//! numerically dependent, and with few steps and noise the extra parameters fit the noise; in
//! both cases the recovered Markov parameters drift while the one-step fit still improves.

pub mod recovery;
pub mod regression;

use recovery::recover_markov;
use regression::{solve_truncated, streaming_qr, unscale, Scaled};

use crate::order::observer;

/// Largest automatically chosen number of observer Markov parameters.
pub const MAX_AUTO_OBSERVER_ORDER: usize = 40;
/// Default relative singular-value threshold of the truncated-SVD solve.
pub const DEFAULT_RCOND: f64 = 1e-10;
/// Default significance threshold (in residual standard deviations) of the solve.
pub const DEFAULT_SIGNIFICANCE: f64 = 0.0;

/// Why OKID refused the data.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OkidError {
    /// No input or no output channel was given.
    #[error("OKID needs at least one input and one output channel")]
    NoChannels,
    /// Channels of different lengths.
    #[error("channel lengths differ: {first} and {other} samples")]
    LengthMismatch {
        /// Length of the first input.
        first: usize,
        /// Length of the offending channel.
        other: usize,
    },
    /// A NaN or infinite value at a sample that is not marked missing.
    #[error("{what} channel {channel} has a non-finite value at sample {sample} that is not marked missing")]
    NonFinite {
        /// "input" or "output".
        what: &'static str,
        /// Channel index.
        channel: usize,
        /// Sample index.
        sample: usize,
    },
    /// Too few usable regression rows for the number of parameters.
    #[error("record too short for OKID: {rows} usable rows for {params} parameters per output (need at least {need})")]
    TooShort {
        /// Usable regression rows.
        rows: usize,
        /// Parameters per output.
        params: usize,
        /// Rows needed.
        need: usize,
    },
    /// An output channel does not vary.
    #[error("output channel {0} is constant: nothing to identify")]
    ConstantOutput(usize),
    /// An input channel does not vary.
    #[error("input channel {0} is constant: it does not excite the system")]
    ConstantInput(usize),
    /// The requested observer order is zero.
    #[error("the number of observer Markov parameters must be at least 1")]
    ZeroObserverOrder,
    /// The least-squares solution came out non-finite (should not happen; reported, not returned).
    #[error("OKID least squares produced a non-finite value")]
    NonFiniteSolution,
}

/// Options of [`okid`]. `Default` chooses everything automatically.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OkidOptions {
    /// Number `ℓ` of observer Markov parameters; `None` = [`auto_observer_order`].
    pub observer_order: Option<usize>,
    /// Number of system Markov parameters `Y_0 .. Y_{L−1}` to return; `None` = [`auto_markov_len`].
    pub markov_len: Option<usize>,
    /// Relative singular-value threshold of the truncated-SVD solve.
    pub rcond: f64,
    /// Significance threshold `τ` of the solve: a direction whose data projection
    /// `|u_iᵀ Qᵀ y|` is below `τ σ_e` is dropped (0 keeps every direction above `rcond`).
    pub significance: f64,
}

impl Default for OkidOptions {
    fn default() -> Self {
        Self {
            observer_order: None,
            markov_len: None,
            rcond: DEFAULT_RCOND,
            significance: DEFAULT_SIGNIFICANCE,
        }
    }
}

/// The system Markov parameters OKID recovered, and how the regression went.
#[derive(Debug, Clone, PartialEq)]
pub struct OkidResult {
    /// Outputs.
    pub q: usize,
    /// Inputs.
    pub p: usize,
    /// Number of blocks `Y_0 .. Y_{len−1}`.
    pub len: usize,
    /// Blocks in the project layout (block `k` at `k*q*p`, column-major inside).
    pub markov: Vec<f64>,
    /// Number `ℓ` of observer Markov parameters used.
    pub observer_order: usize,
    /// Largest number considered (from the data length, or the one given).
    pub observer_order_max: usize,
    /// True when `ℓ` was chosen by output error ([`observer`]), false when it was given.
    pub observer_order_chosen: bool,
    /// Regression rows used.
    pub rows: usize,
    /// Rows skipped because their window touched a missing sample.
    pub rows_skipped: usize,
    /// Parameters per output (`p(ℓ+1) + qℓ + 1`).
    pub params: usize,
    /// `σ_max / σ_min` of the scaled regressor (`σ_min` floored at `σ_max·ε`, so always finite).
    pub condition: f64,
    /// Numerical rank kept by the truncated SVD.
    pub rank: usize,
    /// True when directions were dropped (rank < params).
    pub regularised: bool,
    /// RMS of the one-step-ahead residual of the observer model, per output, in output units.
    pub residual_rms: Vec<f64>,
    /// Standard error of the Markov parameters per output (see the module docs), output units
    /// per input unit (averaged over inputs).
    pub markov_noise: Vec<f64>,
}

impl OkidResult {
    /// Block `Y_k` element (output `i`, input `j`).
    pub fn at(&self, k: usize, i: usize, j: usize) -> f64 {
        self.markov[k * self.q * self.p + i + j * self.q]
    }
}

/// The largest number of observer Markov parameters considered for `n` samples, `p` inputs,
/// `q` outputs: `ℓ_max = clamp(⌊n / (10 (p + q))⌋, 1, 40)`, so that there are at least ten
/// regression rows per parameter, enough lags for a deadbeat observer of any order up to `40·q`,
/// and a bounded cost (`O(N·ℓ²(p+q)²)`). The number used is chosen below it ([`observer`]).
pub fn auto_observer_order(n: usize, p: usize, q: usize) -> usize {
    (n / (10 * (p + q).max(1))).clamp(1, MAX_AUTO_OBSERVER_ORDER)
}

/// Rows of the regression with `ell` lags over `n` samples: the samples `k ≥ ℓ` whose window
/// `k − ℓ ..= k` misses nothing.
pub fn usable_rows(n: usize, ell: usize, is_missing: &impl Fn(usize) -> bool) -> usize {
    let mut run = 0usize;
    (0..n)
        .filter(|&k| {
            run = if is_missing(k) { 0 } else { run + 1 };
            k >= ell && run > ell
        })
        .count()
}

/// The automatic order when gaps leave too few whole windows at `ell_max`: the largest
/// `ℓ < ell_max` that [`auto_observer_order`]'s rule allows on the rows usable at it (ten rows a
/// parameter: `usable(ℓ) + ℓ ≥ 10 (p + q) ℓ`, where without a gap `usable(ℓ) + ℓ = n`); `None`
/// when not even `ℓ = 1` is. Randomly lost samples (a share `s`) keep a window of `ℓ + 1` whole
/// with probability `(1 − s)^(ℓ+1)`: a 50 Hz staircase export whose load cell lost 46 of its
/// 800 readings had 46 whole windows at `ℓ = 40`, where 82 parameters need 164 rows; the order
/// falls to 14.
pub fn gap_observer_order(
    n: usize,
    p: usize,
    q: usize,
    ell_max: usize,
    is_missing: &impl Fn(usize) -> bool,
) -> Option<usize> {
    (1..ell_max)
        .rev()
        .find(|&ell| usable_rows(n, ell, is_missing) + ell >= 10 * (p + q) * ell)
}

/// The automatic number of system Markov parameters to return: `clamp(N/2, 2ℓ + 2, 1024)`
/// (ERA sizes its Hankel from these and cuts where they sink into the noise floor).
pub fn auto_markov_len(n: usize, observer_order: usize) -> usize {
    (n / 2).clamp(2 * observer_order + 2, 1024)
}

/// Identifies the system Markov parameters from inputs `u` (p channels) and outputs `y`
/// (q channels) of equal length, sampled uniformly. `missing[k]` (optional) marks samples that
/// were not measured; every other value must be finite. See the module docs for the method.
pub fn okid(
    u: &[&[f64]],
    y: &[&[f64]],
    missing: Option<&[bool]>,
    opts: &OkidOptions,
) -> Result<OkidResult, OkidError> {
    let (p, q) = (u.len(), y.len());
    if p == 0 || q == 0 {
        return Err(OkidError::NoChannels);
    }
    let n = check_lengths(u, y, missing)?;
    let is_missing = |k: usize| missing.is_some_and(|m| m[k]);
    check_finite(u, "input", &is_missing)?;
    check_finite(y, "output", &is_missing)?;
    let mut ell_max = opts.observer_order.unwrap_or(auto_observer_order(n, p, q));
    if ell_max == 0 {
        return Err(OkidError::ZeroObserverOrder);
    }
    let u_stats = channel_stats(u, &is_missing);
    let y_stats = channel_stats(y, &is_missing);
    if let Some(j) = u_stats.iter().position(|s| s.1 == 0.0) {
        return Err(OkidError::ConstantInput(j));
    }
    if let Some(i) = y_stats.iter().position(|s| s.1 == 0.0) {
        return Err(OkidError::ConstantOutput(i));
    }
    let scaled = Scaled {
        u,
        y,
        u_stats: &u_stats,
        y_stats: &y_stats,
        ell: ell_max,
    };
    let mut params_max = params_for(p, q, ell_max);
    let (mut r_aug, mut rows, mut rows_skipped) = streaming_qr(&scaled, n, params_max, &is_missing);
    let mut need = 2 * params_max;
    if rows < need && opts.observer_order.is_none() {
        // Gaps leave too few rows whose window is whole: the automatic order by the rule of
        // [`auto_observer_order`] on the rows usable at it ([`gap_observer_order`]).
        if let Some(ell) = gap_observer_order(n, p, q, ell_max, &is_missing) {
            ell_max = ell;
            params_max = params_for(p, q, ell);
            need = 2 * params_max;
            let scaled = Scaled { ell, ..scaled };
            (r_aug, rows, rows_skipped) = streaming_qr(&scaled, n, params_max, &is_missing);
        }
    }
    let scaled = Scaled {
        ell: ell_max,
        ..scaled
    };
    if rows < need {
        return Err(OkidError::TooShort {
            rows,
            params: params_max,
            need,
        });
    }
    let fit = |ell: usize| {
        let params = params_for(p, q, ell);
        let solve = solve_truncated(&r_aug, (p, q), params, params_max, rows, opts);
        let theta = unscale(&solve.theta, &scaled, ell);
        let finite = theta.0.iter().chain(&theta.1).all(|v| v.is_finite());
        (params, solve, theta, finite)
    };
    let ell = match opts.observer_order {
        Some(given) => given,
        None => {
            let scores: Vec<(usize, f64)> = observer::candidates(ell_max)
                .into_iter()
                .map(|ell| {
                    let (_, _, theta, finite) = fit(ell);
                    let s = observer::output_error((&theta.0, &theta.1), (p, q, ell), u, y);
                    (ell, if finite { s } else { f64::NAN })
                })
                .collect();
            observer::pick(&scores).unwrap_or(ell_max)
        }
    };
    let (params, solve, theta, finite) = fit(ell);
    let len = opts.markov_len.unwrap_or(auto_markov_len(n, ell)).max(1);
    let markov = recover_markov(&theta, p, q, ell, len);
    if !finite || markov.iter().any(|v| !v.is_finite()) {
        return Err(OkidError::NonFiniteSolution);
    }
    let residual_rms: Vec<f64> = (0..q)
        .map(|i| solve.residual_scaled[i] * y_stats[i].1 / (rows as f64).sqrt())
        .collect();
    let u_scale = (u_stats.iter().map(|s| s.1 * s.1).sum::<f64>() / p as f64).sqrt();
    let markov_noise = residual_rms
        .iter()
        .map(|r| r * solve.input_var_factor.sqrt() / u_scale)
        .collect();
    Ok(OkidResult {
        q,
        p,
        len,
        markov,
        observer_order: ell,
        observer_order_max: ell_max,
        observer_order_chosen: opts.observer_order.is_none(),
        rows,
        rows_skipped,
        params,
        condition: solve.condition,
        rank: solve.rank,
        regularised: solve.rank < params || solve.dropped_any,
        residual_rms,
        markov_noise,
    })
}

/// Regression columns for `ℓ` lags: the intercept, `u_k`, and `(u, y)` at each lag.
fn params_for(p: usize, q: usize, ell: usize) -> usize {
    1 + p + (p + q) * ell
}

fn check_lengths(u: &[&[f64]], y: &[&[f64]], missing: Option<&[bool]>) -> Result<usize, OkidError> {
    let n = u[0].len();
    let others = u.iter().chain(y).map(|c| c.len());
    let others = others.chain(missing.map(|m| m.len()));
    for other in others {
        if other != n {
            return Err(OkidError::LengthMismatch { first: n, other });
        }
    }
    Ok(n)
}

fn check_finite(
    chans: &[&[f64]],
    what: &'static str,
    is_missing: &impl Fn(usize) -> bool,
) -> Result<(), OkidError> {
    for (channel, c) in chans.iter().enumerate() {
        if let Some(sample) = (0..c.len()).find(|&k| !is_missing(k) && !c[k].is_finite()) {
            return Err(OkidError::NonFinite {
                what,
                channel,
                sample,
            });
        }
    }
    Ok(())
}

/// (mean, standard deviation) of each channel over the samples not missing.
fn channel_stats(chans: &[&[f64]], is_missing: &impl Fn(usize) -> bool) -> Vec<(f64, f64)> {
    chans
        .iter()
        .map(|c| {
            let vals = || (0..c.len()).filter(|&k| !is_missing(k)).map(|k| c[k]);
            let count = vals().count().max(1) as f64;
            let mean = vals().sum::<f64>() / count;
            let var = vals().map(|v| (v - mean) * (v - mean)).sum::<f64>() / count;
            let sd = var.sqrt();
            // A spread at rounding level of the mean is no variation at all.
            let sd = if sd <= mean.abs() * 1e-14 { 0.0 } else { sd };
            (mean, sd)
        })
        .collect()
}
