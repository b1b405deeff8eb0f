//! How a diagnosis is validated: blocked cross-validation over the command's steps, or a hold-out
//! tail when the command has no steps.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/folds.rs`.

use std::ops::Range;

use propid_numerics::segment::{levels, Command, SegmentRules};
use serde::Serialize;

use super::ctx::Ctx;
use super::fit::{levenberg_marquardt_from, FirstJacobian, Fit};
use super::model::simulate;
use super::signals::Signals;
pub use crate::thresholds::Gate;
use crate::thresholds::{gain_t, MIN_CV_GAIN_PP};

/// Fewest levels for blocked cross-validation (fewer: the hold-out tail).
pub const MIN_FOLDS: usize = 3;
/// Most folds: levels beyond this many are grouped into consecutive blocks.
pub const MAX_FOLDS: usize = 10;
/// Fewest measured outputs in a fold; a block with fewer joins the one before it.
pub const MIN_FOLD_SAMPLES: usize = 20;
/// Levenberg–Marquardt steps of each fold's refit (from the fit on all samples).
pub const FOLD_ITERS: usize = 20;
/// Blocks the hold-out tail is cut into for the scatter of its fit ([`Scores::blocks`]).
pub const HOLDOUT_BLOCKS: usize = 5;

/// How the held-out figure is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Blocked cross-validation over whole levels of the command.
    BlockedCv,
    /// One hold-out tail (the command has no steps).
    Holdout,
}

/// The folds of a record.
#[derive(Debug, Clone, PartialEq)]
pub struct Folds {
    /// The method.
    pub method: Method,
    /// The held-out samples of each fold (half-open, in order). Under [`Method::Holdout`] one
    /// fold, the tail.
    pub folds: Vec<Range<usize>>,
    /// The samples the published models are fitted on: all of them under
    /// [`Method::BlockedCv`], the head before the tail under [`Method::Holdout`].
    pub estimation: Range<usize>,
}

impl Folds {
    /// The folds of the command `u` with output `y` (`NaN` = missing; see the module doc);
    /// `estimation_fraction` is the head's share when the command has no steps; `rules` are
    /// the segmentation's at the record's rate.
    pub fn from_input(
        u: &[f64],
        y: &[f64],
        estimation_fraction: f64,
        rules: &SegmentRules,
    ) -> Folds {
        let n = u.len().min(y.len());
        let u = &u[..n];
        let measured = |r: &Range<usize>| y[r.clone()].iter().filter(|v| v.is_finite()).count();
        let lv = levels(Command::new(u), rules);
        if lv.len() >= MIN_FOLDS {
            let mut cuts: Vec<usize> = if 2 * lv.len() <= MAX_FOLDS {
                // Few levels: each level is two blocks, the step into it with the first half
                // of its hold, and the rest of the hold.
                lv.iter()
                    .flat_map(|l| [l.start, l.start + (l.end - l.start) / 2])
                    .collect()
            } else {
                // Many levels: blocks of consecutive whole levels, block b holding levels
                // [b·L/k, (b+1)·L/k).
                let k = lv.len().min(MAX_FOLDS);
                (0..k).map(|b| lv[b * lv.len() / k].start).collect()
            };
            cuts[0] = 0;
            cuts.push(n);
            let mut folds: Vec<Range<usize>> = Vec::new();
            for w in cuts.windows(2) {
                let r = w[0]..w[1];
                match folds.last_mut() {
                    Some(last) if measured(&r) < MIN_FOLD_SAMPLES => last.end = r.end,
                    _ => folds.push(r),
                }
            }
            if folds.len() >= MIN_FOLDS && measured(&folds[0]) >= MIN_FOLD_SAMPLES {
                return Folds {
                    method: Method::BlockedCv,
                    folds,
                    estimation: 0..n,
                };
            }
        }
        let n_est = ((n as f64) * estimation_fraction.clamp(0.3, 0.9)).round() as usize;
        Folds {
            method: Method::Holdout,
            folds: std::iter::once(n_est..n).collect(),
            estimation: 0..n_est,
        }
    }
}

