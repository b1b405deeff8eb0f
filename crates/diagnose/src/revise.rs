//! Undoing a greedy choice of the forward search ([`super::search`]): the revision step run each
//! time the forward additions stop.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/revise.rs`.

use super::ctx::Ctx;
use super::effect::Effect;
use super::effects::REGISTRY;
use super::fit::Fit;
use super::folds::{cross_validate, Folds, HeldOutGain, Scores};
use super::model::Model;
use super::spectrum::band_level;
use crate::thresholds::{MIN_RMS_DROP, SCORE_THRESHOLD};
use propid_numerics::EffectName;

/// Parameters of a term: its free ones, and one for a term without any (a delay or a clip
/// level searched on a grid is one parameter all the same).
pub fn param_count(m: &Model, name: EffectName) -> usize {
    m.term(name).map_or(0, |t| t.free().len().max(1))
}

/// `m` without the term of effect `name`.
pub fn without(m: &Model, name: EffectName) -> Model {
    m.terms()
        .filter(|t| t.name() != name)
        .fold(Model::new(m.core), |acc, t| acc.with_boxed(t.clone_box()))
}

/// The addition tests of the search for `after` = `before` + effect `name`: the score
/// `n ln(SSE_before / SSE_after)` when it passes them (score, RMS drop, plausibility, and the
/// effect's own test that the data can tell it apart, [`Effect::identifiable`]); for a term
/// with a band ([`Term::band_hz`](super::effect::Term::band_hz)) that fails the score, its
/// local score ([`local_score`]) when that passes.
pub fn passes(ctx: &Ctx, before: &Fit, after: &Fit, name: EffectName) -> Option<f64> {
    assess(ctx, before, after, name).ok()
}

/// Why an extension failed the addition tests: its score (NaN when the fit is unusable) and
/// the reason in words.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// `n ln(SSE_before / SSE_after)`.
    pub score: f64,
    /// The test it failed, in words.
    pub reason: String,
}

impl Refusal {
    /// Whether it fits in-sample (its score passed the threshold): a refusal worth telling
    /// ([`super::rejected`]).
    pub fn fits(&self) -> bool {
        self.score >= SCORE_THRESHOLD
    }
}

/// [`passes`] with the reason of a refusal. The tests in order: a usable fit, the score (or
/// the local score of a term with a band), the RMS drop, plausibility, then [`Effect::identifiable`] (last: it may fit again).
pub fn assess(ctx: &Ctx, before: &Fit, after: &Fit, name: EffectName) -> Result<f64, Refusal> {
    let usable = after.sse.is_finite() && after.sse > 0.0 && before.sse > 0.0;
    if !usable {
        return Err(Refusal {
            score: f64::NAN,
            reason: "the fit failed".into(),
        });
    }
    let score = after.n as f64 * (before.sse / after.sse).ln();
    let rms_drop = 1.0 - (after.sse / before.sse).sqrt();
    let refuse = |reason: String| Err(Refusal { score, reason });
    let score = if score >= SCORE_THRESHOLD {
        score
    } else {
        match local_score(ctx, before, after, name).filter(|s| *s >= SCORE_THRESHOLD) {
            Some(local) => local,
            None => return refuse(format!("score below {SCORE_THRESHOLD}")),
        }
    };
    if rms_drop < MIN_RMS_DROP {
        return refuse(format!(
            "lowers the estimation residual RMS by only {:.2} % (< {:.0} %): not taken",
            100.0 * rms_drop,
            100.0 * MIN_RMS_DROP
        ));
    }
    let plausible = after
        .model
        .term(name)
        .is_some_and(|t| t.plausible(ctx, &after.model.core, after.model.has_nan()));
    if !plausible {
        return refuse("fits in-sample but with physically implausible values: not taken".into());
    }
    // Every parameter moves in the joint fit: a term taken earlier may leave its plausible
    // range once this one is in (krull's staircase: a direction's time constant of 0.1 ms at
    // 50 Hz once a cubic stiffness joined). Such a model is an artefact too.
    if let Some(t) = after
        .model
        .terms()
        .find(|t| t.name() != name && !t.plausible(ctx, &after.model.core, after.model.has_nan()))
    {
        return refuse(format!(
            "fits in-sample but drives {} to physically implausible values: not taken",
            t.name()
        ));
    }
    if let Some(e) = REGISTRY.iter().find(|e| e.name() == name) {
        if let Err(reason) = e.identifiable(ctx, before, after) {
            return refuse(reason);
        }
    }
    Ok(score)
}

