//! The catalogue of effects: for each, how the model is extended, where the fit starts, and
//! what is reported.
//!
//! **Test statistic.** For an extension `e` of the current model `M` (both fitted by
//! output-error least squares on the same `n` estimation samples), the score is the Gaussian
//! log-likelihood ratio `S = n · ln(SSE_M / SSE_{M+e})`. With white noise and no effect, `S` is
//! asymptotically χ² with as many degrees of freedom as `e` adds (1–3), so a threshold of 40
//! puts the false-alarm probability per test below 1e-7 in theory; real residuals are coloured,
//! which is why the threshold was set on measured clean cases (see `docs/diagnose.md`) and why
//! an effect must also lower the residual RMS by at least 1 % and improve the held-out
//! validation error.
//!
//! **Search.** Forward stepwise: every effect not yet in the model is fitted on top of it; the
//! one with the largest score is taken if it passes; repeat (at most 3 effects). A sensor clip is
//! recognised directly from the data (a flat top at the largest reading), before the search.

use std::ops::Range;

use super::fit::{levenberg_marquardt, linear_refit, sse, Fit};
use super::model::{ix, max_freq_hz, Signals, Spec};
use super::spectrum::peaks;

/// Names of the effects, as published (issue 5).
pub const EFFECTS: [&str; 7] = [
    "dead_time",
    "static_nonlinearity",
    "extra_mode",
    "baseline_drift",
    "periodic_disturbance",
    "supply_sag",
    "saturation",
];

/// Decision threshold on the score `n ln(SSE_M / SSE_{M+e})`.
pub const SCORE_THRESHOLD: f64 = 40.0;
/// Smallest accepted relative drop of the estimation residual RMS.
pub const MIN_RMS_DROP: f64 = 0.01;
/// Longest dead time searched, seconds.
pub const MAX_DELAY_S: f64 = 0.15;

/// The data, the estimation range and the validation range.
#[derive(Debug, Clone)]
pub struct Ctx<'a> {
    /// Signals.
    pub sig: Signals<'a>,
    /// Estimation samples.
    pub est: Range<usize>,
    /// Validation samples.
    pub val: Range<usize>,
}

impl Ctx<'_> {
    /// SSE of a fit on the validation samples.
    pub fn val_sse(&self, f: &Fit) -> f64 {
        let mut buf = Vec::new();
        sse(&f.spec, &f.params, &self.sig, self.val.clone(), &mut buf).0
    }

    fn lm(&self, spec: &Spec, p: &super::model::Params, iters: usize) -> Fit {
        levenberg_marquardt(spec, p, &self.sig, self.est.clone(), iters)
    }

    fn best_of(
        &self,
        spec: Spec,
        starts: impl IntoIterator<Item = super::model::Params>,
        keep: usize,
    ) -> Fit {
        let mut scored: Vec<(f64, super::model::Params)> = starts
            .into_iter()
            .map(|p| {
                let (q, s) = linear_refit(&spec, &p, &self.sig, self.est.clone());
                (s, q)
            })
            .filter(|(s, _)| s.is_finite())
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best: Option<Fit> = None;
        for (_, p) in scored.into_iter().take(keep.max(1)) {
            let f = self.lm(&spec, &p, 40);
            if best.as_ref().map_or(true, |b| f.sse < b.sse) {
                best = Some(f);
            }
        }
        best.unwrap_or(Fit {
            spec,
            params: super::model::Params::default(),
            sse: f64::INFINITY,
            n: 0,
        })
    }

    fn residual(&self, f: &Fit) -> Vec<f64> {
        let mut buf = vec![0.0; self.sig.u.len()];
        super::model::simulate(&f.spec, &f.params, &self.sig, &mut buf);
        self.est.clone().map(|k| self.sig.y[k] - buf[k]).collect()
    }
}

