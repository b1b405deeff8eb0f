//! One entry for any excitation: the pulse path for a clean pulse experiment, OKID otherwise.
//!
//! A record is a **clean pulse experiment** when it has one input, device pulse starts (EVENT
//! IMPULSE_START) or an input that is piecewise constant (the input holds its previous value
//! on at least half of the samples: levels, pulses and the ramps between levels of a stand's
//! experiment plan, but not random, chirp or multisine input, whose rare equal neighbours could
//! look like pulses) or a ramped staircase (flat levels on at least half of the samples;
//! [`looks_like_pulses`]), and the pulse path of the core finds and keeps at least one pulse in
//! it. Everything else (random, chirp, multisine, steps,
//! staircases, ramps, several inputs) goes through [`okid`](super::okid) and then ERA on the
//! recovered Markov parameters ([`Workspace::identify_markov`]). The path taken is reported.
//!
//! **Hankel size and order on the OKID path.** The recovered sequence is smooth (it is the pulse
//! response of the fitted observer model), so the RMS of its tail says nothing about how well it
//! is known. The noise floor used instead is measured by **split halves**: OKID with the same
//! `ℓ` on the first and on the second half of the record gives two independent estimates, and
//! `σ = RMS(Y_a − Y_b) / 2` over the first `max(64, 2ℓ)` blocks (each half has twice the
//! variance of the whole, the difference four times). It includes what a formula would miss:
//! drift, a change of operating point. It is inflated when the halves are excited differently
//! (a sine sweep: low frequencies in one half, high in the other), while OKID's regression
//! standard error ([`OkidResult::markov_noise`]) is inflated by collinear input lags (slow
//! inputs). Each overstates the noise for a known reason, so the smaller of the two is used
//! (the regression one alone when a half cannot be identified). The Hankel size follows from where the sequence sinks below
//! it ([`sizing::signal_length`], [`sizing::hankel_dims`]), and the order from the singular
//! values above `NOISE_SV_FACTOR · σ (√rows + √cols)` ([`sizing::noise_singular_value`],
//! [`sizing::auto_order`]), the same rules as the pulse path with this σ.

use serde::Serialize;

use super::{okid, OkidError, OkidOptions, OkidResult};
use crate::hankel::HankelDims;
use crate::pulses::PulseInput;
use crate::report::Gain;
use crate::sizing;
use crate::workspace::{IdentOptions, Limits, Workspace};
use crate::{IdentError, MarkovSeq, ModelReport};

/// Which way the Markov parameters were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PathTaken {
    /// Pulses segmented and ensemble-averaged (core::pulses).
    Pulse,
    /// Observer/Kalman filter identification from arbitrary input.
    Okid,
}

/// How the OKID regression went (published beside the model).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OkidSummary {
    /// Observer Markov parameters `ℓ` used.
    pub observer_order: usize,
    /// Largest `ℓ` considered.
    pub observer_order_max: usize,
    /// `"output_error"` when chosen, `"given"` otherwise.
    pub observer_order_from: &'static str,
    /// Regression rows used.
    pub rows: usize,
    /// Rows skipped (missing samples in their window).
    pub rows_skipped: usize,
    /// Parameters per output.
    pub params: usize,
    /// Condition number of the scaled regressor.
    pub condition: f64,
    /// Numerical rank kept.
    pub rank: usize,
    /// True when the truncated SVD dropped directions.
    pub regularised: bool,
    /// One-step residual RMS per output, output units.
    pub residual_rms: Vec<f64>,
    /// System Markov parameters recovered and handed to ERA.
    pub markov_len: usize,
    /// Noise of the Markov parameters per output (the floor for Hankel size and order).
    pub markov_noise: Vec<f64>,
    /// `"split_half"` or `"regression"`: the smaller estimate (see the module docs).
    pub markov_noise_from: &'static str,
}

impl From<&OkidResult> for OkidSummary {
    fn from(r: &OkidResult) -> Self {
        Self {
            observer_order: r.observer_order,
            observer_order_max: r.observer_order_max,
            observer_order_from: if r.observer_order_chosen {
                "output_error"
            } else {
                "given"
            },
            rows: r.rows,
            rows_skipped: r.rows_skipped,
            params: r.params,
            condition: r.condition,
            rank: r.rank,
            regularised: r.regularised,
            residual_rms: r.residual_rms.clone(),
            markov_len: r.len,
            markov_noise: r.markov_noise.clone(),
            markov_noise_from: "regression",
        }
    }
}