/// The score of an additive narrowband output term (a drift, a sinusoid) against the
/// residual's level in its own band: `n ln(1 + (SSE_before − SSE_after) / (n σ²_B))`, with
/// `σ²_B` the mean periodogram of `after`'s estimation residual over the term's band `B`
/// ([`band_level`]). For white noise `σ²_B ≈ SSE_after / n` and it is the score itself; on a
/// measured log whose residual is dominated by a misfit elsewhere in the spectrum (a sweep
/// through a lightly damped mode) it is the likelihood-ratio test under that coloured noise
/// (Whittle: the noise's variance at a frequency is its spectral density there), where the
/// white-noise score, which counts the whole misfit as noise, misses a drift or a sinusoid
/// that stands well clear of it. `None` for a term without a band.
pub fn local_score(ctx: &Ctx, before: &Fit, after: &Fit, name: EffectName) -> Option<f64> {
    let band = after
        .model
        .term(name)?
        .band_hz(ctx.est.len(), ctx.sig.dt_s)?;
    let level = band_level(&ctx.residual(after), ctx.sig.dt_s, band, None)?;
    let n = after.n as f64;
    let gain = (before.sse - after.sse) / (n * level);
    (level > 0.0 && gain.is_finite()).then(|| n * gain.ln_1p())
}

/// A change of the model proposed by the revision (module doc).
#[derive(Debug)]
pub enum Change {
    /// Effect `out` leaves; `fit` is the model without it.
    Remove { out: EffectName, fit: Fit },
    /// Effect `out` is replaced by `into`: `fit` is `R + into`, `score` and `base` are
    /// `into`'s score on `R` and `R` itself.
    Swap {
        out: EffectName,
        into: EffectName,
        fit: Fit,
        score: f64,
        base: Fit,
    },
    /// Effect `into` joins (with `X` refitted afresh): `fit` is the new model, `score` its
    /// score against the current one.
    Add {
        into: EffectName,
        fit: Fit,
        score: f64,
    },
}

/// What the revision kept: the change, the new model's held-out scores, and (for a swap) the
/// held-out scores of `R`.
pub struct Kept {
    /// The change.
    pub change: Change,
    /// Held-out scores of the changed model.
    pub cv: Scores,
    /// For a swap: held-out scores of the model without `out` (the gain of `into` is measured
    /// against it).
    pub base_cv: Option<Scores>,
}

