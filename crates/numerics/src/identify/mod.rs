//! The identification path choice: the pulse path for a clean pulse experiment, OKID + ERA
//! otherwise, one entry for any excitation ([`identify_any`]).
//!
//! A record is a **clean pulse experiment** when it has one input, device pulse starts (EVENT
//! IMPULSE_START) or an input that is piecewise constant (the input holds its previous value
//! on at least half of the samples: levels, pulses and the ramps between levels of a stand's
//! experiment plan, but not random, chirp or multisine input, whose rare equal neighbours could
//! look like pulses) or a ramped staircase (flat levels on at least half of the samples;
//! [`looks_like_pulses`]), and the pulse path of the core finds and keeps at least one pulse in
//! it. Everything else (random, chirp, multisine, steps, staircases, ramps, several inputs)
//! goes through [`okid`](crate::okid) and then ERA on the recovered Markov parameters
//! ([`identify_okid`], [`Workspace::identify_markov`]). The path taken is reported.
//!
//! - [`excitation`]: does the record look like a pulse experiment?
//! - [`okid_path`]: OKID, its noise floor (split halves) and ERA on the recovered sequence.
//! - [`finite`]: a model with non-finite parts is refused, never published.
//! - [`gain`]: an OKID model's DC gain is its Markov sequence's (`B`, `D` re-fitted when ERA's
//!   truncation lost it).
//!
//! Hankel size and model order follow the rules of [`crate::order`] on both paths.

pub mod excitation;
pub mod finite;
pub mod gain;
pub mod okid_path;

use serde::Serialize;

pub use excitation::{is_piecewise_constant, is_ramped_staircase, looks_like_pulses};
pub use finite::{check_finite, ILL_CONDITIONED};
pub use okid_path::{identify_okid, identify_okid_sized, identify_okid_with, OkidSummary};

use crate::okid::{OkidError, OkidOptions};
use crate::order::hankel_size::square_blocks;
use crate::order::model_order::check_order;
use crate::order::HankelSize;
use crate::pulses::PulseInput;
use crate::segment::{Command, SegmentRules};
use crate::stabilization::{StabOptions, Stabilization};
use crate::workspace::{IdentOptions, Limits, Workspace, AUTO_MAX_BLOCKS};
use crate::{IdentError, ModelReport};

/// Which way the Markov parameters were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PathTaken {
    /// Pulses segmented and ensemble-averaged ([`crate::pulses`]).
    Pulse,
    /// Observer/Kalman filter identification from arbitrary input.
    Okid,
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
    /// The stabilization diagram of the model's Hankel SVD, when asked for
    /// ([`identify_any_with`]) and computable.
    pub stabilization: Option<Stabilization>,
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
    identify_any_with(input, ident, okid_opts, size, None)
}

/// [`identify_any_sized`], with the stabilization diagram of the model's own Hankel SVD
/// ([`crate::stabilization`]) when `stab` is given: [`AnyModel::stabilization`] (`None` when
/// the diagram cannot be realised; the model is the same either way).
pub fn identify_any_with(
    input: &AnyInput<'_>,
    ident: &IdentOptions,
    okid_opts: &OkidOptions,
    size: HankelSize,
    stab: Option<&StabOptions>,
) -> Result<AnyModel, AnyError> {
    let n = input.u.first().map_or(0, |c| c.len());
    let q = input.y.len();
    check_order(ident.order, n, q, input.u.len(), size)?;
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
        let pulses = pulse_count(input, ident.max_pulse_width);
        let limits = limits_for(n, q, 1, pulses, ident, size);
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
                let stabilization = stab.and_then(|o| ws.stabilization(o).ok());
                return Ok(AnyModel {
                    report,
                    path: PathTaken::Pulse,
                    okid: None,
                    stabilization,
                });
            }
            Err(IdentError::NoPulse | IdentError::AllPulsesSkipped { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
    identify_okid_with(input, ident, okid_opts, size, stab)
}

/// Pulses the pulse path will look at in `input`: the device's pulse starts, or the
/// segmentation's pulses of the input (the rule [`crate::pulses`] applies). The workspace is
/// sized from this count, so a record holds as many pulses as it has (a 5 000-pulse recording
/// is identified, not refused at a fixed limit).
fn pulse_count(input: &AnyInput<'_>, max_width: usize) -> usize {
    match (input.pulse_starts, input.u.first()) {
        (Some(starts), _) if !starts.is_empty() => starts.len(),
        (_, Some(u)) => {
            let rules = SegmentRules {
                max_pulse_samples: max_width,
                ..SegmentRules::DEFAULT
            };
            crate::segment::pulses(Command::with_missing(u, input.missing), &rules).count()
        }
        (_, None) => 0,
    }
}

/// Workspace limits for `n` samples (or Markov blocks), `q` outputs, `p` inputs, `pulses`
/// pulses ([`pulse_count`]) and the Hankel `size`. Automatic sizing may take up to half the
/// record each way, at least the default block caps and at most [`AUTO_MAX_BLOCKS`] (the span
/// itself is the noise floor's); a square or explicit Hankel raises them to what it needs (square: at most `n / 2` blocks each way, since `r + c ≤ L − 1 < n`).
/// With a given order and a sized Hankel, `max_order` is that order: the singular-vector
/// buffers hold `rows × (max_order + 4)` doubles, which at 50 000 rows is what keeps the
/// process within O(N) memory of a few MB per buffer.
fn limits_for(
    n: usize,
    q: usize,
    p: usize,
    pulses: usize,
    ident: &IdentOptions,
    size: HankelSize,
) -> Limits {
    let d = Limits::default();
    let (max_block_rows, max_block_cols) = match size {
        HankelSize::Auto => {
            let m = (n / 2).clamp(d.max_block_rows, AUTO_MAX_BLOCKS);
            (m, m)
        }
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
        max_pulses: pulses.max(1),
        max_block_rows,
        max_block_cols,
    }
}