/// The 2nd-order baseline: a grid over `fn` and `ζ` (gain and offset by least squares), then
/// Levenberg–Marquardt from the best two grid points and from every extra start (the core's
/// ERA model); the best result wins.
pub fn baseline(ctx: &Ctx, spec: Spec, extra_starts: &[super::model::Params]) -> Fit {
    let dt = ctx.sig.dt_s;
    let n = ctx.est.len().max(2) as f64;
    let f_lo = (5.0 / (n * dt)).min(0.1 / dt);
    let f_hi = 0.3 / dt;
    let mut starts = Vec::new();
    for i in 0..14 {
        let f = f_lo * (f_hi / f_lo).powf(i as f64 / 13.0);
        for z in [0.3, 0.7, 1.2, 2.5] {
            let mut p = super::model::Params::default();
            p.v[ix::FN] = f;
            p.v[ix::ZETA] = z;
            starts.push(p);
        }
    }
    let grid = ctx.best_of(spec, starts, 2);
    let extra = ctx.best_of(spec, extra_starts.iter().copied(), 1);
    if extra.sse < grid.sse {
        extra
    } else {
        grid
    }
}

/// Fits `effect` on top of `cur`; `None` when the effect does not apply to this data.
pub fn extend(ctx: &Ctx, cur: &Fit, effect: &str) -> Option<Fit> {
    let p0 = cur.params;
    let dt = ctx.sig.dt_s;
    let fmax = max_freq_hz(dt);
    match effect {
        "dead_time" => {
            if cur.spec.delay > 0 {
                return None;
            }
            // At most 0.15 s, 80 samples and a tenth of the estimation part (≥ 60 samples).
            let cap = (ctx.est.len() / 10).clamp(1, 80);
            let dmax = ((MAX_DELAY_S / dt).round() as usize).clamp(1, cap);
            // Coarse grid with a short refit of every parameter at each delay (the baseline's
            // fn and ζ have absorbed part of the delay), then every delay around the best.
            let lm_at = |d: usize, iters: usize| {
                ctx.lm(
                    &Spec {
                        delay: d,
                        ..cur.spec
                    },
                    &p0,
                    iters,
                )
            };
            let coarse = (1..=dmax).step_by(4).map(|d| (d, lm_at(d, 8).sse));
            let d0 = coarse.min_by(|a, b| a.1.total_cmp(&b.1))?.0;
            let mut best: Option<Fit> = None;
            for d in d0.saturating_sub(4).max(1)..=(d0 + 4).min(dmax) {
                let f = lm_at(d, 30);
                if best.as_ref().map_or(true, |b| f.sse < b.sse) {
                    best = Some(f);
                }
            }
            best
        }
        "static_nonlinearity" => {
            // A power law needs a throttle-like input: non-negative, away from zero on average.
            let throttle_like = ctx.sig.u[ctx.est.clone()].iter().all(|&x| x >= 0.0);
            if cur.spec.static_map || !throttle_like || ctx.sig.u_ref <= 1e-3 {
                return None;
            }
            let s = Spec {
                static_map: true,
                ..cur.spec
            };
            let starts = [0.5, 0.75, 1.5, 2.0, 3.0].map(|e| {
                let mut p = p0;
                p.v[ix::EXPONENT] = e;
                p
            });
            Some(ctx.best_of(s, starts, 2))
        }
        "extra_mode" => {
            if cur.spec.extra_mode {
                return None;
            }
            let s = Spec {
                extra_mode: true,
                ..cur.spec
            };
            let f_core = p0.v[ix::FN];
            let lo = (1.5 * f_core).min(0.5 * fmax);
            let mut freqs: Vec<f64> = peaks(&ctx.residual(cur), dt, lo, 0.95 * fmax, 3)
                .into_iter()
                .map(|p| p.0)
                .collect();
            freqs.extend([2.0, 4.0, 8.0, 16.0].map(|m| (m * f_core).min(0.9 * fmax)));
            let mut starts = Vec::new();
            for f in freqs {
                for z in [0.03, 0.15] {
                    let mut p = p0;
                    p.v[ix::MODE_FN] = f;
                    p.v[ix::MODE_ZETA] = z;
                    p.v[ix::MODE_GAIN] = 1.0;
                    starts.push(p);
                }
            }
            Some(ctx.best_of(s, starts, 2))
        }
        "baseline_drift" => {
            if cur.spec.drift {
                return None;
            }
            let s = Spec {
                drift: true,
                ..cur.spec
            };
            Some(ctx.best_of(s, [p0], 1))
        }
        "periodic_disturbance" => {
            if cur.spec.periodic {
                return None;
            }
            let s = Spec {
                periodic: true,
                ..cur.spec
            };
            let n = ctx.est.len() as f64;
            let starts: Vec<_> = peaks(&ctx.residual(cur), dt, 3.0 / (n * dt), 0.95 * fmax, 3)
                .into_iter()
                .map(|(f, _)| {
                    let mut p = p0;
                    p.v[ix::SIN_FREQ] = f;
                    p
                })
                .collect();
            if starts.is_empty() {
                return None;
            }
            Some(ctx.best_of(s, starts, 1))
        }
        "supply_sag" => {
            if cur.spec.supply || ctx.sig.voltage.is_none() {
                return None;
            }
            let s = Spec {
                supply: true,
                ..cur.spec
            };
            let starts = [-0.1, -0.03, 0.03, 0.1].map(|g| {
                let mut p = p0;
                p.v[ix::GAIN_PER_VOLT] = g;
                p
            });
            Some(ctx.best_of(s, starts, 1))
        }
        "saturation" => {
            if cur.spec.clip_throttle || cur.spec.clip_sensor.is_some() {
                return None;
            }
            throttle_clip(ctx, cur)
        }
        _ => None,
    }
}

