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
//! # Least squares
//!
//! One regression row per sample `k = ℓ .. N−1` (rows whose window touches a missing sample are
//! skipped and counted): regressor
//! `φ_k = [1, u_k, u_{k−1}, y_{k−1}, …, u_{k−ℓ}, y_{k−ℓ}]` (the leading 1 absorbs the operating
//! point), target `y_k`. Every channel is centred by its mean and scaled by its standard deviation
//! first (an affine change of variables that the intercept absorbs; it keeps the condition number
//! meaningful when thrust sits at 5 N ± 0.1 N). The stacked system `Φ θ = Y` is reduced by a
//! streaming Householder QR of the augmented matrix `[Φ Y]` in blocks (memory `O(cols²)`, not
//! `O(N·cols)`), then `R θ = Qᵀ Y` is solved through the SVD of the small triangular `R`:
//!
//! ```text
//! θ_out = Σ_{i kept} v_i (u_iᵀ Qᵀ y_out) / σ_i,
//! kept:  σ_i > rcond·σ_1   and   |u_iᵀ Qᵀ y_out| > τ·σ_e,out
//! ```
//!
//! a truncated-SVD (minimum-norm) solution. Directions below rounding (`σ_i ≤ rcond·σ_1`,
//! default `rcond` = 1e-10) carry no information and are dropped: that is the regularisation of
//! an ill-conditioned (or rank-deficient) regression, and [`OkidResult::regularised`] says when
//! it happened; the condition number is reported either way. Optionally (`significance` τ > 0,
//! off by default) a direction whose data projection is not significant against the residual
//! noise is dropped too: in the rotated system `Qᵀ y = R θ + Qᵀ e` with white `e`, each
//! `u_iᵀ Qᵀ e` has standard deviation `σ_e`, so dropping `|u_iᵀ Qᵀ y| ≤ τ σ_e` is a
//! hard-threshold estimator. (Measured on noisy staircases it discards too much: the default
//! relies on the choice of `ℓ` below instead.)
//!
//! # Choosing `ℓ`
//!
//! `ℓ_max = clamp(⌊N / (10 (p+q))⌋, 1, 40)` follows from the data length (at least ten rows per
//! parameter). Because the columns are ordered by lag, the regression with `ℓ ≤ ℓ_max` lags uses a
//! *prefix* of the columns, so one QR serves every `ℓ`: `R_φ` is the leading `m(ℓ) × m(ℓ)` block
//! with `m(ℓ) = 1 + p + (p+q)ℓ`, and `RSS(ℓ) = ‖z_{m(ℓ):}‖² + ‖R_res‖²`. The number used is
//! chosen by output (simulation) error over a set of candidates ([`observer`]). Too many lags are
//! not harmless: with a band-limited input (a chirp, a multisine) the lagged input columns are
//! numerically dependent, and with few steps and noise the extra parameters fit the noise; in
//! both cases the recovered Markov parameters drift while the one-step fit still improves.

//! # Noise of the Markov parameters
//!
//! With residual standard deviation `σ_e` of output `i` and the (pseudo-)inverse Gram matrix
//! `(ΦᵀΦ)⁺ = V Σ⁻² Vᵀ` (kept directions only), the standard error of the coefficient of column
//! `c` is `σ_e √[(ΦᵀΦ)⁺]_cc`. The input-lag coefficients `M_k^u` are the leading term of `Y_k`,
//! so [`OkidResult::markov_noise`] = `σ_e · √(mean over input-lag columns of [(ΦᵀΦ)⁺]_cc)` in
//! output units per input unit: the noise floor ERA's order choice compares against.
//!
//! # Recovery of the system Markov parameters (JPHL eqs. 11–13)
//!
//! With `Ȳ_i⁽¹⁾ = C Ā^(i−1) (B + G D)` and `Ȳ_i⁽²⁾ = C Ā^(i−1) G`:
//!
//! ```text
//! Y_0 = D
//! Y_k = Ȳ_k⁽¹⁾ − Σ_{i=1..k} Ȳ_i⁽²⁾ Y_{k−i}          k = 1 .. ℓ
//! Y_k =        − Σ_{i=1..ℓ} Ȳ_i⁽²⁾ Y_{k−i}          k > ℓ
//! ```
//!
//! i.e. the pulse response of the fitted ARX model `y_k = Σ M_i^y y_{k−i} + Σ M_i^u u_{k−i}` with
//! `M_i^u = Ȳ_i⁽¹⁾`, `M_i^y = −Ȳ_i⁽²⁾`. The result follows the project's Markov convention
//! (`docs/ARCHITECTURE.md`): response to a unit input held for one sample, no `1/dt` scaling,
//! block `k` at `data[k·q·p ..]`, column-major inside the block.

