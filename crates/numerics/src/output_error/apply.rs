//! The refinement of an OKID + ERA identification ([`refine`]) and the published model it
//! replaces ([`apply`]): the output-error model replaces the realisation only where its
//! held-out free-run score beats the realisation's own on the same tail (the realisation
//! was fitted on the whole record, tail included, so the comparison favours it).

use nalgebra::Complex;
use serde::Serialize;

use super::fit::Data;
use super::model::OeModel;
use super::select::{arx_poles, era_poles, select, split, tail_score_abcd};
use super::select::{Candidate, SelectOptions, Start};
use crate::identify::{AnyInput, AnyModel, PathTaken};
use crate::modal::{continuous, fn_zeta};
use crate::report::Gain;
use crate::ModelReport;

/// What the refinement found (`identify --json`'s `"refinement"`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refinement {
    /// Whether the refined model replaced the realisation.
    pub applied: bool,
    /// Samples fitted before the held-out tail; the tail is the rest.
    pub fit_samples: usize,
    /// Held-out samples.
    pub holdout_samples: usize,
    /// The realisation's held-out RMS per output and score.
    pub era_tail_rms: Vec<f64>,
    /// The realisation's score (`mean_i RMS_i / std_i` on the tail).
    pub era_score: f64,
    /// The chosen candidate (order, integrator, start, held-out RMS and score).
    pub chosen: Candidate,
    /// Every candidate tried.
    pub candidates: Vec<Candidate>,
    /// The refined model (refitted on the whole record).
    #[serde(skip)]
    pub model: OeModel,
}

/// Refines `model` (an OKID + ERA identification of the one-input record `input`) by the
/// output-error fit of [`super`]; `None` on the pulse path, with several inputs, or when no
/// candidate could be fitted.
pub fn refine(input: &AnyInput<'_>, model: &AnyModel, opts: &SelectOptions) -> Option<Refinement> {
    if model.path != PathTaken::Okid || input.u.len() != 1 || input.y.is_empty() {
        return None;
    }
    let data = Data {
        u: input.u[0],
        y: input.y,
        missing: input.missing,
    };
    let n_fit = split(data.len(), opts.holdout);
    // A tail too short to judge anything: no refinement.
    if data.len() - n_fit < 20 || n_fit < 50 {
        return None;
    }
    let mut starts: Vec<(Start, Vec<Complex<f64>>)> = Vec::new();
    if let Some(stab) = &model.stabilization {
        for z in era_poles(stab, input.dt_s) {
            starts.push((Start::Era, z));
        }
    }
    // The published realisation's own poles (its order is one row of the diagram).
    starts.push((
        Start::Era,
        model
            .report
            .poles_z
            .iter()
            .map(|p| Complex::new(p[0], p[1]))
            .collect(),
    ));
    for n in 1..=opts.max_order {
        if let Some(z) = arx_poles(&data, n, n_fit) {
            starts.push((Start::Arx, z));
        }
    }
    let sel = select(&data, &starts, opts)?;
    let r = &model.report;
    let (era_tail_rms, era_score) = tail_score_abcd(&r.a, &r.b, &r.c, &r.d, &data, opts.holdout);
    let chosen = sel.best().clone();
    let applied = chosen.score < era_score || !era_score.is_finite();
    Some(Refinement {
        applied,
        fit_samples: sel.n_fit,
        holdout_samples: data.len() - sel.n_fit,
        era_tail_rms,
        era_score,
        chosen,
        candidates: sel.candidates,
        model: sel.model,
    })
}

/// `report` with the model `m` in place of the realisation: order, `A, B, C, D`, poles,
/// time constants, dominant `fn`/`ζ` and DC gain (null with the integrator: the pole at
/// `z = 1` has none). The Hankel figures, indicators and uncertainty stay the realisation's.
pub fn apply(report: &mut ModelReport, m: &OeModel) {
    let dt = report.dt_s;
    let (a, b, c, d) = m.abcd();
    report.order = m.order();
    report.a = a;
    report.b = b;
    report.c = c;
    report.d = d;
    let z = m.poles();
    report.poles_z = z.iter().map(|p| [p.re, p.im]).collect();
    let s: Vec<Complex<f64>> = z
        .iter()
        .map(|&p| {
            if p == Complex::new(1.0, 0.0) {
                Complex::new(0.0, 0.0)
            } else {
                continuous(p, dt)
            }
        })
        .collect();
    report.poles_s = s.iter().map(|p| [p.re, p.im]).collect();
    report.time_constants_s = s
        .iter()
        .zip(&z)
        .filter(|(s, z)| z.im == 0.0 && s.re < 0.0)
        .map(|(s, _)| -1.0 / s.re)
        .collect();
    // The dominant pair: the least damped in time (largest Re s).
    let pair = m
        .pairs
        .iter()
        .map(|&(sg, w)| {
            let s1 = continuous(Complex::new(sg, w), dt);
            fn_zeta(s1, s1.conj())
        })
        .filter(|(f, z)| f.is_finite() && z.is_finite())
        .min_by(|x, y| (x.0 * x.1).total_cmp(&(y.0 * y.1)));
    (report.fn_hz, report.zeta) = pair.unwrap_or((f64::NAN, f64::NAN));
    let gains = m.dc_gain().unwrap_or_else(|| vec![f64::NAN; m.outputs()]);
    report.dc_gain = Gain::from_block(&gains, gains.len(), 1);
}