/// The revision step (module doc) on the current fit `cur` (held-out scores `cur_cv`):
/// `searched` are the effects the forward search took (in the model); additions are proposed
/// only when `may_add` (the model has room for one more effect). The first change that the
/// held-out figure keeps, or `None`.
pub fn revise(
    ctx: &Ctx,
    folds: &Folds,
    cur: &Fit,
    cur_cv: &Scores,
    searched: &[EffectName],
    may_add: bool,
) -> Option<Kept> {
    let cv = |f: &Fit| cross_validate(ctx, folds, f);
    let mut removals = Vec::new();
    let mut swaps: Vec<(usize, f64, Change)> = Vec::new();
    let mut adds: Vec<(f64, Change)> = Vec::new();
    // Terms the current model holds at physically implausible values (a joint refit moved
    // them there, the supply's side settled after them): removed whatever the held-out figure
    // says, as an implausible addition is refused whatever it gains.
    let implausible: Vec<EffectName> = searched
        .iter()
        .copied()
        .filter(|&x| {
            cur.model
                .term(x)
                .is_some_and(|t| !t.plausible(ctx, &cur.model.core, cur.model.has_nan()))
        })
        .collect();
    for &x_name in searched {
        let Some(x) = REGISTRY.iter().find(|e| e.name() == x_name) else {
            continue;
        };
        let reduced = without(&cur.model, x_name);
        let r = ctx.best_of([reduced], 1);
        if !r.sse.is_finite() || r.n == 0 {
            continue;
        }
        if passes(ctx, &r, cur, x_name).is_none() {
            removals.push(Change::Remove {
                out: x_name,
                fit: r,
            });
            continue;
        }
        let k_x = param_count(&cur.model, x_name);
        let open: Vec<&'static dyn Effect> = REGISTRY
            .iter()
            .copied()
            .filter(|y| cur.model.term(y.name()).is_none())
            .collect();
        // Each replacement's fit and tests are independent of the others': on every core.
        let tried = crate::par::map(&open, |&y| {
            let y_name = y.name();
            let f = y.extend(ctx, &r)?;
            let score = passes(ctx, &r, &f, y_name)?;
            let into = refit_into(ctx, *x, &f);
            Some((y_name, f, score, into))
        });
        for (y_name, f, score, into) in tried.into_iter().flatten() {
            match into {
                None => {
                    let k_y = param_count(&f.model, y_name);
                    if k_y < k_x || (k_y == k_x && f.sse < cur.sse) {
                        swaps.push((
                            k_y,
                            f.sse,
                            Change::Swap {
                                out: x_name,
                                into: y_name,
                                fit: f,
                                score,
                                base: r.clone(),
                            },
                        ));
                    }
                }
                Some(g) if may_add => {
                    if let Some(s) = passes_against(ctx, cur, &g, &[x_name, y_name]) {
                        adds.push((
                            s,
                            Change::Add {
                                into: y_name,
                                fit: g,
                                score: s,
                            },
                        ));
                    }
                }
                Some(_) => {}
            }
        }
    }
    swaps.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    adds.sort_by(|a, b| b.0.total_cmp(&a.0));
    let ordered = removals
        .into_iter()
        .chain(swaps.into_iter().map(|s| s.2))
        .chain(adds.into_iter().map(|a| a.1));
    for change in ordered {
        let fit = match &change {
            Change::Remove { fit, .. } | Change::Swap { fit, .. } | Change::Add { fit, .. } => fit,
        };
        let f_cv = cv(fit);
        // An addition is kept when its held-out gain passes the acceptance test
        // (`HeldOutGain`), a removal when the effect's gain over the model without it does
        // not (or it is implausible), a swap when the figure does not fall.
        let kept = match change {
            Change::Add { .. } => HeldOutGain::of(cur_cv, &f_cv).accepted(ctx.gate),
            Change::Remove { out, .. } if implausible.contains(&out) => true,
            Change::Remove { .. } => !HeldOutGain::of(&f_cv, cur_cv).accepted(ctx.gate),
            Change::Swap { .. } => f_cv.mean >= cur_cv.mean,
        };
        if kept {
            let base_cv = match &change {
                Change::Swap { base, .. } => Some(cv(base)),
                _ => None,
            };
            return Some(Kept {
                change,
                cv: f_cv,
                base_cv,
            });
        }
    }
    None
}

/// Effect `x` fitted afresh on `f`: the extended fit when `x` passes the addition tests there,
/// `None` when it does not (once `f`'s new effect is in, `x` explains nothing more).
fn refit_into(ctx: &Ctx, x: &dyn Effect, f: &Fit) -> Option<Fit> {
    let g = x.extend(ctx, f)?;
    passes(ctx, f, &g, x.name()).map(|_| g)
}