/// Throttle clip: a grid over levels between the median and the largest throttle of the
/// estimation part (other parameters held, gain and offset by least squares), a finer grid
/// around the best, then Levenberg–Marquardt with the level held.
fn throttle_clip(ctx: &Ctx, cur: &Fit) -> Option<Fit> {
    let mut u: Vec<f64> = ctx.sig.u[ctx.est.clone()]
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    u.sort_by(|a, b| a.total_cmp(b));
    let lo = *u.get(u.len() / 2)?;
    let hi = *u.last()?;
    if hi - lo <= 1e-9 {
        return None;
    }
    let s = Spec {
        clip_throttle: true,
        ..cur.spec
    };
    let score = |l: f64| {
        let mut p = cur.params;
        p.v[ix::CLIP] = l;
        let (q, e) = linear_refit(&s, &p, &ctx.sig, ctx.est.clone());
        (e, q)
    };
    let step = (hi - lo) / 40.0;
    let mut best = (f64::INFINITY, cur.params, hi);
    for i in 0..40 {
        let l = lo + step * i as f64;
        let (e, q) = score(l);
        if e < best.0 {
            best = (e, q, l);
        }
    }
    let centre = best.2;
    for i in -10..=10 {
        let l = centre + step * 0.1 * i as f64;
        let (e, q) = score(l);
        if e < best.0 {
            best = (e, q, l);
        }
    }
    let mut p = best.1;
    p.v[ix::CLIP] = best.2;
    Some(ctx.lm(&s, &p, 30))
}

/// Sensor clip: the largest reading repeats on at least 20 samples and 0.5 % of the estimation
/// part (a flat top); returns the level and the share of clipped samples.
pub fn sensor_clip(ctx: &Ctx) -> Option<(f64, usize)> {
    let ys = &ctx.sig.y[ctx.est.clone()];
    let top = ys
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    if !top.is_finite() {
        return None;
    }
    let tol = 1e-9 * top.abs().max(1e-12);
    let count = ys.iter().filter(|v| (*v - top).abs() <= tol).count();
    (count >= 20 && count * 200 >= ys.len()).then_some((top, count))
}