use nalgebra::{DMatrix, SVD};

use crate::order::observer;

/// Rows per block of the streaming QR.
const QR_BLOCK_ROWS: usize = 512;
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
    let ell_max = opts.observer_order.unwrap_or(auto_observer_order(n, p, q));
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
    let params_max = params_for(p, q, ell_max);
    let (r_aug, rows, rows_skipped) = streaming_qr(&scaled, n, params_max, &is_missing);
    let need = 2 * params_max;
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

/// Squared residual of output `i` for the prefix model with `m` columns, read off the augmented
/// triangular factor: `‖z_{m:, i}‖² + ‖R_res e_i‖²`.
fn prefix_rss(r_aug: &DMatrix<f64>, m: usize, params_max: usize, i: usize) -> f64 {
    let z = r_aug
        .view((m, params_max + i), (params_max - m, 1))
        .norm_squared();
    let res = r_aug
        .view((params_max, params_max + i), (i + 1, 1))
        .norm_squared();
    z + res
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

/// The record seen through the centring and scaling.
struct Scaled<'a> {
    u: &'a [&'a [f64]],
    y: &'a [&'a [f64]],
    u_stats: &'a [(f64, f64)],
    y_stats: &'a [(f64, f64)],
    ell: usize,
}

impl Scaled<'_> {
    fn u(&self, j: usize, k: usize) -> f64 {
        (self.u[j][k] - self.u_stats[j].0) / self.u_stats[j].1
    }
    fn y(&self, i: usize, k: usize) -> f64 {
        (self.y[i][k] - self.y_stats[i].0) / self.y_stats[i].1
    }

    /// Writes the augmented row `[φ_k, y_k]` into `out`.
    fn row(&self, k: usize, out: &mut [f64]) {
        let (p, q) = (self.u.len(), self.y.len());
        out[0] = 1.0;
        let mut c = 1;
        for j in 0..p {
            out[c] = self.u(j, k);
            c += 1;
        }
        for lag in 1..=self.ell {
            for j in 0..p {
                out[c] = self.u(j, k - lag);
                c += 1;
            }
            for i in 0..q {
                out[c] = self.y(i, k - lag);
                c += 1;
            }
        }
        for i in 0..q {
            out[c + i] = self.y(i, k);
        }
    }
}

/// Streaming Householder QR of the augmented regression `[Φ Y]`: returns the upper-triangular
/// factor (`cols × cols`, `cols = params + q`), the rows used and the rows skipped.
fn streaming_qr(
    s: &Scaled<'_>,
    n: usize,
    params: usize,
    is_missing: &impl Fn(usize) -> bool,
) -> (DMatrix<f64>, usize, usize) {
    let cols = params + s.y.len();
    let mut stack = DMatrix::<f64>::zeros(cols + QR_BLOCK_ROWS, cols);
    let mut r = DMatrix::<f64>::zeros(cols, cols);
    let mut row = vec![0.0; cols];
    let (mut filled, mut used, mut skipped) = (0usize, 0usize, 0usize);
    // Number of consecutive samples (ending at k) that are not missing.
    let mut run = 0usize;
    for k in 0..n {
        run = if is_missing(k) { 0 } else { run + 1 };
        if k < s.ell {
            continue;
        }
        if run <= s.ell {
            skipped += 1;
            continue;
        }
        s.row(k, &mut row);
        for (c, v) in row.iter().enumerate() {
            stack[(cols + filled, c)] = *v;
        }
        filled += 1;
        used += 1;
        if filled == QR_BLOCK_ROWS {
            fold_block(&mut stack, &mut r, cols, filled);
            filled = 0;
        }
    }
    if filled > 0 {
        fold_block(&mut stack, &mut r, cols, filled);
    }
    (r, used, skipped)
}