/// The held-out scores of one model structure.
#[derive(Debug, Clone, PartialEq)]
pub struct Scores {
    /// Fit percent on each fold.
    pub fits: Vec<f64>,
    /// Their mean: the held-out figure.
    pub mean: f64,
    /// The fit percent of each block the acceptance test pairs ([`HeldOutGain`]): the folds'
    /// under [`Method::BlockedCv`], the tail cut into [`HOLDOUT_BLOCKS`] consecutive blocks
    /// (each scored about the tail's mean) under [`Method::Holdout`].
    pub blocks: Vec<f64>,
    /// RMS of the held-out residuals of every fold together.
    pub rms: f64,
    /// The held-out prediction of every sample of a fold (NaN outside the folds).
    pub prediction: Vec<f64>,
}

/// `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)` over the finite outputs of `range` with `ȳ` their mean,
/// and the SSE and count.
pub fn fit_percent(y: &[f64], yhat: &[f64], range: Range<usize>) -> (f64, f64, usize) {
    let fin = range.clone().filter(|&k| y[k].is_finite());
    let (s, c) = fin.fold((0.0, 0usize), |(s, c), k| (s + y[k], c + 1));
    fit_percent_about(y, yhat, range, s / c.max(1) as f64)
}

/// `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)` over the finite outputs of `range` about a given `mean`,
/// and the SSE and count.
pub fn fit_percent_about(
    y: &[f64],
    yhat: &[f64],
    range: Range<usize>,
    mean: f64,
) -> (f64, f64, usize) {
    let ok = || {
        range
            .clone()
            .filter(|&k| y[k].is_finite() && yhat[k].is_finite())
    };
    let m = ok().count();
    let e2: f64 = ok().map(|k| (y[k] - yhat[k]).powi(2)).sum();
    let d2: f64 = ok().map(|k| (y[k] - mean).powi(2)).sum();
    (100.0 * (1.0 - (e2 / d2.max(1e-300)).sqrt()), e2, m)
}

/// The held-out scores of the fit `f` (module doc): each fold refitted without it and scored
/// on it under [`Method::BlockedCv`]; `f` itself scored on the tail under [`Method::Holdout`].
pub fn cross_validate(ctx: &Ctx, folds: &Folds, f: &Fit) -> Scores {
    let n = ctx.sig.u.len();
    let mut prediction = vec![f64::NAN; n];
    let mut sim = vec![0.0; n];
    let mut fits = Vec::with_capacity(folds.folds.len());
    let mut blocks = Vec::new();
    let (mut e2, mut m) = (0.0, 0usize);
    let held = folds
        .folds
        .iter()
        .flat_map(|r| r.clone())
        .filter(|&k| ctx.sig.y[k].is_finite());
    let (s, c) = held.fold((0.0, 0usize), |(s, c), k| (s + ctx.sig.y[k], c + 1));
    let mean_y = s / c.max(1) as f64;
    // Every fold's refit starts at `f`: its first Jacobian is simulated once for all.
    let first = (folds.method == Method::BlockedCv).then(|| FirstJacobian::of(&f.model, &ctx.sig));
    // Each fold's refit is independent of the others': on every core.
    let models = crate::par::map(&folds.folds, |fold| match folds.method {
        Method::Holdout => f.model.clone(),
        Method::BlockedCv => {
            let mut y = ctx.sig.y.to_vec();
            for v in &mut y[fold.clone()] {
                *v = f64::NAN;
            }
            let sig = Signals { y: &y, ..ctx.sig };
            levenberg_marquardt_from(&f.model, &sig, 0..n, FOLD_ITERS, first.as_ref()).model
        }
    });
    for (fold, model) in folds.folds.iter().zip(models) {
        simulate(&model, &ctx.sig, &mut sim);
        prediction[fold.clone()].copy_from_slice(&sim[fold.clone()]);
        let (fit, s, c) = fit_percent_about(ctx.sig.y, &sim, fold.clone(), mean_y);
        fits.push(fit);
        match folds.method {
            Method::BlockedCv => blocks.push(fit),
            Method::Holdout => blocks.extend(
                sub_blocks(fold.clone(), HOLDOUT_BLOCKS)
                    .map(|b| fit_percent_about(ctx.sig.y, &sim, b, mean_y).0),
            ),
        }
        e2 += s;
        m += c;
    }
    let mean = fits.iter().sum::<f64>() / fits.len().max(1) as f64;
    Scores {
        fits,
        mean,
        blocks,
        rms: (e2 / m.max(1) as f64).sqrt(),
        prediction,
    }
}

