//! The published diagnosis: each model simulated over the whole record and measured on the
//! held-out validation samples (`100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)` and the residual RMS), the gain of
//! the extension, and the traces for the report.

use super::ctx::Ctx;
use super::era_start::{self, EraStart};
use super::fit::Fit;
use super::model::{simulate, Model};
use super::noise;
use super::result::{Diagnosis, Extended, Gain, Split, Stage, Traces};
use super::search::Searched;
use super::summary::ModelSummary;
use super::verdict::{self, Residual};

/// Validation fit percent and residual RMS of a fit; its simulation over the whole record is
/// left in `sim`.
fn validate(ctx: &Ctx, f: &Fit, sim: &mut Vec<f64>) -> (f64, f64) {
    sim.resize(ctx.sig.u.len(), 0.0);
    simulate(&f.model, &ctx.sig, sim);
    let ys: Vec<f64> = ctx
        .val
        .clone()
        .filter(|&k| ctx.sig.y[k].is_finite())
        .map(|k| ctx.sig.y[k])
        .collect();
    let mean = ys.iter().sum::<f64>() / ys.len().max(1) as f64;
    let mut e2 = 0.0;
    let mut d2 = 0.0;
    let mut m = 0usize;
    for k in ctx.val.clone() {
        let yk = ctx.sig.y[k];
        if yk.is_finite() {
            e2 += (yk - sim[k]).powi(2);
            d2 += (yk - mean).powi(2);
            m += 1;
        }
    }
    let fit = 100.0 * (1.0 - (e2 / d2.max(1e-300)).sqrt());
    (fit, (e2 / m.max(1) as f64).sqrt())
}

/// The diagnosis from the search's result and the core's model (when it gave one).
pub fn assemble(ctx: &Ctx, searched: Searched, era: Option<&EraStart>) -> Diagnosis {
    let dt = ctx.sig.dt_s;
    let effects = searched.effects();
    let Searched {
        base,
        extended: cur,
        findings,
    } = searched;
    let mut sim_b = Vec::new();
    let mut sim_e = Vec::new();
    let (fit_b, rms_b) = validate(ctx, &base, &mut sim_b);
    let core = era.map(|e| &e.report);
    let core_model = era.map(|e| {
        let q = era_start::with_offset(ctx, &e.core);
        let f = Fit {
            model: Model::new(q),
            sse: 0.0,
            n: 0,
        };
        let (fit, _) = validate(ctx, &f, &mut sim_e);
        era_start::summary(&q, e.path, fit)
    });
    let baseline = Stage {
        model: ModelSummary::from_fit(&base, dt, core),
        fit_percent: fit_b,
        core_model,
    };
    let (extended, gain, rms_e) = if effects.is_empty() {
        sim_e = sim_b.clone();
        (None, None, None)
    } else {
        let (fit_e, rms_e) = validate(ctx, &cur, &mut sim_e);
        let ext = Extended {
            effects,
            model: ModelSummary::from_fit(&cur, dt, core),
            fit_percent: fit_e,
        };
        let gain = Gain {
            fit_percent_points: fit_e - fit_b,
            rms_ratio: rms_e / rms_b.max(1e-300),
        };
        (Some(ext), Some(gain), Some(rms_e))
    };
    let noise_floor = noise::noise_floor(ctx.sig.u, ctx.sig.y);
    let residual = Residual {
        baseline_rms: rms_b,
        extended_rms: rms_e,
    };
    let verdict = verdict::verdict(noise_floor.as_ref(), &residual, extended.is_some());
    let band = verdict::excited_band(ctx.sig.u, dt);
    let mut warnings = verdict::warnings(&baseline.model, "baseline", band);
    if let Some(e) = &extended {
        warnings.extend(verdict::warnings(&e.model, "extended", band));
    }
    Diagnosis {
        baseline,
        findings,
        extended,
        gain,
        split: Split {
            estimation: [ctx.est.start, ctx.est.end],
            validation: [ctx.val.start, ctx.val.end],
        },
        noise_floor,
        residual,
        verdict,
        warnings,
        traces: Traces {
            dt_s: dt,
            u: ctx.sig.u.to_vec(),
            y: ctx.sig.y.to_vec(),
            baseline: sim_b,
            extended: sim_e,
            stabilization: era.and_then(|e| {
                let s = e.stabilization.clone()?;
                Some((s, e.report.fn_hz, e.report.zeta))
            }),
        },
    }
}