/// `R ← triu(qr([R; block]))`.
fn fold_block(stack: &mut DMatrix<f64>, r: &mut DMatrix<f64>, cols: usize, filled: usize) {
    stack.view_mut((0, 0), (cols, cols)).copy_from(r);
    let m = stack.rows_range(0..cols + filled).into_owned();
    let qr_r = m.qr().r();
    // qr().r() has min(rows, cols) rows; rows ≥ cols here unless the first block is short.
    r.fill(0.0);
    let rr = qr_r.nrows().min(cols);
    r.view_mut((0, 0), (rr, cols)).copy_from(&qr_r.rows(0, rr));
}

struct Solve {
    /// `params × q`, in scaled variables.
    theta: DMatrix<f64>,
    condition: f64,
    rank: usize,
    /// Norm of the least-squares residual per output (scaled units).
    residual_scaled: Vec<f64>,
    /// Mean of `[(ΦᵀΦ)⁺]_cc` over the input-lag columns (scaled units).
    input_var_factor: f64,
    /// True when some output dropped a direction.
    dropped_any: bool,
}

/// Truncated-SVD solve of `R_φ θ = z` for the first `params` columns, from the augmented
/// triangular factor `[[R_φ, z], [0, R_res]]` of all `params_max` columns (`rcond` and
/// `significance` of `opts`).
fn solve_truncated(
    r_aug: &DMatrix<f64>,
    (p, q): (usize, usize),
    params: usize,
    params_max: usize,
    rows: usize,
    opts: &OkidOptions,
) -> Solve {
    let (rcond, significance) = (opts.rcond, opts.significance);
    let r_phi = r_aug.view((0, 0), (params, params)).into_owned();
    let z = r_aug.view((0, params_max), (params, q)).into_owned();
    // Residual norm: the part of [Φ Y] that Φ does not span, plus what truncation drops.
    let svd = SVD::new(r_phi, true, true);
    let (uu, vt) = (svd.u.as_ref(), svd.v_t.as_ref());
    let sig = &svd.singular_values;
    let smax = sig.max();
    let smin = sig.min();
    let condition = if smax > 0.0 {
        smax / smin.max(smax * f64::EPSILON)
    } else {
        f64::INFINITY
    };
    let mut theta = DMatrix::<f64>::zeros(params, q);
    let mut rank = 0;
    let mut dropped = vec![0.0; q];
    let mut dropped_any = false;
    // Residual standard deviation per output (scaled units), for the significance test.
    let dof = rows.saturating_sub(params).max(1) as f64;
    let sigma_e: Vec<f64> = (0..q)
        .map(|c| (prefix_rss(r_aug, params, params_max, c) / dof).sqrt())
        .collect();
    if let (Some(uu), Some(vt)) = (uu, vt) {
        let uz = uu.transpose() * &z;
        for (i, &s) in sig.iter().enumerate() {
            let mut kept_any = false;
            for c in 0..q {
                let coef = uz[(i, c)];
                let keep = smax > 0.0
                    && s > rcond * smax
                    && (significance == 0.0 || coef.abs() > significance * sigma_e[c]);
                if keep {
                    kept_any = true;
                    for r in 0..params {
                        theta[(r, c)] += vt[(i, r)] * coef / s;
                    }
                } else {
                    dropped[c] += coef * coef;
                }
            }
            rank += usize::from(kept_any);
            dropped_any |= !kept_any || dropped.iter().any(|d| *d > 0.0);
        }
    }
    let residual_scaled = (0..q)
        .map(|c| (prefix_rss(r_aug, params, params_max, c) + dropped[c]).sqrt())
        .collect();
    let input_var_factor = vt.map_or(f64::NAN, |vt| {
        let cols = input_lag_columns(p, q, params);
        let total: f64 = cols
            .iter()
            .map(|&c| {
                (0..sig.len())
                    .filter(|&i| sig[i] > rcond * smax)
                    .map(|i| (vt[(i, c)] / sig[i]).powi(2))
                    .sum::<f64>()
            })
            .sum();
        total / cols.len().max(1) as f64
    });
    Solve {
        theta,
        condition,
        rank,
        residual_scaled,
        input_var_factor,
        dropped_any,
    }
}

