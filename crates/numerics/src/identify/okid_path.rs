//! OKID, then ERA on the recovered Markov parameters.
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
//! (the regression one alone when a half cannot be identified). The Hankel size follows from
//! where the sequence sinks below it ([`hankel_size::auto_dims`] with [`Span::OkidFloor`]),
//! and the order from the singular values above the noise
//! ([`model_order::order_above_noise`]), the same rules as the pulse path with this σ,
//! stepping down like the pulse path's to the largest order that settles
//! ([`model_order::settled_order`]).
//!
//! **DC gain.** The realisation's gain is checked against the sequence's own `Σ Y_k` and, when
//! ERA's truncation lost it, `B` and `D` are re-fitted to hold it ([`super::gain`]; published
//! as `dc_gain_from`, `realised_dc_gain`).

use serde::Serialize;

use super::{check_finite, limits_for, AnyError, AnyInput, AnyModel, PathTaken};
use crate::hankel::HankelDims;
use crate::okid::{okid, OkidOptions, OkidResult};
use crate::order::hankel_size::{self, square_blocks, Span};
use crate::order::model_order::{self, check_order};
use crate::order::HankelSize;
use crate::stabilization::StabOptions;
use crate::workspace::{IdentOptions, Workspace};
use crate::{MarkovSeq, ModelReport};

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
    /// `"realisation"` (`D + C (I − A)⁻¹ B` as ERA realised it) or `"markov_sum"` (the
    /// realisation's gain contradicted `Σ Y_k` and `B`, `D` were re-fitted to hold it:
    /// [`super::gain`]).
    pub dc_gain_from: &'static str,
    /// The realisation's DC gain (input 0 to output 0) when it was replaced, else null.
    pub realised_dc_gain: Option<f64>,
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
            dc_gain_from: "realisation",
            realised_dc_gain: None,
        }
    }
}

/// OKID, then ERA on the recovered Markov parameters.
pub fn identify_okid(
    input: &AnyInput<'_>,
    ident: &IdentOptions,
    okid_opts: &OkidOptions,
) -> Result<AnyModel, AnyError> {
    identify_okid_sized(input, ident, okid_opts, HankelSize::Auto)
}

/// [`identify_okid`] with the Hankel size chosen by `size` (see [`super::identify_any_sized`]).
pub fn identify_okid_sized(
    input: &AnyInput<'_>,
    ident: &IdentOptions,
    okid_opts: &OkidOptions,
    size: HankelSize,
) -> Result<AnyModel, AnyError> {
    identify_okid_with(input, ident, okid_opts, size, None)
}

/// [`identify_okid_sized`] with the stabilization diagram of the final ERA's SVD when `stab`
/// is given (see [`super::identify_any_with`]).
pub fn identify_okid_with(
    input: &AnyInput<'_>,
    ident: &IdentOptions,
    okid_opts: &OkidOptions,
    size: HankelSize,
    stab: Option<&StabOptions>,
) -> Result<AnyModel, AnyError> {
    let n = input.u.first().map_or(0, |c| c.len());
    check_order(ident.order, n, input.y.len(), input.u.len(), size)?;
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
    check_order(ident.order, r.len, r.q, r.p, size)?;
    let limits = limits_for(r.len, r.q, r.p, 1, ident, size);
    let mut ws = Workspace::new(&limits)?;
    let mut opts = *ident;
    match size {
        HankelSize::Auto => {}
        HankelSize::Square => opts.hankel_blocks = Some(square_blocks(r.len, r.q, r.p)?),
        HankelSize::Blocks(rb, cb) => opts.hankel_blocks = Some((rb, cb)),
    }
    if opts.hankel_blocks.is_none() {
        let max = (limits.max_block_rows, limits.max_block_cols);
        let noise = &r.markov_noise;
        let dims = hankel_size::auto_dims(&markov, noise, &[], Span::OkidFloor, opts.order, max)?;
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
            opts.order_is_a_ceiling = true;
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
    report.missing_samples = crate::workspace::count_missing(input.missing);
    if let Some(repair) = super::gain::impose_sequence_gain(&mut report, &markov) {
        summary.dc_gain_from = "markov_sum";
        summary.realised_dc_gain = Some(repair.realised);
    }
    check_finite(&report, Some(r.condition))?;
    let stabilization = stab.and_then(|o| ws.stabilization_markov(&markov, o).ok());
    Ok(AnyModel {
        report,
        path: PathTaken::Okid,
        okid: Some(summary),
        stabilization,
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
/// [`OkidResult::markov_noise`] ([`model_order::order_above_noise`]); at least 1.
fn okid_order(report: &ModelReport, r: &OkidResult, max_order: usize) -> usize {
    let dims = HankelDims {
        q: r.q,
        p: r.p,
        r: report.hankel_block_rows,
        c: report.hankel_block_cols,
    };
    let sigma = &report.singular_values;
    model_order::order_above_noise(sigma, &r.markov_noise, &dims, &[], max_order).max(1)
}

/// Root mean square of `v` (NaN when empty).
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}
