//! The baseline fit and the forward search over the catalogue of effects.
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
//! **Search.** Effects recognised straight from the data ([`Effect::detect`], e.g. a sensor
//! clip) are named first and kept in every model. Then forward stepwise: every effect not yet in
//! the model is fitted on top of it ([`Effect::extend`]); the one with the largest score is
//! taken if it passes and its fitted term is plausible
//! ([`Term::plausible`](super::effect::Term::plausible)); repeat (at most
//! `max_effects` effects in all).

use super::ctx::Ctx;
use super::effect::Effect;
use super::effects::REGISTRY;
use super::fit::Fit;
use super::model::{Core, Model};
use super::result::Finding;

/// Decision threshold on the score `n ln(SSE_M / SSE_{M+e})`.
pub const SCORE_THRESHOLD: f64 = 40.0;
/// Smallest accepted relative drop of the estimation residual RMS.
pub const MIN_RMS_DROP: f64 = 0.01;

/// What the search found.
#[derive(Debug, Clone)]
pub struct Searched {
    /// The 2nd-order baseline (no effect).
    pub base: Fit,
    /// The model with every effect found.
    pub extended: Fit,
    /// The findings, in the order found.
    pub findings: Vec<Finding>,
}

impl Searched {
    /// Names of the effects found, in the order found.
    pub fn effects(&self) -> Vec<String> {
        self.findings.iter().map(|f| f.effect.clone()).collect()
    }
}

/// The 2nd-order baseline with the terms of `template`: a grid over `fn` and `ζ` (gain,
/// offset and linear terms by least squares), then Levenberg–Marquardt from the best two grid
/// points and from every extra start (the core's ERA model); the best result wins.
pub fn baseline(ctx: &Ctx, template: &Model, extra_starts: &[Core]) -> Fit {
    let dt = ctx.sig.dt_s;
    let n = ctx.est.len().max(2) as f64;
    let f_lo = (5.0 / (n * dt)).min(0.1 / dt);
    let f_hi = 0.3 / dt;
    let mut starts = Vec::new();
    for i in 0..14 {
        let fn_hz = f_lo * (f_hi / f_lo).powf(i as f64 / 13.0);
        for zeta in [0.3, 0.7, 1.2, 2.5] {
            starts.push(template.with_core(Core {
                fn_hz,
                zeta,
                ..Core::default()
            }));
        }
    }
    let grid = ctx.best_of(starts, 2);
    let extra = ctx.best_of(extra_starts.iter().map(|c| template.with_core(*c)), 1);
    if extra.sse < grid.sse {
        extra
    } else {
        grid
    }
}

/// Runs the search (module doc) with the core's model as an extra start of the baseline;
/// `None` when the baseline cannot be fitted (non-finite SSE or no sample counted).
pub fn search(ctx: &Ctx, era_starts: &[Core], max_effects: usize) -> Option<Searched> {
    let mut template = Model::default();
    let mut findings = Vec::new();
    for e in REGISTRY {
        if let Some(d) = e.detect(ctx) {
            findings.push(Finding {
                effect: e.name().to_string(),
                score: d.score,
                evidence: d.term.evidence(&template.core, ctx, ""),
                params: d.term.finding_params(ctx.sig.dt_s),
            });
            template = template.with_boxed(d.term);
        }
    }
    let base = baseline(ctx, &Model::default(), era_starts);
    if !base.sse.is_finite() || base.n == 0 {
        return None;
    }
    let mut cur = if findings.is_empty() {
        base.clone()
    } else {
        baseline(ctx, &template, era_starts)
    };
    while findings.len() < max_effects {
        let val_cur = ctx.val_sse(&cur);
        let mut best: Option<(f64, &dyn Effect, Fit)> = None;
        for &e in REGISTRY {
            if findings.iter().any(|f| f.effect == e.name()) {
                continue;
            }
            let Some(f) = e.extend(ctx, &cur) else {
                continue;
            };
            let usable = f.sse.is_finite() && f.sse > 0.0 && cur.sse > 0.0;
            let plausible = f
                .model
                .term(e.name())
                .is_some_and(|t| t.plausible(ctx, &f.model));
            if !(usable && plausible) {
                continue;
            }
            let score = f.n as f64 * (cur.sse / f.sse).ln();
            let rms_drop = 1.0 - (f.sse / cur.sse).sqrt();
            let passes =
                score >= SCORE_THRESHOLD && rms_drop >= MIN_RMS_DROP && ctx.val_sse(&f) < val_cur;
            if passes && best.as_ref().map_or(true, |b| score > b.0) {
                best = Some((score, e, f));
            }
        }
        let Some((score, e, f)) = best else { break };
        findings.push(finding(e, score, &cur, &f, ctx));
        cur = f;
    }
    Some(Searched {
        base,
        extended: cur,
        findings,
    })
}

/// The finding for effect `e` fitted on top of `before`: parameters from the extended fit,
/// evidence in words.
fn finding(e: &dyn Effect, score: f64, before: &Fit, after: &Fit, ctx: &Ctx) -> Finding {
    let rms = |f: &Fit| (f.sse / f.n.max(1) as f64).sqrt();
    let drop = format!(
        "the estimation residual RMS falls from {:.4} to {:.4} ({:.0} % lower)",
        rms(before),
        rms(after),
        100.0 * (1.0 - rms(after) / rms(before).max(1e-300))
    );
    let term = after.model.term(e.name());
    Finding {
        effect: e.name().to_string(),
        score,
        evidence: term.map_or_else(
            || drop.clone(),
            |t| t.evidence(&after.model.core, ctx, &drop),
        ),
        params: term.map_or_else(Default::default, |t| t.finding_params(ctx.sig.dt_s)),
    }
}