/// A model from any excitation.
#[derive(Debug, Clone, PartialEq)]
pub struct AnyModel {
    /// The published model.
    pub report: ModelReport,
    /// The path taken.
    pub path: PathTaken,
    /// The OKID regression, when that path was taken.
    pub okid: Option<OkidSummary>,
}

/// Why neither path gave a model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnyError {
    /// The OKID regression refused the data.
    #[error("OKID: {0}")]
    Okid(#[from] OkidError),
    /// ERA (or the pulse path) refused the data.
    #[error("{0}")]
    Ident(#[from] IdentError),
    /// The identification ran but its model has non-finite entries: the data (too short, too
    /// little excitation) cannot support it. Never published as a model.
    #[error(
        "the identified model is not finite ({what}): the record is too short or not exciting \
         enough{}; use a longer record or a lower --order",
        condition.map_or(String::new(), |c| format!(" (OKID regression condition {c:.1e})"))
    )]
    NonFiniteModel {
        /// Which part of the model is not finite.
        what: &'static str,
        /// Condition number of the OKID regression, when that path was taken.
        condition: Option<f64>,
    },
}

/// The record to identify, borrowed: `u` inputs and `y` outputs of equal length.
#[derive(Debug, Clone, Copy)]
pub struct AnyInput<'a> {
    /// Sample period, seconds.
    pub dt_s: f64,
    /// Inputs (throttle first).
    pub u: &'a [&'a [f64]],
    /// Outputs.
    pub y: &'a [&'a [f64]],
    /// Missing samples (empty: none).
    pub missing: &'a [bool],
    /// Device pulse starts, if any.
    pub pulse_starts: Option<&'a [usize]>,
}

/// How ERA's Hankel matrix is sized (`propid identify --hankel auto|square|RxC`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HankelSize {
    /// From the noise floor (`sizing::hankel_dims`), at most the default [`Limits`] blocks.
    #[default]
    Auto,
    /// The largest near-square Hankel the Markov sequence `Y_0 .. Y_{L−1}` allows
    /// ([`square_blocks`]): `r = c = ⌊(L − 1)/2⌋` blocks for one input and one output.
    Square,
    /// Explicit block rows and columns `(r, c)`.
    Blocks(usize, usize),
}

/// Block counts `(r, c)` of the largest near-square Hankel from `len` Markov blocks with `q`
/// outputs and `p` inputs: `H(0)` and `H(1)` use `Y_1 .. Y_{r+c}`, so `r + c = L − 1`, and
/// `r q ≈ c p` (the split that maximises the rank bound `min(r q, c p)`), i.e.
/// `r = round((L − 1) p / (p + q))`. Square Hankel matrices give the least biased and least
/// scattered damping under noise (issue 6). Every dimension is at least one block.
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

/// Identifies `input` by the pulse path when it is a clean pulse experiment, by OKID + ERA
/// otherwise, with the Hankel sized automatically.
pub fn identify_any(
    input: &AnyInput<'_>,
    ident: &IdentOptions,
    okid_opts: &OkidOptions,
) -> Result<AnyModel, AnyError> {
    identify_any_sized(input, ident, okid_opts, HankelSize::Auto)
}

