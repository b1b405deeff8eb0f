//! The published diagnosis: each model's held-out figures from the search
//! ([`super::folds`]: each fold's fit, their mean, the RMS of the held-out residuals), the gain
//! of the extension, and the traces for the report (each model fitted on the estimation
//! samples, simulated over the whole record).

use super::ctx::Ctx;
use super::effects::REGISTRY;
use super::era_start::{self, EraStart};
use super::fit::Fit;
use super::folds::{fit_percent, Folds};
use super::model::{simulate, Model};
use super::noise;
use super::result::{
    Diagnosis, Extended, FoldFit, Gain, InputLead, Split, Stage, Traces, Validation,
};
use super::search::Searched;
use super::summary::ModelSummary;
use super::verdict::{self, Residual, Warning};

/// Fit percent of a fit on the validation samples (`ctx.val`); its simulation over the whole
/// record is left in `sim`.
fn validate(ctx: &Ctx, f: &Fit, sim: &mut Vec<f64>) -> f64 {
    sim.resize(ctx.sig.u.len(), 0.0);
    simulate(&f.model, &ctx.sig, sim);
    fit_percent(ctx.sig.y, sim, ctx.val.clone()).0
}

/// The diagnosis from the search's result, the core's model (when it gave one) and the
/// output's noise floor ([`noise::noise_floor`]).
pub fn assemble(
    ctx: &Ctx,
    folds: &Folds,
    searched: Searched,
    era: Option<&EraStart>,
    noise_floor: Option<noise::NoiseFloor>,
) -> Diagnosis {
    let dt = ctx.sig.dt_s;
    let effects = searched.effects();
    let Searched {
        base,
        base_cv,
        extended: cur,
        extended_cv,
        findings,
        rejected,
    } = searched;
    let mut sim_b = vec![0.0; ctx.sig.u.len()];
    let mut sim_e = Vec::new();
    simulate(&base.model, &ctx.sig, &mut sim_b);
    let (fit_b, rms_b) = (base_cv.mean, base_cv.rms);
    let core = era.map(|e| &e.report);
    let core_model = era.map(|e| {
        let q = era_start::with_offset(ctx, &e.core);
        let f = Fit {
            model: Model::new(q),
            sse: 0.0,
            n: 0,
        };
        let fit = validate(ctx, &f, &mut sim_e);
        era_start::summary(&q, e.path, fit)
    });
    let baseline = Stage {
        choice: Default::default(),
        model: ModelSummary::from_fit(&base, dt, core),
        fit_percent: fit_b,
        core_model,
    };
    let (extended, gain, rms_e) = if effects.is_empty() {
        sim_e = sim_b.clone();
        (None, None, None)
    } else {
        sim_e.resize(ctx.sig.u.len(), 0.0);
        simulate(&cur.model, &ctx.sig, &mut sim_e);
        let (fit_e, rms_e) = (extended_cv.mean, extended_cv.rms);
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
    // What the effects say about this record (a confounded effect, one that could not have
    // shown), in the order of their kinds.
    let model = if extended.is_some() {
        "extended"
    } else {
        "baseline"
    };
    let mut said: Vec<Warning> = REGISTRY
        .iter()
        .filter_map(|e| {
            let found = findings.iter().any(|f| f.effect == e.name());
            e.warning(ctx, &cur, found, model)
        })
        .collect();
    said.sort_by_key(|w| w.kind);
    warnings.extend(said);
    // The published (extended) model's lead: a canonical form may have moved it into the
    // dead time (`super::lead::canonical`).
    let lead = cur.model.core.lead;
    Diagnosis {
        source: Default::default(),
        input_lead: (lead > 0.0).then_some(InputLead {
            samples: lead,
            seconds: lead * dt,
        }),
        baseline,
        findings,
        extended,
        gain,
        split: Split {
            estimation: [ctx.est.start, ctx.est.end],
            validation: [ctx.val.start, ctx.val.end],
        },
        validation: Validation {
            method: folds.method,
            folds: folds
                .folds
                .iter()
                .zip(base_cv.fits.iter().zip(&extended_cv.fits))
                .map(|(r, (&b, &e))| FoldFit {
                    samples: [r.start, r.end],
                    baseline_fit_percent: b,
                    fit_percent: e,
                })
                .collect(),
            baseline_mean_fit_percent: base_cv.mean,
            mean_fit_percent: extended_cv.mean,
        },
        noise_floor,
        residual,
        verdict,
        warnings,
        rejected,
        stand: None,
        stand_model: None,
        traces: Traces {
            dt_s: dt,
            rules: ctx.rules,
            u: ctx.sig.u.to_vec(),
            y: ctx.sig.y.to_vec(),
            baseline: sim_b,
            extended: sim_e,
            stabilization: era.and_then(|e| {
                let s = e.stabilization.clone()?;
                Some((s, e.report.fn_hz, e.report.zeta))
            }),
            model: cur.model.clone(),
            refs: [ctx.sig.u_ref, ctx.sig.v_ref],
        },
    }
}
