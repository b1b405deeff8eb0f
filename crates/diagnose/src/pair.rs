//! The pair step of the forward search: two effects that are only right together.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/pair.rs`.
use crate::thresholds::{MIN_CV_GAIN_PP, MIN_RMS_DROP, SCORE_THRESHOLD};

/// How many of the strongest candidates are paired.
pub const PAIR_POOL: usize = 3;
/// At most this many pair fits per forward step.
pub const MAX_PAIR_FITS: usize = 3;

/// The pairs to try among candidates of in-sample `scores` (indices into `scores`): the
/// [`PAIR_POOL`] highest scores that reach [`SCORE_THRESHOLD`], every pair of them, in order
/// of decreasing summed score (ties: the first listed), the stronger of each pair first; at
/// most [`MAX_PAIR_FITS`].
pub fn pairs(scores: &[f64]) -> Vec<(usize, usize)> {
    let mut order: Vec<usize> = (0..scores.len())
        .filter(|&i| scores[i] >= SCORE_THRESHOLD)
        .collect();
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]));
    order.truncate(PAIR_POOL);
    let mut out = Vec::new();
    for (k, &a) in order.iter().enumerate() {
        for &b in &order[k + 1..] {
            out.push((a, b));
        }
    }
    out.sort_by(|p, q| (scores[q.0] + scores[q.1]).total_cmp(&(scores[p.0] + scores[p.1])));
    out.truncate(MAX_PAIR_FITS);
    out
}

/// Whether the joint fit of a pair carries two effects' worth of evidence against the
/// current model: `n ln(SSE_M / SSE_pair) ≥ 2 ·` [`SCORE_THRESHOLD`] and an RMS drop of at
/// least [`MIN_RMS_DROP`]. Non-finite or empty fits never pass.
pub fn joint_evidence(sse_cur: f64, sse_pair: f64, n: usize) -> Option<f64> {
    if !(sse_cur.is_finite() && sse_pair.is_finite() && sse_cur > 0.0 && sse_pair > 0.0) {
        return None;
    }
    let score = n as f64 * (sse_cur / sse_pair).ln();
    let rms_drop = 1.0 - (sse_pair / sse_cur).sqrt();
    (score >= 2.0 * SCORE_THRESHOLD && rms_drop >= MIN_RMS_DROP).then_some(score)
}

/// The pair rule (module doc): every pair of [`pairs`] over `scores` is fitted by `fit`
/// (`None`: the pair fails an in-sample test, or its held-out gain the acceptance test of
/// [`crate::folds::HeldOutGain`]); of those whose held-out figure exceeds
/// `current` by more than [`MIN_CV_GAIN_PP`], the highest figure is returned (ties: the
/// first tried) with what `fit` gave.
pub fn select_pair<S>(
    scores: &[f64],
    current: f64,
    mut fit: impl FnMut(usize, usize) -> Option<(f64, S)>,
) -> Option<(usize, usize, S)> {
    let mut best: Option<(f64, usize, usize, S)> = None;
    for (a, b) in pairs(scores) {
        let Some((figure, extra)) = fit(a, b) else {
            continue;
        };
        let better = best.as_ref().map_or(true, |b| figure > b.0);
        if figure - current > MIN_CV_GAIN_PP && better {
            best = Some((figure, a, b, extra));
        }
    }
    best.map(|(_, a, b, extra)| (a, b, extra))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::{select, Selection};

    #[test]
    fn two_effects_that_fail_held_out_alone_are_taken_together() {
        // The current model's held-out figure is 50. Alone, "sag" (score 300) gives 30 and
        // "map" (score 200) gives 45: the single step takes neither (search::select).
        let alone = [("sag", 300.0, 30.0), ("map", 200.0, 45.0)];
        let singles: Vec<(f64, (&str, f64))> = alone.iter().map(|&(n, s, f)| (s, (n, f))).collect();
        for rule in [Selection::BestFigure, Selection::FirstByScore] {
            let none = select(rule, singles.clone(), 50.0, |&(_, f)| (f, true, ()));
            assert!(none.is_none());
        }
        // Together they give 62: the pair is taken, the stronger first.
        let scores: Vec<f64> = alone.iter().map(|a| a.1).collect();
        let got = select_pair(&scores, 50.0, |a, b| Some((62.0, (alone[a].0, alone[b].0))));
        assert_eq!(got.map(|g| g.2), Some(("sag", "map")));
    }

    #[test]
    fn a_pair_that_does_not_raise_the_held_out_figure_or_fails_in_sample_is_not_taken() {
        let scores = [300.0, 200.0];
        assert!(select_pair(&scores, 50.0, |_, _| Some((50.0, ()))).is_none());
        assert!(select_pair(&scores, 50.0, |_, _| None::<(f64, ())>).is_none());
        assert!(select_pair(&[300.0], 0.0, |_, _| Some((99.0, ()))).is_none());
    }

    #[test]
    fn of_the_pairs_that_pass_the_best_held_out_figure_wins() {
        let scores = [300.0, 200.0, 100.0];
        // (0,1) → 55, (0,2) → 60, (1,2) → 52.
        let fig = |a: usize, b: usize| match (a, b) {
            (0, 1) => 55.0,
            (0, 2) => 60.0,
            _ => 52.0,
        };
        let got = select_pair(&scores, 50.0, |a, b| Some((fig(a, b), ())));
        assert_eq!(got.map(|g| (g.0, g.1)), Some((0, 2)));
    }

    #[test]
    fn pairs_are_bounded_and_strongest_first() {
        let scores = [50.0, 400.0, 10.0, 300.0, 100.0, 45.0];
        // 10 is below the threshold; the pool is 400, 300, 100.
        assert_eq!(pairs(&scores), vec![(1, 3), (1, 4), (3, 4)]);
        assert!(pairs(&[500.0; 10]).len() <= MAX_PAIR_FITS);
        assert!(pairs(&[39.0, 500.0]).is_empty());
    }

    #[test]
    fn a_pair_needs_two_effects_worth_of_evidence() {
        // n ln(SSE_M / SSE_pair) with n = 1000: a 5 % SSE drop scores ≈ 51 (one effect's
        // worth, not two); a 10 % drop scores ≈ 105.
        assert!(joint_evidence(1.0, 0.95, 1000).is_none());
        assert!(joint_evidence(1.0, 0.90, 1000).is_some_and(|s| s > 80.0));
        assert!(joint_evidence(1.0, f64::NAN, 1000).is_none());
        assert!(joint_evidence(0.0, 0.0, 1000).is_none());
    }
}