/// `r` cut into `k` consecutive blocks of (nearly) equal length (fewer when `r` is shorter).
fn sub_blocks(r: Range<usize>, k: usize) -> impl Iterator<Item = Range<usize>> {
    let (start, len) = (r.start, r.len());
    let k = k.clamp(1, len.max(1));
    (0..k).map(move |b| start + b * len / k..start + (b + 1) * len / k)
}

/// The held-out gain of a model over another, judged against the scatter of the folds' own
/// fits (issue 29 item 4): the acceptance test of every effect the search takes
/// ([`crate::search`], [`crate::pair`], [`crate::revise`]).
///
/// With `f_b` and `g_b` the two models' fit percent on block `b` ([`Scores::blocks`]: the
/// folds, or the hold-out tail cut into [`HOLDOUT_BLOCKS`]) the paired differences are
/// `d_b = g_b − f_b`, `b = 1..k`. The gain is the difference of the held-out figures
/// (`mean(d)` under blocked cross-validation), its standard error `s_d / √k` with `s_d` the
/// sample standard deviation of the `d_b`. The gain is accepted when
///
/// `gain > MIN_CV_GAIN_PP` and `gain > t_{0.95, k−1} · s_d / √k`,
///
/// a one-sided paired t-test at 5 % ([`crate::thresholds::gain_t`]): a gain that the folds
/// themselves scatter by more than that could be the refits' noise (a sinusoid or a clip fitted
/// to a misfit). Fewer than two blocks carry no scatter: never accepted. The folds are not
/// independent samples (neighbouring levels, refits from one start), so the 5 % is nominal;
/// the false-alarm rate of the whole search is measured on clean simulated stands
/// (`docs/detection.md`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldOutGain {
    /// Held-out figure of the larger model minus the smaller's, percentage points.
    pub gain_pp: f64,
    /// Standard error of the gain from the blocks' paired differences, percentage points.
    pub se_pp: f64,
    /// Blocks paired.
    pub blocks: usize,
}

impl HeldOutGain {
    /// The gain of `after` over `before` (module doc of [`HeldOutGain`]).
    pub fn of(before: &Scores, after: &Scores) -> HeldOutGain {
        HeldOutGain::paired(&before.blocks, &after.blocks, after.mean - before.mean)
    }