/// The addition tests for `after` against `before` where `after` has the terms `names`
/// (plausible each): the score when it passes.
fn passes_against(ctx: &Ctx, before: &Fit, after: &Fit, names: &[EffectName]) -> Option<f64> {
    let mut score = None;
    for n in names {
        score = Some(passes(ctx, before, after, *n)?);
    }
    score
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::dead_time::DeadTimeParams;
    use crate::effects::extra_mode::ExtraModeParams;
    use crate::signals::Core;

    fn model() -> Model {
        Model::new(Core::default())
            .with(DeadTimeParams::throttle(2))
            .with(ExtraModeParams {
                fn_hz: 5.0,
                zeta: 0.1,
                gain: 1.0,
            })
    }

    #[test]
    fn a_delay_counts_one_parameter_and_a_mode_three() {
        let m = model();
        assert_eq!(param_count(&m, EffectName::DeadTime), 1);
        assert_eq!(param_count(&m, EffectName::ExtraMode), 3);
        assert_eq!(param_count(&m, EffectName::SupplySag), 0);
    }

    /// A lightly damped 2nd-order plant behind a dead time of 3 samples, driven by a staircase
    /// with a small deterministic noise. The mode that fits it best in the delay's place has a
    /// share above 1 (an inverse response: the Padé stand-in for a delay,
    /// [`crate::effects::extra_mode::MAX_SHARE`]) and fails the addition tests; the
    /// same mode with share 1 (a plain lag in series, plausible) still takes up part of the
    /// delay, and the greedy model that holds it must be revised: the mode swapped for the
    /// delay (one parameter, and the mode adds nothing once the delay is in), with its length.
    #[test]
    fn a_delay_fitted_as_an_extra_mode_is_swapped_back() {
        use crate::model::simulate;
        use crate::signals::Signals;
        let dt = 0.01;
        let levels = [0.3, 0.6, 0.4, 0.8, 0.5, 0.7, 0.35, 0.65];
        let u: Vec<f64> = levels
            .iter()
            .flat_map(|&l| std::iter::repeat(l).take(150))
            .collect();
        let truth = Model::new(Core {
            fn_hz: 4.0,
            zeta: 0.3,
            gain: 2.0,
            offset: 0.1,
            lead: 0.0,
        })
        .with(DeadTimeParams::throttle(3));
        let mut y = vec![0.0; u.len()];
        let sig0 = Signals {
            dt_s: dt,
            u: &u,
            y: &y.clone(),
            voltage: None,
            u_ref: 0.5,
            v_ref: 0.0,
        };
        simulate(&truth, &sig0, &mut y);
        for (k, v) in y.iter_mut().enumerate() {
            *v += 0.002 * ((k as f64 * 1.7).sin() + (k as f64 * 0.37).cos());
        }
        let rules = propid_numerics::segment::SegmentRules::DEFAULT;
        let folds = Folds::from_input(&u, &y, 0.7, &rules);
        let mean = u.iter().sum::<f64>() / u.len() as f64;
        let ctx = Ctx {
            sig: Signals {
                dt_s: dt,
                u: &u,
                y: &y,
                voltage: None,
                u_ref: mean,
                v_ref: 0.0,
            },
            est: folds.estimation.clone(),
            val: 0..u.len(),
            rules: propid_numerics::segment::SegmentRules::DEFAULT,
            gate: Default::default(),
        };
        let base = ctx.best_of(
            [1.0, 2.0, 4.0, 8.0].map(|f| {
                Model::new(Core {
                    fn_hz: f,
                    ..Core::default()
                })
            }),
            2,
        );
        let greedy = crate::effects::extra_mode::ExtraMode
            .extend(&ctx, &base)
            .expect("a mode can be fitted");
        assert!(greedy.sse < base.sse, "the mode takes up part of the delay");
        let mode = |m: &Model| m.term(EffectName::ExtraMode).map(|t| t.finding_params(dt));
        let share = mode(&greedy.model)
            .and_then(|p| p["gain"].as_f64())
            .unwrap();
        assert!(
            share > 1.05,
            "the stand-in's inverse response: share {share}"
        );
        assert!(passes(&ctx, &base, &greedy, EffectName::ExtraMode).is_none());
        // A mode with share 1 in the delay's place: the best of a grid of lags in series,
        // the core's linear parameters refitted.
        let greedy = (1..=12)
            .flat_map(|i| [0.5, 0.7, 1.0, 1.5].map(|zeta| (4.0 * i as f64, zeta)))
            .map(|(fn_hz, zeta)| {
                let lag = base.model.with(ExtraModeParams {
                    fn_hz,
                    zeta,
                    gain: 1.0,
                });
                let (lag, _) = crate::fit::linear_refit(&lag, &ctx.sig, ctx.est.clone());
                let (sse, n) = crate::fit::sse(&lag, &ctx.sig, ctx.est.clone(), &mut Vec::new());
                Fit { model: lag, sse, n }
            })
            .min_by(|a, b| a.sse.total_cmp(&b.sse))
            .unwrap();
        assert!(
            greedy.sse < base.sse,
            "a lag in series takes up part of the delay too"
        );
        let cv = cross_validate(&ctx, &folds, &greedy);
        let kept = revise(&ctx, &folds, &greedy, &cv, &[EffectName::ExtraMode], true)
            .expect("a change is kept");
        match kept.change {
            Change::Swap { out, into, fit, .. } => {
                assert_eq!((out, into), (EffectName::ExtraMode, EffectName::DeadTime));
                let d = fit
                    .model
                    .term(EffectName::DeadTime)
                    .map(|t| t.finding_params(dt));
                assert_eq!(d.and_then(|p| p["delay_samples"].as_u64()), Some(3));
            }
            other => panic!("expected a swap, got {other:?}"),
        }
        assert!(kept.cv.mean >= cv.mean);
    }

    /// An addition whose joint fit leaves an earlier term outside its plausible range is
    /// refused, and the refusal names that term (cf21: a delay beside a series mode whose share
    /// went to −2.8); the same addition with the earlier term in range passes.
    #[test]
    fn an_addition_that_drives_an_earlier_term_implausible_is_refused() {
        let (u, y) = (vec![0.5; 100], vec![0.0; 100]);
        let ctx = Ctx::whole(0.01, &u, &y);
        let fit = |model: Model, sse: f64| Fit { model, sse, n: 100 };
        let mode = |gain: f64| ExtraModeParams {
            fn_hz: 2.0,
            zeta: 0.2,
            gain,
        };
        let before = fit(Model::new(Core::default()).with(mode(1.0)), 1.0);
        let with_delay = |gain: f64| {
            fit(
                Model::new(Core::default())
                    .with(mode(gain))
                    .with(DeadTimeParams::throttle(3)),
                0.5,
            )
        };
        let refused = assess(&ctx, &before, &with_delay(-2.8), EffectName::DeadTime).unwrap_err();
        assert!(refused.reason.contains("drives extra_mode"), "{refused:?}");
        assert!(assess(&ctx, &before, &with_delay(0.8), EffectName::DeadTime).is_ok());
    }

    /// A drift of 0.6 σ over the record under a strong 12 Hz component that no term models (a
    /// sweep through a lightly damped mode, as in the robot arm log): the white-noise score
    /// counts the 12 Hz power as noise and misses the drift; against the residual's level near
    /// 0 Hz it passes. On white noise alone the local score is the score.
    #[test]
    fn a_drift_under_a_misfit_elsewhere_in_the_spectrum_passes_the_local_test() {
        use crate::effects::baseline_drift::BaselineDriftParams;
        use crate::signals::Signals;
        let (n, dt) = (1000, 0.01);
        let u: Vec<f64> = (0..n).map(|k| 0.5 + 0.1 * ((k / 100) % 2) as f64).collect();
        // The mean of `rate · t` over the record is `rate · 5 s`.
        // White noise, uniform in ±0.02 (xorshift64).
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let white: Vec<f64> = (0..n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                0.02 * (2.0 * (state >> 11) as f64 / (1u64 << 53) as f64 - 1.0)
            })
            .collect();
        let noise = |k: usize| white[k];
        let run = |misfit: f64, rate: f64| {
            let y: Vec<f64> = (0..n)
                .map(|k| {
                    let t = k as f64 * dt;
                    misfit * (2.0 * std::f64::consts::PI * 12.3 * t).sin() + rate * t + noise(k)
                })
                .collect();
            let ctx = Ctx {
                sig: Signals {
                    dt_s: dt,
                    u: &u,
                    y: &y,
                    voltage: None,
                    u_ref: 0.55,
                    v_ref: 0.0,
                },
                est: 0..n,
                val: 0..n,
                rules: propid_numerics::segment::SegmentRules::DEFAULT,
                gate: Default::default(),
            };
            // The model predicts the mean (no gain); the drift term adds the true line.
            let core = Core {
                gain: 0.0,
                offset: rate * 5.0,
                ..Core::default()
            };
            let sse = |m: Model| {
                let f = Fit {
                    model: m,
                    sse: 0.0,
                    n,
                };
                let e = ctx.residual(&f);
                Fit {
                    sse: e.iter().map(|v| v * v).sum(),
                    ..f
                }
            };
            let before = sse(Model::new(core));
            let after = sse(Model::new(Core {
                offset: 0.0,
                ..core
            })
            .with(BaselineDriftParams { rate_per_s: rate }));
            let global = after.n as f64 * (before.sse / after.sse).ln();
            let local = local_score(&ctx, &before, &after, EffectName::BaselineDrift).unwrap();
            (
                global,
                local,
                passes(&ctx, &before, &after, EffectName::BaselineDrift),
            )
        };
        // σ ≈ 0.3 / √2 from the misfit; a drift of 0.6 σ over 10 s (its RMS drop passes the
        // 1 % floor, which stays as it is).
        let (global, local, pass) = run(0.3, 0.6 * 0.21 / 10.0);
        assert!(global < SCORE_THRESHOLD, "global {global}");
        assert!(
            local >= SCORE_THRESHOLD && pass == Some(local),
            "global {global} local {local} {pass:?}"
        );
        let (global, local, _) = run(0.0, 0.0005);
        assert!(
            (local / global - 1.0).abs() < 0.5,
            "global {global}, local {local}"
        );
    }

    #[test]
    fn without_drops_one_term_and_keeps_the_rest() {
        let m = without(&model(), EffectName::ExtraMode);
        assert!(m.term(EffectName::ExtraMode).is_none());
        assert!(m.term(EffectName::DeadTime).is_some());
        assert_eq!(m.core, Core::default());
    }
}