/// Columns holding `u_{k−i}` (`i = 0..ℓ`) among the first `params` regression columns.
fn input_lag_columns(p: usize, q: usize, params: usize) -> Vec<usize> {
    let mut cols: Vec<usize> = (1..=p).collect();
    let mut c = 1 + p;
    while c + p + q <= params {
        cols.extend(c..c + p);
        c += p + q;
    }
    cols
}

/// Observer coefficients in physical units: `M_i^u` (q×p, i = 0..ℓ) and `M_i^y` (q×q, i = 1..ℓ),
/// packed as `(mu, my)`, each block column-major. Centring only moves the intercept, which is
/// not needed further; scaling maps `θ_phys[c] = θ_scaled[c] · sd(y_out) / sd(regressor c)`.
fn unscale(theta: &DMatrix<f64>, s: &Scaled<'_>, ell: usize) -> (Vec<f64>, Vec<f64>) {
    let (p, q) = (s.u.len(), s.y.len());
    let mut mu = vec![0.0; (ell + 1) * q * p];
    let mut my = vec![0.0; (ell + 1) * q * q];
    for out in 0..q {
        let sy = s.y_stats[out].1;
        let mut c = 1;
        for lag in 0..=ell {
            for j in 0..p {
                mu[lag * q * p + out + j * q] = theta[(c, out)] * sy / s.u_stats[j].1;
                c += 1;
            }
            if lag == 0 {
                continue;
            }
            for i in 0..q {
                my[lag * q * q + out + i * q] = theta[(c, out)] * sy / s.y_stats[i].1;
                c += 1;
            }
        }
    }
    (mu, my)
}

/// `Y_0 = M_0^u`, `Y_k = M_k^u + Σ_{i=1..min(k,ℓ)} M_i^y Y_{k−i}` (`M_k^u = 0` for `k > ℓ`):
/// JPHL eqs. 11–13 written with the regression's own coefficients (`M_i^y = −Ȳ_i⁽²⁾`).
fn recover_markov(
    theta: &(Vec<f64>, Vec<f64>),
    p: usize,
    q: usize,
    ell: usize,
    len: usize,
) -> Vec<f64> {
    let (mu, my) = theta;
    let qp = q * p;
    let mut out = vec![0.0; len * qp];
    for k in 0..len {
        let (done, rest) = out.split_at_mut(k * qp);
        let yk = &mut rest[..qp];
        if k <= ell {
            yk.copy_from_slice(&mu[k * qp..(k + 1) * qp]);
        }
        for i in 1..=k.min(ell) {
            let m = &my[i * q * q..(i + 1) * q * q];
            let prev = &done[(k - i) * qp..(k - i + 1) * qp];
            for j in 0..p {
                for r in 0..q {
                    let mut acc = 0.0;
                    for c in 0..q {
                        acc += m[r + c * q] * prev[c + j * q];
                    }
                    yk[r + j * q] += acc;
                }
            }
        }
    }
    out
}
