//! The forward search over the catalogue of effects, from the baseline of [`crate::baseline`].
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/search.rs`.

use crate::thresholds::{MAX_REVISIONS, MIN_CV_GAIN_PP};
use propid_numerics::EffectName;

use super::baseline::baseline;
use super::ctx::Ctx;
use super::effect::Effect;
use super::effects::REGISTRY;
use super::finding::Finding;
use super::fit::Fit;
use super::folds::{cross_validate, Folds, HeldOutGain, Method, Scores};
use super::lead;
use super::model::Model;
use super::pair::{joint_evidence, select_pair};
use super::rejected::{Ledger, Rejected};
use super::revise::{assess, revise, Change, Kept};
use super::signals::Core;

/// What the search found.
#[derive(Debug, Clone)]
pub struct Searched {
    /// The 2nd-order baseline (no effect).
    pub base: Fit,
    /// Its held-out scores.
    pub base_cv: Scores,
    /// The model with every effect found.
    pub extended: Fit,
    /// Its held-out scores (equal to the baseline's when nothing was found).
    pub extended_cv: Scores,
    /// The findings, in the order found.
    pub findings: Vec<Finding>,
    /// The candidates that fitted in-sample and were not taken ([`super::rejected`]).
    pub rejected: Vec<Rejected>,
}

impl Searched {
    /// Names of the effects found, in the order found.
    pub fn effects(&self) -> Vec<EffectName> {
        self.findings.iter().map(|f| f.effect).collect()
    }
}

/// Runs the search (module doc) with the core's model as an extra start of the baseline and
/// `folds` for the held-out figure, at the input lead the record shows (once more at the lead
/// the final model shows, when that differs); `None` when the baseline cannot be fitted
/// (non-finite SSE or no sample counted).
pub fn search(
    ctx: &Ctx,
    folds: &Folds,
    era_starts: &[Core],
    max_effects: usize,
) -> Option<Searched> {
    let base = lead::baseline_with_lead(ctx, era_starts);
    let first = search_from(ctx, folds, base, era_starts, max_effects)?;
    // A lead the baseline could not show (a static map hid it): the search again with it.
    let Some(lead) = lead::better_lead(ctx, &first.extended) else {
        return Some(first);
    };
    let template = Model::new(Core {
        lead,
        ..Core::default()
    });
    let base = baseline(ctx, &template, era_starts);
    match search_from(ctx, folds, base, era_starts, max_effects) {
        Some(second) if second.extended_cv.mean > first.extended_cv.mean => Some(second),
        _ => Some(first),
    }
}

/// The search from the baseline `base` (its core's lead kept by every model).
fn search_from(
    ctx: &Ctx,
    folds: &Folds,
    base: Fit,
    era_starts: &[Core],
    max_effects: usize,
) -> Option<Searched> {
    let cv = |f: &Fit| cross_validate(ctx, folds, f);
    if !base.sse.is_finite() || base.n == 0 {
        return None;
    }
    let base_cv = cv(&base);
    let mut template = Model::new(Core {
        lead: base.model.core.lead,
        ..Core::default()
    });
    let mut findings = Vec::new();
    let (mut cur, mut cur_cv) = (base.clone(), base_cv.clone());
    for e in REGISTRY {
        if let Some(d) = e.detect(ctx) {
            let evidence = d.term.evidence(&template.core, ctx, "");
            let params = d.term.finding_params(ctx.sig.dt_s);
            let with = template.clone().with_boxed(d.term);
            let f = baseline(ctx, &with, era_starts);
            let f_cv = cv(&f);
            // Read off the data, yet taken only when its held-out gain passes the acceptance
            // test like any other (`HeldOutGain`); else the forward search may try it again.
            if !HeldOutGain::of(&cur_cv, &f_cv).accepted(ctx.gate) {
                continue;
            }
            template = with;
            findings.push(Finding {
                effect: e.name(),
                score: d.score,
                cv_gain_pp: f_cv.mean - cur_cv.mean,
                evidence,
                params,
                drop: String::new(),
            });
            (cur, cur_cv) = (f, f_cv);
        }
    }
    let detected = findings.len();
    let rule = Selection::for_method(folds.method);
    let mut g = Growth {
        findings,
        cur,
        cur_cv,
        ledger: Ledger::default(),
        revisions: 0,
        detected,
    };
    g.grow(ctx, folds, rule, max_effects, &cv);
    // What the supply scales, settled on the model the search ends with; kept only when the
    // held-out figure does not fall. When it changes the model, the search and its revisions
    // run again on it (a term that stood in for the side's misfit can then be removed, and
    // what it kept out taken).
    for e in REGISTRY {
        if let Some(f) = e.settle(ctx, &g.cur) {
            let f_cv = cv(&f);
            if f_cv.mean >= g.cur_cv.mean {
                (g.cur, g.cur_cv) = (f, f_cv);
                g.grow(ctx, folds, rule, max_effects, &cv);
            }
        }
    }
    let Growth {
        mut findings,
        mut cur,
        cur_cv,
        ledger,
        ..
    } = g;
    if let Some(c) = lead::canonical(&cur) {
        cur = c;
    }
    final_values(&mut findings[detected..], &cur, ctx);
    let taken: Vec<EffectName> = findings.iter().map(|f| f.effect).collect();
    Some(Searched {
        base,
        base_cv,
        extended: cur,
        extended_cv: cur_cv,
        findings,
        rejected: ledger.rejected(&taken),
    })
}

/// The search as it grows: the findings (those read off the data first, `detected` of them),
/// the current model and its held-out scores, the candidates not taken, the revisions made.
struct Growth {
    findings: Vec<Finding>,
    cur: Fit,
    cur_cv: Scores,
    ledger: Ledger,
    revisions: usize,
    detected: usize,
}

impl Growth {
    /// Forward steps until none is taken or `max_effects` are in, then a revision
    /// ([`revise`]); again after each kept revision, at most [`MAX_REVISIONS`] in all.
    fn grow(
        &mut self,
        ctx: &Ctx,
        folds: &Folds,
        rule: Selection,
        max_effects: usize,
        cv: &impl Fn(&Fit) -> Scores,
    ) {
        loop {
            while self.findings.len() < max_effects {
                let room = max_effects - self.findings.len();
                let Some(step) = forward(
                    ctx,
                    &self.findings,
                    &self.cur,
                    (&self.cur_cv, rule),
                    cv,
                    &mut self.ledger,
                    room,
                ) else {
                    break;
                };
                for (score, e, gain, with) in step.taken {
                    let mut f = finding(e, score, gain, &self.cur, &step.fit, ctx);
                    if let Some(other) = with {
                        let note = format!(
                            "; taken together with {other}: neither raised the held-out fit \
                             alone, the pair did (the pair's held-out gain is reported on the \
                             stronger of the two, 0 on the other)"
                        );
                        f.drop.push_str(&note);
                        f.evidence.push_str(&note);
                    }
                    self.findings.push(f);
                }
                (self.cur, self.cur_cv) = (step.fit, step.cv);
            }
            let searched: Vec<EffectName> = self.findings[self.detected..]
                .iter()
                .filter_map(|f| REGISTRY.iter().map(|e| e.name()).find(|n| *n == f.effect))
                .collect();
            if self.revisions >= MAX_REVISIONS || searched.is_empty() {
                return;
            }
            let may_add = self.findings.len() < max_effects;
            let Some(kept) = revise(ctx, folds, &self.cur, &self.cur_cv, &searched, may_add) else {
                return;
            };
            self.revisions += 1;
            apply(
                ctx,
                kept,
                &mut self.findings,
                &mut self.cur,
                &mut self.cur_cv,
                &mut self.ledger,
            );
        }
    }
}

/// What one forward step takes: one effect, or a pair ([`super::pair`]), each as (score,
/// effect, held-out gain in pp, the effect it was taken with), and the model with them.
struct Step {
    taken: Vec<(f64, &'static dyn Effect, f64, Option<EffectName>)>,
    fit: Fit,
    cv: Scores,
}

/// One forward step (module doc): every effect not in `findings` fitted on top of `cur`; the
/// candidate the selection rule takes, or when none is and `room` allows two, the pair the
/// pair rule takes ([`super::pair`]). Every candidate that fitted in-sample and was not taken
/// is noted in `ledger` with the reason.
fn forward(
    ctx: &Ctx,
    findings: &[Finding],
    cur: &Fit,
    (cur_cv, rule): (&Scores, Selection),
    cv: &impl Fn(&Fit) -> Scores,
    ledger: &mut Ledger,
    room: usize,
) -> Option<Step> {
    let mut candidates: Vec<(f64, (&'static dyn Effect, Fit))> = Vec::new();
    let open: Vec<&'static dyn Effect> = REGISTRY
        .iter()
        .copied()
        .filter(|e| findings.iter().all(|f| f.effect != e.name()))
        .collect();
    // Each candidate's fit and tests are independent of the others': on every core.
    let fitted = crate::par::map(&open, |&e| {
        let f = e.extend(ctx, cur)?;
        let assessed = assess(ctx, cur, &f, e.name());
        Some((e, f, assessed))
    });
    for (e, f, assessed) in fitted.into_iter().flatten() {
        match assessed {
            Ok(score) => candidates.push((score, (e, f))),
            Err(r) if r.fits() => ledger.note(Rejected {
                effect: e.name(),
                score: r.score,
                cv_gain_pp: None,
                reason: r.reason,
            }),
            // It explains nothing more on this model: an earlier word on it is out of date.
            Err(_) => ledger.forget(e.name()),
        }
    }
    let scores: Vec<(EffectName, f64)> = candidates
        .iter()
        .map(|(s, (e, _))| (e.name(), *s))
        .collect();
    let pool = candidates.clone();
    let cur_figure = cur_cv.mean;
    let mut tried: Vec<(EffectName, HeldOutGain)> = Vec::new();
    let taken = select(rule, candidates, cur_figure, |(e, f)| {
        let s = cv(f);
        let gain = HeldOutGain::of(cur_cv, &s);
        tried.push((e.name(), gain));
        (s.mean, gain.accepted(ctx.gate), s)
    });
    let taken_gain = taken
        .as_ref()
        .map(|(_, (e, _), s)| (e.name(), s.mean - cur_figure));
    for &(name, held) in tried
        .iter()
        .filter(|t| Some(t.0) != taken_gain.map(|t| t.0))
    {
        let score = scores
            .iter()
            .find(|s| s.0 == name)
            .map_or(f64::NAN, |s| s.1);
        let gain = held.gain_pp;
        ledger.note(match taken_gain {
            // Raised the figure within the folds' scatter: not shown by the data.
            _ if gain > MIN_CV_GAIN_PP && !held.accepted(ctx.gate) => {
                Rejected::within_scatter(name, score, &held)
            }
            // Raised the figure, less than the one taken (`Selection::BestFigure`).
            Some((by, by_gain)) if gain > MIN_CV_GAIN_PP => {
                Rejected::outranked(name, score, gain, by, by_gain)
            }
            _ => Rejected::held_out(name, score, gain),
        });
    }
    if let Some((score, (e, f), f_cv)) = taken {
        return Some(Step {
            taken: vec![(score, e, f_cv.mean - cur_figure, None)],
            fit: f,
            cv: f_cv,
        });
    }
    if room < 2 {
        return None;
    }
    let pool_scores: Vec<f64> = pool.iter().map(|c| c.0).collect();
    let (a, b, (score_b, fit, f_cv)) = select_pair(&pool_scores, cur_figure, |a, b| {
        let ((_, (ea, fa)), (_, (eb, fb))) = (&pool[a], &pool[b]);
        let both = eb.extend(ctx, fa)?;
        let score_b = assess(ctx, fa, &both, eb.name()).ok()?;
        assess(ctx, fb, &both, ea.name()).ok()?;
        joint_evidence(cur.sse, both.sse, both.n)?;
        let s = cv(&both);
        // The pair's gain must pass the acceptance test too (`HeldOutGain`).
        HeldOutGain::of(cur_cv, &s)
            .accepted(ctx.gate)
            .then_some(())?;
        Some((s.mean, (score_b, both, s)))
    })?;
    let (ea, eb) = (pool[a].1 .0, pool[b].1 .0);
    for e in [ea, eb] {
        ledger.forget(e.name());
    }
    Some(Step {
        taken: vec![
            (pool[a].0, ea, f_cv.mean - cur_figure, Some(eb.name())),
            (score_b, eb, 0.0, Some(ea.name())),
        ],
        fit,
        cv: f_cv,
    })
}

/// Applies a change the revision kept ([`super::revise`]): a removed effect's finding goes, a
/// swapped-in effect's finding takes the place of the one it replaces (its score and held-out
/// gain measured against the model without the effect it replaces), an added one is appended.
/// An effect that leaves is noted in `ledger` with the revision's reason.
fn apply(
    ctx: &Ctx,
    kept: Kept,
    findings: &mut Vec<Finding>,
    cur: &mut Fit,
    cur_cv: &mut Scores,
    ledger: &mut Ledger,
) {
    let effect = |name: EffectName| REGISTRY.iter().copied().find(|e| e.name() == name);
    let score_of = |before: &Fit, after: &Fit| after.n as f64 * (before.sse / after.sse).ln();
    match kept.change {
        Change::Remove { out, fit } => {
            ledger.note(Rejected {
                effect: out,
                score: score_of(&fit, &*cur),
                cv_gain_pp: Some(cur_cv.mean - kept.cv.mean),
                reason: "taken, then removed by the revision: once the other effects were in, \
                         it no longer passed the addition tests"
                    .into(),
            });
            findings.retain(|f| f.effect != out);
            *cur = fit;
        }
        Change::Swap {
            out,
            into,
            fit,
            score,
            base,
        } => {
            let gain = kept.cv.mean - kept.base_cv.as_ref().map_or(cur_cv.mean, |s| s.mean);
            ledger.note(Rejected {
                effect: out,
                score: score_of(&base, &*cur),
                cv_gain_pp: kept.base_cv.as_ref().map(|s| cur_cv.mean - s.mean),
                reason: format!(
                    "taken, then replaced by {into} in the revision: {into} explains the same \
                     feature of the data with no more parameters and leaves it nothing to add"
                ),
            });
            if let (Some(e), Some(i)) =
                (effect(into), findings.iter().position(|f| f.effect == out))
            {
                findings[i] = finding(e, score, gain, &base, &fit, ctx);
            }
            *cur = fit;
        }
        Change::Add { into, fit, score } => {
            if let Some(e) = effect(into) {
                findings.push(finding(
                    e,
                    score,
                    kept.cv.mean - cur_cv.mean,
                    cur,
                    &fit,
                    ctx,
                ));
            }
            *cur = fit;
        }
    }
    *cur_cv = kept.cv;
}

/// Which of the candidates that raise the held-out figure is taken (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Selection {
    /// The highest held-out figure (blocked cross-validation: a mean over folds).
    BestFigure,
    /// The first in order of score (one hold-out tail: the tail only vetoes).
    FirstByScore,
}

impl Selection {
    /// The rule for a record validated by `method`.
    pub fn for_method(method: Method) -> Selection {
        match method {
            Method::BlockedCv => Selection::BestFigure,
            Method::Holdout => Selection::FirstByScore,
        }
    }
}

/// The selection rule (module doc): the `candidates` (score, item) that passed the score and
/// RMS tests, in order of decreasing score (ties: the first listed), get their held-out figure
/// (`figure` gives it, whether its gain passes the acceptance test of
/// [`HeldOutGain`], and what comes with it); of those that pass it and whose figure exceeds
/// `current` by more than [`MIN_CV_GAIN_PP`], `rule` takes the highest figure (equal figures: the earlier in that
/// order) or the first, with its score and what `figure` gave. `None`: no addition improves
/// the held-out figure. Under [`Selection::FirstByScore`] `figure` runs only until one is
/// taken.
pub fn select<T, S>(
    rule: Selection,
    mut candidates: Vec<(f64, T)>,
    current: f64,
    mut figure: impl FnMut(&T) -> (f64, bool, S),
) -> Option<(f64, T, S)> {
    candidates.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut best: Option<(f64, f64, T, S)> = None;
    for (score, item) in candidates {
        let (fig, accepted, extra) = figure(&item);
        if accepted && fig - current > MIN_CV_GAIN_PP && best.as_ref().map_or(true, |b| fig > b.1) {
            best = Some((score, fig, item, extra));
            if rule == Selection::FirstByScore {
                break;
            }
        }
    }
    best.map(|(score, _, item, extra)| (score, item, extra))
}

/// The finding for effect `e` fitted on top of `before`: parameters from the extended fit,
/// evidence in words.
fn finding(
    e: &dyn Effect,
    score: f64,
    cv_gain_pp: f64,
    before: &Fit,
    after: &Fit,
    ctx: &Ctx,
) -> Finding {
    let rms = |f: &Fit| (f.sse / f.n.max(1) as f64).sqrt();
    let drop = format!(
        "the estimation residual RMS falls from {:.4} to {:.4} ({:.0} % lower)",
        rms(before),
        rms(after),
        100.0 * (1.0 - rms(after) / rms(before).max(1e-300))
    );
    let term = after.model.term(e.name());
    Finding {
        effect: e.name(),
        score,
        cv_gain_pp,
        evidence: term.map_or_else(
            || drop.clone(),
            |t| t.evidence(&after.model.core, ctx, &drop),
        ),
        params: term.map_or_else(Default::default, |t| t.finding_params(ctx.sig.dt_s)),
        drop,
    }
}

/// Every finding's parameters and evidence from the final fit `f` (module doc: a step fits the
/// parameters of the model of that step, and the effects added later move them — an exponent
/// fitted before a supply sag has absorbed part of the sag; the final model fits them all
/// jointly, and it is the model published). The sentence on the residual's drop stays the
/// step's.
fn final_values(findings: &mut [Finding], f: &Fit, ctx: &Ctx) {
    for finding in findings {
        if let Some(t) = f.model.term(finding.effect) {
            finding.params = t.finding_params(ctx.sig.dt_s);
            finding.evidence = t.evidence(&f.model.core, ctx, &finding.drop);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (score, name, held-out figure); the current model's figure is 50. b has the largest
    /// score but lowers the figure; c raises it; d, scored lower (a dead time below a flexible
    /// time scale per direction), raises it more.
    fn four() -> Vec<(f64, (&'static str, f64))> {
        vec![
            (100.0, ("a", 49.0)),
            (300.0, ("b", 48.0)),
            (200.0, ("c", 55.0)),
            (150.0, ("d", 57.0)),
        ]
    }

    #[test]
    fn under_blocked_cv_the_highest_held_out_figure_is_taken() {
        let mut tried = Vec::new();
        let got = select(Selection::BestFigure, four(), 50.0, |&(name, fig)| {
            tried.push(name);
            (fig, true, name)
        });
        assert_eq!(got.map(|g| (g.0, g.2)), Some((150.0, "d")));
        assert_eq!(
            tried,
            ["b", "c", "d", "a"],
            "every candidate is scored held-out"
        );
    }

    #[test]
    fn with_one_tail_the_strongest_candidate_that_raises_it_is_taken() {
        let mut tried = Vec::new();
        let got = select(Selection::FirstByScore, four(), 50.0, |&(name, fig)| {
            tried.push(name);
            (fig, true, name)
        });
        assert_eq!(got.map(|g| (g.0, g.2)), Some((200.0, "c")));
        assert_eq!(
            tried,
            ["b", "c"],
            "the rest is never scored once c is taken"
        );
        assert_eq!(
            Selection::for_method(Method::Holdout),
            Selection::FirstByScore
        );
        assert_eq!(
            Selection::for_method(Method::BlockedCv),
            Selection::BestFigure
        );
    }

    #[test]
    fn an_addition_that_does_not_raise_the_held_out_figure_is_not_taken() {
        for rule in [Selection::BestFigure, Selection::FirstByScore] {
            let c = vec![(500.0, 50.0), (90.0, 49.9)];
            assert!(
                select(rule, c, 50.0, |&fig| (fig, true, ())).is_none(),
                "equal is not better"
            );
            assert!(select(rule, Vec::<(f64, f64)>::new(), 0.0, |&f| (f, true, ())).is_none());
        }
    }

    #[test]
    fn a_gain_inside_the_folds_scatter_is_not_taken() {
        for rule in [Selection::BestFigure, Selection::FirstByScore] {
            // "b" raises the figure most but fails the acceptance test: "c" is taken.
            let c = vec![(300.0, ("b", 58.0, false)), (200.0, ("c", 55.0, true))];
            let got = select(rule, c, 50.0, |&(n, fig, ok)| (fig, ok, n)).map(|g| g.2);
            assert_eq!(got, Some("c"));
            let c = vec![(300.0, ("b", 58.0, false))];
            assert!(select(rule, c, 50.0, |&(n, fig, ok)| (fig, ok, n)).is_none());
        }
    }

    #[test]
    fn ties_go_to_the_higher_score_then_the_first_listed() {
        for rule in [Selection::BestFigure, Selection::FirstByScore] {
            let c = vec![(10.0, "first"), (10.0, "second")];
            let got = select(rule, c, 0.0, |_| (1.0, true, ())).map(|g| g.1);
            assert_eq!(got, Some("first"));
            let c = vec![(10.0, "weaker"), (20.0, "stronger")];
            let got = select(rule, c, 0.0, |_| (1.0, true, ())).map(|g| g.1);
            assert_eq!(got, Some("stronger"));
        }
    }
}