/// [`identify_any`] with the Hankel size chosen by `size` (an explicit `ident.hankel_blocks`
/// is overridden unless `size` is [`HankelSize::Auto`]). For large sizes the workspace is
/// sized to the Hankel, whose dense buffers stay capped at [`crate::svd::DENSE_MAX_DIM`]:
/// beyond it the truncated (FFT + Lanczos, O(N) memory) SVD runs.
pub fn identify_any_sized(
    input: &AnyInput<'_>,
    ident: &IdentOptions,
    okid_opts: &OkidOptions,
    size: HankelSize,
) -> Result<AnyModel, AnyError> {
    let n = input.u.first().map_or(0, |c| c.len());
    let q = input.y.len();
    check_order(n, q, input.u.len(), ident, size)?;
    if let HankelSize::Blocks(r, c) = size {
        // Refused before any buffer is sized from it: the Markov sequence is never longer
        // than the record.
        if r == 0 || c == 0 {
            return Err(
                IdentError::InvalidInput("Hankel block rows and columns must be >= 1").into(),
            );
        }
        if r.saturating_add(c) > n.saturating_sub(1) {
            return Err(IdentError::RecordTooShort {
                needed: r.saturating_add(c).saturating_add(1),
                available: n,
            }
            .into());
        }
    }
    if input.u.len() == 1 && looks_like_pulses(input, ident.max_pulse_width) {
        let limits = limits_for(n, q, 1, ident, size);
        let mut ws = Workspace::new(&limits)?;
        let pulse = PulseInput {
            dt_s: input.dt_s,
            u: input.u[0],
            y: input.y,
            missing: input.missing,
            pulse_starts: input.pulse_starts,
        };
        let mut opts = *ident;
        match size {
            HankelSize::Auto => {}
            HankelSize::Blocks(r, c) => opts.hankel_blocks = Some((r, c)),
            HankelSize::Square => {
                // The pulse window (hence L) is known only once the ensemble is built: a
                // small probe builds it, then the square Hankel is cut from its length.
                let m = ident.order.unwrap_or(2) + 1;
                let probe = IdentOptions {
                    hankel_blocks: Some((m, m)),
                    jackknife: false,
                    ..*ident
                };
                let probed = ws.identify(&pulse, &probe).map(|_| ()).err();
                let len = match probed {
                    Some(IdentError::NoPulse | IdentError::AllPulsesSkipped { .. }) => 0,
                    Some(e) if ws.markov().is_empty() => return Err(e.into()),
                    _ => ws.markov().len(),
                };
                if len > 0 {
                    opts.hankel_blocks = Some(square_blocks(len, q, 1)?);
                }
            }
        }
        match ws.identify(&pulse, &opts) {
            Ok(_) => {
                let report = ws.to_report();
                check_finite(&report, None)?;
                return Ok(AnyModel {
                    report,
                    path: PathTaken::Pulse,
                    okid: None,
                });
            }
            Err(IdentError::NoPulse | IdentError::AllPulsesSkipped { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
    identify_okid_sized(input, ident, okid_opts, size)
}

/// OKID, then ERA on the recovered Markov parameters.
pub fn identify_okid(
    input: &AnyInput<'_>,
    ident: &IdentOptions,
    okid_opts: &OkidOptions,
) -> Result<AnyModel, AnyError> {
    identify_okid_sized(input, ident, okid_opts, HankelSize::Auto)
}

/// [`identify_okid`] with the Hankel size chosen by `size` (see [`identify_any_sized`]).
pub fn identify_okid_sized(
    input: &AnyInput<'_>,
    ident: &IdentOptions,
    okid_opts: &OkidOptions,
    size: HankelSize,
) -> Result<AnyModel, AnyError> {
    let n = input.u.first().map_or(0, |c| c.len());
    check_order(n, input.y.len(), input.u.len(), ident, size)?;
    let missing = (!input.missing.is_empty()).then_some(input.missing);
    let mut r = okid(input.u, input.y, missing, okid_opts)?;
    let from = match split_half_noise(input, &r, okid_opts) {
        Some(noise) if noise.iter().sum::<f64>() < r.markov_noise.iter().sum::<f64>() => {
            r.markov_noise = noise;
            "split_half"
        }
        Some(_) | None => "regression",
    };
    let markov = MarkovSeq::from_data(r.q, r.p, r.markov.clone())?;
    check_order(r.len, r.q, r.p, ident, size)?;
    let limits = limits_for(r.len, r.q, r.p, ident, size);
    let mut ws = Workspace::new(&limits)?;
    let mut opts = *ident;
    match size {
        HankelSize::Auto => {}
        HankelSize::Square => opts.hankel_blocks = Some(square_blocks(r.len, r.q, r.p)?),
        HankelSize::Blocks(rb, cb) => opts.hankel_blocks = Some((rb, cb)),
    }
    if opts.hankel_blocks.is_none() {
        let signal = sizing::signal_length(&markov, &r.markov_noise, &[]).max(8);
        let min_size = opts.order.map_or(3, |n| n + 1);
        let (rmax, cmax) = (limits.max_block_rows, limits.max_block_cols);
        let avail = r.len.saturating_sub(1);
        let dims = sizing::hankel_dims(r.q, r.p, avail, signal, min_size, rmax, cmax)?;
        opts.hankel_blocks = Some((dims.r, dims.c));
    }
    if opts.order.is_none() {
        // Probe with the largest order the Hankel allows to see every leading singular value,
        // then keep those above OKID's noise floor. If the probe is refused (exact data of
        // lower rank), the core's own choice stands.
        let (r_blk, c_blk) = opts.hankel_blocks.unwrap_or((1, 1));
        let wide = (r_blk * r.q).min(c_blk * r.p);
        let probe = IdentOptions {
            order: Some(limits.max_order.min(wide).max(1)),
            jackknife: false,
            ..opts
        };
        if ws.identify_markov(&markov, input.dt_s, &probe).is_ok() {
            opts.order = Some(okid_order(&ws.to_report(), &r, limits.max_order));
        }
    }
    ws.identify_markov(&markov, input.dt_s, &opts)?;
    let mut summary = OkidSummary::from(&r);
    summary.markov_noise_from = from;
    let mut report = ws.to_report();
    // The recovered Markov sequence is the smooth pulse response of the fitted observer
    // model: its tail RMS (what `identify_markov` reports) is ~0 and says nothing about the
    // measurement. The output noise on this path is the one-step residual RMS of the OKID
    // regression (RMS over outputs).
    report.noise_rms = rms(&r.residual_rms);
    check_finite(&report, Some(r.condition))?;
    Ok(AnyModel {
        report,
        path: PathTaken::Okid,
        okid: Some(summary),
    })
}

/// `σ_i = RMS_{k, j}(Y_a − Y_b)/2` from OKID on the two halves with the same `ℓ` (see the module
/// docs); `None` when a half cannot be identified.
fn split_half_noise(input: &AnyInput<'_>, r: &OkidResult, o: &OkidOptions) -> Option<Vec<f64>> {
    let n = input.u.first()?.len();
    let half = n / 2;
    let opts = OkidOptions {
        observer_order: Some(r.observer_order),
        markov_len: Some(r.len),
        ..*o
    };
    let part = |range: std::ops::Range<usize>| {
        let u: Vec<&[f64]> = input.u.iter().map(|c| &c[range.clone()]).collect();
        let y: Vec<&[f64]> = input.y.iter().map(|c| &c[range.clone()]).collect();
        let m = (!input.missing.is_empty()).then(|| &input.missing[range.clone()]);
        okid(&u, &y, m, &opts).ok()
    };
    let (a, b) = (part(0..half)?, part(half..n)?);
    let blocks = (r.len - 1).min(64.max(2 * r.observer_order));
    let (q, p) = (r.q, r.p);
    let noise = (0..q)
        .map(|i| {
            let mut sum = 0.0;
            for k in 1..=blocks {
                for j in 0..p {
                    sum += (a.at(k, i, j) - b.at(k, i, j)).powi(2);
                }
            }
            (sum / (blocks * p) as f64).sqrt() / 2.0
        })
        .collect::<Vec<f64>>();
    noise.iter().all(|v| v.is_finite()).then_some(noise)
}

/// The order from the singular values of the last identification against OKID's noise floor
/// (RMS of [`OkidResult::markov_noise`] over outputs); at least 1.
fn okid_order(report: &ModelReport, r: &OkidResult, max_order: usize) -> usize {
    let dims = HankelDims {
        q: r.q,
        p: r.p,
        r: report.hankel_block_rows,
        c: report.hankel_block_cols,
    };
    let n = r.markov_noise.len().max(1) as f64;
    let sigma = (r.markov_noise.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    let noise_sv = sizing::noise_singular_value(sigma, &dims, &[]);
    sizing::auto_order(&report.singular_values, noise_sv, max_order).max(1)
}

/// True when the pulse path should be tried first: the record has device pulse starts
/// (EVENT IMPULSE_START), or its input is piecewise constant, or it is a ramped staircase
/// ([`is_ramped_staircase`]). The pulse path itself decides whether there are pulses
/// ([`IdentError::NoPulse`] falls back to OKID); ramps between levels do not disqualify it,
/// because every pulse window ends at the next level change and each pulse is referenced to
/// its own pre-pulse baseline ([`crate::pulses`]).
pub fn looks_like_pulses(input: &AnyInput<'_>, max_pulse_width: usize) -> bool {
    let Some(u) = input.u.first() else {
        return false;
    };
    input.pulse_starts.is_some_and(|s| !s.is_empty())
        || is_piecewise_constant(u)
        || is_ramped_staircase(u, max_pulse_width)
}

/// True when `u` is a ramped staircase with pulses up to `max_pulse_width` samples wide
/// ([`crate::segment::is_ramped_staircase`]).
pub fn is_ramped_staircase(u: &[f64], max_pulse_width: usize) -> bool {
    let rules = crate::segment::SegmentRules {
        max_pulse_samples: max_pulse_width,
        ..crate::segment::SegmentRules::DEFAULT
    };
    crate::segment::is_ramped_staircase(crate::segment::Command::new(u), &rules)
}

/// True when `u` is piecewise constant ([`crate::segment::is_piecewise_constant`]).
pub fn is_piecewise_constant(u: &[f64]) -> bool {
    crate::segment::is_piecewise_constant(
        crate::segment::Command::new(u),
        &crate::segment::SegmentRules::DEFAULT,
    )
}

/// Root mean square of `v` (NaN when empty).
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// Refuses a requested order larger than `n` samples (or Markov blocks) with `q` outputs and
/// `p` inputs can support, before any workspace is sized from it. ERA's Hankel `H(0)` of `r × c`
/// blocks from `Y_1 .. Y_{r+c−1}` (and `H(1)` one block further) needs `r + c ≤ n − 1`; its
/// rank is at most `min(r q, c p)`, largest for `r q = c p`: `(n − 1) p q / (p + q)`. The
/// workspace also caps `r` and `c` at the default block counts of [`Limits`] when the size is
/// automatic. The core checks the exact Hankel later ([`IdentError::OrderTooHigh`] too); this
/// bound only has to be safe.
fn check_order(
    n: usize,
    q: usize,
    p: usize,
    ident: &IdentOptions,
    size: HankelSize,
) -> Result<(), IdentError> {
    let Some(order) = ident.order else {
        return Ok(());
    };
    let (q, p) = (q.max(1), p.max(1));
    let d = Limits::default();
    let data = n.saturating_sub(1) * p * q / (p + q);
    let max = match size {
        HankelSize::Auto => data.min((d.max_block_rows * q).min(d.max_block_cols * p)),
        HankelSize::Square => data,
        HankelSize::Blocks(r, c) => data.min((r * q).min(c * p)),
    };
    if order > max {
        return Err(IdentError::OrderTooHigh { order, max });
    }
    Ok(())
}

/// OKID regression condition above which an order-2 model without a pole pair (`fn_hz` NaN) is
/// refused rather than published: a short or poorly exciting record (the audit's 119 samples
/// gave 4.5e15).
pub const ILL_CONDITIONED: f64 = 1e12;

/// Refuses a model with non-finite matrices, poles or DC gain, or (order 2, from an OKID
/// regression whose condition exceeds [`ILL_CONDITIONED`]) non-finite `fn_hz`/`zeta`: a short
/// or poorly exciting record can produce one without any step failing. An order-2 model of a
/// first-order plant from well-conditioned data legitimately has no pole pair (`fn_hz` null).
pub fn check_finite(r: &ModelReport, condition: Option<f64>) -> Result<(), AnyError> {
    let bad = |m: &[Vec<f64>]| m.iter().flatten().any(|v| !v.is_finite());
    let gain_bad = match &r.dc_gain {
        Gain::Scalar(g) => !g.is_finite(),
        Gain::List(v) => v.iter().any(|g| !g.is_finite()),
        Gain::Matrix(m) => bad(m),
    };
    let what = if bad(&r.a) || bad(&r.b) || bad(&r.c) || bad(&r.d) {
        "state-space matrices"
    } else if r.poles_z.iter().flatten().any(|v| !v.is_finite()) {
        "poles"
    } else if r.order == 2
        && !(r.fn_hz.is_finite() && r.zeta.is_finite())
        && condition.is_some_and(|c| c.is_nan() || c > ILL_CONDITIONED)
    {
        "fn_hz/zeta"
    } else if gain_bad {
        "dc_gain"
    } else {
        return Ok(());
    };
    Err(AnyError::NonFiniteModel { what, condition })
}

/// Workspace limits for `n` samples (or Markov blocks), `q` outputs, `p` inputs and the Hankel
/// `size`. Automatic sizing keeps the default block caps; a square or explicit Hankel raises
/// them to what it needs (square: at most `n / 2` blocks each way, since `r + c ≤ L − 1 < n`).
/// With a given order and a sized Hankel, `max_order` is that order: the singular-vector
/// buffers hold `rows × (max_order + 4)` doubles, which at 50 000 rows is what keeps the
/// process within O(N) memory of a few MB per buffer.
fn limits_for(n: usize, q: usize, p: usize, ident: &IdentOptions, size: HankelSize) -> Limits {
    let d = Limits::default();
    let (max_block_rows, max_block_cols) = match size {
        HankelSize::Auto => (d.max_block_rows, d.max_block_cols),
        HankelSize::Square => ((n / 2).max(1), (n / 2).max(1)),
        HankelSize::Blocks(r, c) => (r.max(1), c.max(1)),
    };
    let max_order = match (size, ident.order) {
        (HankelSize::Auto, o) | (_, o @ None) => o.unwrap_or(d.max_order).max(d.max_order),
        (_, Some(o)) => o.max(1),
    };
    Limits {
        max_samples: n.max(4),
        max_outputs: q.max(1),
        max_inputs: p.max(1),
        max_order,
        max_pulses: (n / 4).clamp(1, 4096),
        max_block_rows,
        max_block_cols,
    }
}
