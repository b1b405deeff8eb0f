//! The OKID regression (Juang, Phan, Horta & Longman 1993; see [`crate::okid`]).
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
//! an ill-conditioned (or rank-deficient) regression, and [`super::OkidResult::regularised`] says when
//! it happened; the condition number is reported either way. Optionally (`significance` τ > 0,
//! off by default) a direction whose data projection is not significant against the residual
//! noise is dropped too: in the rotated system `Qᵀ y = R θ + Qᵀ e` with white `e`, each
//! `u_iᵀ Qᵀ e` has standard deviation `σ_e`, so dropping `|u_iᵀ Qᵀ y| ≤ τ σ_e` is a
//! hard-threshold estimator. (Measured on noisy staircases it discards too much: the default
//! relies on the choice of `ℓ` instead, [`crate::order::observer`].)
//!
//! **Noise of the Markov parameters.**
//! With residual standard deviation `σ_e` of output `i` and the (pseudo-)inverse Gram matrix
//! `(ΦᵀΦ)⁺ = V Σ⁻² Vᵀ` (kept directions only), the standard error of the coefficient of column
//! `c` is `σ_e √[(ΦᵀΦ)⁺]_cc`. The input-lag coefficients `M_k^u` are the leading term of `Y_k`,
//! so [`super::OkidResult::markov_noise`] = `σ_e · √(mean over input-lag columns of [(ΦᵀΦ)⁺]_cc)` in
//! output units per input unit: the noise floor ERA's order choice compares against.

use nalgebra::{DMatrix, SVD};

use super::OkidOptions;

/// Rows per block of the streaming QR.
const QR_BLOCK_ROWS: usize = 512;
/// The record seen through the centring and scaling.
pub(super) struct Scaled<'a> {
    pub(super) u: &'a [&'a [f64]],
    pub(super) y: &'a [&'a [f64]],
    pub(super) u_stats: &'a [(f64, f64)],
    pub(super) y_stats: &'a [(f64, f64)],
    pub(super) ell: usize,
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
pub(super) fn streaming_qr(
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

pub(super) struct Solve {
    /// `params × q`, in scaled variables.
    pub(super) theta: DMatrix<f64>,
    pub(super) condition: f64,
    pub(super) rank: usize,
    /// Norm of the least-squares residual per output (scaled units).
    pub(super) residual_scaled: Vec<f64>,
    /// Mean of `[(ΦᵀΦ)⁺]_cc` over the input-lag columns (scaled units).
    pub(super) input_var_factor: f64,
    /// True when some output dropped a direction.
    pub(super) dropped_any: bool,
}

/// Truncated-SVD solve of `R_φ θ = z` for the first `params` columns, from the augmented
/// triangular factor `[[R_φ, z], [0, R_res]]` of all `params_max` columns (`rcond` and
/// `significance` of `opts`).
pub(super) fn solve_truncated(
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
pub(super) fn unscale(theta: &DMatrix<f64>, s: &Scaled<'_>, ell: usize) -> (Vec<f64>, Vec<f64>) {
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
