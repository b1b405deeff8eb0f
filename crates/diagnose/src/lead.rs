//! The input's lead: when, within a sample, a logged command takes effect.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/lead.rs`.

use super::baseline::baseline;
use super::ctx::Ctx;
use super::fit::Fit;
use super::model::Model;
use super::signals::Core;
use crate::thresholds::{MIN_RMS_DROP, SCORE_THRESHOLD};

/// The leads tried, shares of a sample.
pub const LEADS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

/// The baseline at the lead the record shows (module doc): the plain hold's unless a lead
/// beats it by [`SCORE_THRESHOLD`].
pub fn baseline_with_lead(ctx: &Ctx, era_starts: &[Core]) -> Fit {
    let at = |lead: f64| {
        let template = Model::new(Core {
            lead,
            ..Core::default()
        });
        baseline(ctx, &template, era_starts)
    };
    let hold = at(0.0);
    let mut best = hold.clone();
    for &lead in &LEADS[1..] {
        let f = at(lead);
        if f.sse < best.sse {
            best = f;
        }
    }
    if clearly_better(hold.n, hold.sse, best.sse) {
        best
    } else {
        hold
    }
}

/// A lead other than the current one that fits the (extended) model `cur` better by the
/// effects' evidence ([`clearly_better`]; every parameter refitted at each of [`LEADS`], and at
/// the current lead for the comparison): the best such, or `None`.
pub fn better_lead(ctx: &Ctx, cur: &Fit) -> Option<f64> {
    let now = cur.model.core.lead;
    // The current lead refitted as long as the others, so that a fit that was still
    // converging is not taken for a better lead.
    let again = ctx.lm(&cur.model, 30);
    let cur = if again.sse < cur.sse { &again } else { cur };
    let best = LEADS
        .iter()
        .filter(|&&l| l != now)
        .map(|&lead| {
            let core = Core {
                lead,
                ..cur.model.core
            };
            (lead, ctx.lm(&cur.model.with_core(core), 30))
        })
        .min_by(|a, b| a.1.sse.total_cmp(&b.1.sse))?;
    clearly_better(cur.n, cur.sse, best.1.sse).then_some(best.0)
}

/// The effects' own evidence for a change of a fit over `n` samples from SSE `before` to
/// `after`: a score `n ln(before / after)` of at least [`SCORE_THRESHOLD`] and an RMS at least
/// [`MIN_RMS_DROP`] lower.
fn clearly_better(n: usize, before: f64, after: f64) -> bool {
    let score = n as f64 * (before / after).ln();
    after.is_finite() && score >= SCORE_THRESHOLD && (after / before).sqrt() <= 1.0 - MIN_RMS_DROP
}

/// `fit` in canonical form when it has a whole sample of lead beside a dead time of `d ≥ 2`
/// samples: `d − 1` samples and no lead, the same simulation (module doc); `None` otherwise.
/// A share of the delay on the output's side (the voltage as late as the thrust) moves with
/// it; a model whose voltage is read at the throttle's time beside a lead keeps its form.
pub fn canonical(fit: &Fit) -> Option<Fit> {
    let core = fit.model.core;
    let delay = fit.model.terms().find(|t| t.input_delay() > 0)?;
    let (d, s) = (delay.input_delay(), delay.voltage_delay());
    let reads_voltage = fit.model.terms().any(|t| t.reads_voltage());
    if core.lead != 1.0 || d < 2 || (reads_voltage && s == 0) {
        return None;
    }
    let model = fit
        .model
        .with_boxed(delay.one_sample_shorter()?)
        .with_core(Core { lead: 0.0, ..core });
    Some(Fit {
        model,
        ..fit.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::dead_time::{self, DeadTimeParams};
    use crate::model::simulate;
    use crate::signals::Signals;
    use crate::{diagnose, Options};
    use propid_numerics::EffectName;
    use propid_sim::synth;

    #[test]
    fn a_whole_sample_of_lead_beside_a_dead_time_is_published_as_one_sample_less() {
        let u: Vec<f64> = (0..300).map(|k| [0.2, 0.6, 0.4][(k / 60) % 3]).collect();
        let y = vec![0.0; u.len()];
        let sig = Signals {
            dt_s: 0.01,
            u: &u,
            y: &y,
            voltage: None,
            u_ref: 0.4,
            v_ref: 0.0,
        };
        let core = Core {
            fn_hz: 4.0,
            zeta: 0.9,
            gain: 3.0,
            lead: 1.0,
            ..Core::default()
        };
        let fit = |d| Fit {
            model: Model::new(core).with(DeadTimeParams::throttle(d)),
            sse: 1.0,
            n: 300,
        };
        let c = canonical(&fit(4)).expect("a canonical form");
        assert_eq!(c.model.core.lead, 0.0);
        assert_eq!(c.model.term(dead_time::NAME).unwrap().input_delay(), 3);
        let (mut a, mut b) = (vec![0.0; u.len()], vec![0.0; u.len()]);
        simulate(&fit(4).model, &sig, &mut a);
        simulate(&c.model, &sig, &mut b);
        for k in 0..u.len() - 1 {
            assert!((a[k] - b[k]).abs() < 1e-12, "{k}: {} vs {}", a[k], b[k]);
        }
        // One sample of dead time stays beside the lead (it would leave no dead time), and a
        // lead short of a sample is no whole sample.
        assert!(canonical(&fit(1)).is_none());
        let mut partial = fit(4);
        partial.model.core.lead = 0.75;
        assert!(canonical(&partial).is_none());
    }

    #[test]
    fn a_same_row_logger_gets_a_lead_and_a_held_input_none() {
        // The detection table's clean plants (a zero-order hold: the plain hold, no lead), and
        // the same plants logged one sample later beside their command (y'_k = y_{k+1}: the
        // thrust read after the command was sent, both on one row): a lead, and no dead time.
        for i in 0..3 {
            let (_, m) = synth::case(None, i).unwrap();
            let held = diagnose(synth::DT_S, &m.u, &m.y, &[], None, &Options::default());
            let held = held.unwrap();
            assert!(held.input_lead.is_none(), "{i}: {:?}", held.input_lead);
            let n = m.y.len() - 1;
            let early = diagnose(
                synth::DT_S,
                &m.u[..n],
                &m.y[1..],
                &[],
                None,
                &Options::default(),
            );
            let early = early.unwrap();
            let lead = early.input_lead.expect("a lead");
            assert!(lead.samples >= 0.75, "{i}: {lead:?}");
            assert!((lead.seconds - lead.samples * synth::DT_S).abs() < 1e-12);
            // The lead costs the baseline nothing on the early log (within a point of the
            // plain log's fit).
            assert!(
                early.baseline.fit_percent > held.baseline.fit_percent - 1.0,
                "{i}: {} vs {}",
                early.baseline.fit_percent,
                held.baseline.fit_percent
            );
            assert!(
                early
                    .findings
                    .iter()
                    .all(|f| f.effect != EffectName::DeadTime),
                "{i}"
            );
        }
    }
}