    /// The gain `gain_pp` of a model whose blocks' figures are `after` over one whose are
    /// `before` (the same blocks, in order), with its scatter.
    pub fn paired(before: &[f64], after: &[f64], gain_pp: f64) -> HeldOutGain {
        let d: Vec<f64> = before.iter().zip(after).map(|(f, g)| g - f).collect();
        let k = d.len();
        let se_pp = if k >= 2 {
            let m = d.iter().sum::<f64>() / k as f64;
            let var = d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1) as f64;
            (var / k as f64).sqrt()
        } else {
            f64::NAN
        };
        HeldOutGain {
            gain_pp,
            se_pp,
            blocks: k,
        }
    }

    /// The gain in standard errors (`t`; infinite for a gain with no scatter).
    pub fn t(&self) -> f64 {
        if self.se_pp > 0.0 {
            self.gain_pp / self.se_pp
        } else if self.gain_pp > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }

    /// Whether the gain is taken: a held-out figure that rises ([`MIN_CV_GAIN_PP`]). The
    /// paired test against the folds' scatter ([`Self::significant`]) is said with every
    /// rejection but does not decide: its power on 3–5 folds is too low for the effects the
    /// injection tests hide (docs/diagnose_effects.md).
    pub fn passes(&self) -> bool {
        self.gain_pp.is_finite() && self.gain_pp > MIN_CV_GAIN_PP
    }

    /// The one-sided paired t-test at 95 %: `gain > t₀.₉₅,ₖ₋₁ · s_d/√k` over at least two
    /// blocks (see the type's doc).
    pub fn significant(&self) -> bool {
        self.blocks >= 2
            && self.passes()
            && self.se_pp.is_finite()
            && self.gain_pp > gain_t(self.blocks) * self.se_pp
    }

    /// Whether the gain is taken under `gate` ([`Gate`]).
    pub fn accepted(&self, gate: Gate) -> bool {
        match gate {
            Gate::Rising => self.passes(),
            Gate::Paired => self.significant(),
        }
    }

    /// The test in words: "+0.13 pp, 0.4 standard errors of the folds' scatter (needs 1.83)".
    pub fn describe(&self) -> String {
        format!(
            "{:+.2} pp held out, {:.1} standard errors of the {} folds' paired scatter (a 95 % \
             paired test needs more than {:.2})",
            self.gain_pp,
            self.t(),
            self.blocks,
            gain_t(self.blocks)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn staircase(levels: &[f64], per: usize) -> Vec<f64> {
        levels
            .iter()
            .flat_map(|&l| std::iter::repeat(l).take(per))
            .collect()
    }

    #[test]
    fn a_short_staircase_is_cut_at_its_steps_and_the_middle_of_each_hold() {
        let u = staircase(&[0.1, 0.3, 0.5, 0.7, 0.9], 100);
        let f = Folds::from_input(&u, &u, 0.7, &SegmentRules::DEFAULT);
        assert_eq!(f.method, Method::BlockedCv);
        let want: Vec<Range<usize>> = (0..10).map(|i| 50 * i..50 * (i + 1)).collect();
        assert_eq!(f.folds, want);
        assert_eq!(f.estimation, 0..500);
        // The top level (only at the end) is never held out whole: its step is scored with its
        // steady half in the fit, and the other way round.
        assert!(f.folds.iter().all(|r| r.len() < 100));
    }

    #[test]
    fn many_levels_are_grouped_into_consecutive_blocks_of_whole_levels() {
        let lv: Vec<f64> = (0..25).map(|i| 0.1 + 0.03 * i as f64).collect();
        let u = staircase(&lv, 50);
        let f = Folds::from_input(&u, &u, 0.7, &SegmentRules::DEFAULT);
        assert_eq!(f.folds.len(), MAX_FOLDS);
        // Every cut is at a step, the folds tile the record.
        assert_eq!(f.folds[0].start, 0);
        assert_eq!(f.folds.last().unwrap().end, u.len());
        for w in f.folds.windows(2) {
            assert_eq!(w[0].end, w[1].start);
            assert_eq!(w[1].start % 50, 0, "{:?}", f.folds);
        }
    }

    #[test]
    fn pulses_on_a_level_stay_in_its_fold_and_a_lead_in_joins_the_first() {
        let mut u = vec![0.0; 10]; // shorter than a level: no level of its own
        u.extend(staircase(&[0.4, 0.6, 0.5], 200));
        u[10 + 50] = 0.45; // a one-sample pulse on the first level
        let f = Folds::from_input(&u, &u, 0.7, &SegmentRules::DEFAULT);
        assert_eq!(
            f.folds,
            vec![0..110, 110..210, 210..310, 310..410, 410..510, 510..610]
        );
    }

    #[test]
    fn a_record_without_steps_keeps_the_hold_out_tail() {
        let u: Vec<f64> = (0..1000).map(|k| (k as f64 * 0.37).sin()).collect();
        let f = Folds::from_input(&u, &u, 0.7, &SegmentRules::DEFAULT);
        assert_eq!(f.method, Method::Holdout);
        assert_eq!(f.folds.len(), 1);
        assert_eq!(f.folds[0], 700..1000);
        assert_eq!(f.estimation, 0..700);
        // Two levels are not enough for folds either.
        let u = staircase(&[0.2, 0.6], 300);
        let f = Folds::from_input(&u, &u, 0.5, &SegmentRules::DEFAULT);
        assert_eq!(f.method, Method::Holdout);
        assert_eq!(f.folds.len(), 1);
        assert_eq!(f.folds[0], 300..600);
    }

    #[test]
    fn a_block_with_too_few_measured_outputs_joins_the_one_before() {
        let u = staircase(&[0.2, 0.4, 0.6, 0.8], 100);
        let mut y = u.clone();
        for v in &mut y[305..] {
            *v = f64::NAN; // the last level's output was not measured
        }
        let f = Folds::from_input(&u, &y, 0.7, &SegmentRules::DEFAULT);
        assert_eq!(
            f.folds,
            vec![0..50, 50..100, 100..150, 150..200, 200..250, 250..400]
        );
    }

    fn scores(blocks: &[f64]) -> Scores {
        Scores {
            fits: blocks.to_vec(),
            mean: blocks.iter().sum::<f64>() / blocks.len() as f64,
            blocks: blocks.to_vec(),
            rms: 0.0,
            prediction: Vec::new(),
        }
    }

    #[test]
    fn a_gain_inside_the_folds_scatter_fails_and_a_consistent_one_passes() {
        let before = scores(&[60.0, 70.0, 80.0, 65.0, 75.0]);
        // +0.12 pp on average, the folds going both ways by ±0.5: t ≈ 0.6 < 2.13.
        let scattered = scores(&[60.5, 69.5, 80.6, 64.6, 75.4]);
        let g = HeldOutGain::of(&before, &scattered);
        assert!((g.gain_pp - 0.12).abs() < 1e-9, "{g:?}");
        assert!(!g.significant() && g.t() < 1.0, "{g:?}");
        assert!(g.describe().contains("5 folds"), "{}", g.describe());
        // +0.5 pp in every fold, ±0.05: passes.
        let consistent = scores(&[60.5, 70.45, 80.55, 65.5, 75.5]);
        assert!(HeldOutGain::of(&before, &consistent).significant());
        // No gain, a loss, or a single block (no scatter) are never significant.
        assert!(!HeldOutGain::of(&before, &before).significant());
        assert!(!HeldOutGain::of(&consistent, &before).significant());
        assert!(!HeldOutGain::of(&scores(&[50.0]), &scores(&[60.0])).significant());
        // The same gain in every block has no scatter: it is significant.
        let shifted = scores(&[61.0, 71.0, 81.0, 66.0, 76.0]);
        assert!(HeldOutGain::of(&before, &shifted).significant());
        // What is taken: a rising figure, significant or not; a loss or no gain is not.
        assert!(g.passes() && !HeldOutGain::of(&before, &before).passes());
        assert!(!HeldOutGain::of(&consistent, &before).passes());
        // The gate decides which: a gain inside the scatter is taken only by a rising figure.
        assert!(g.accepted(Gate::Rising) && !g.accepted(Gate::Paired));
        let c = HeldOutGain::of(&before, &consistent);
        assert!(c.accepted(Gate::Rising) && c.accepted(Gate::Paired));
    }

    #[test]
    fn a_hold_out_tail_is_cut_into_blocks_for_its_scatter() {
        let b: Vec<Range<usize>> = sub_blocks(700..1000, HOLDOUT_BLOCKS).collect();
        assert_eq!(b, vec![700..760, 760..820, 820..880, 880..940, 940..1000]);
        assert_eq!(sub_blocks(0..3, 5).count(), 3);
    }

    #[test]
    fn fit_percent_is_100_for_a_perfect_prediction_and_0_for_the_mean() {
        let y = [1.0, 2.0, 3.0, f64::NAN, 5.0];
        assert_eq!(fit_percent(&y, &y, 0..5).0, 100.0);
        let mean = [2.75; 5];
        assert!(fit_percent(&y, &mean, 0..5).0.abs() < 1e-12);
    }
}
