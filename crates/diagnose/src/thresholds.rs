//! The discrepancy engine's decision thresholds, in one place: what a score, an RMS drop and a
//! held-out gain must reach for an effect to be taken ([`crate::search`], [`crate::revise`],
//! [`crate::pair`], [`crate::lead`]), and when a confounded effect is called unidentifiable
//! ([`crate::verdict`] and the effects). How they were set: `docs/diagnose.md`.

/// Decision threshold on the score `n ln(SSE_M / SSE_{M+e})`.
pub const SCORE_THRESHOLD: f64 = 40.0;

/// Smallest accepted relative drop of the estimation residual RMS.
pub const MIN_RMS_DROP: f64 = 0.01;

/// Smallest held-out gain of an addition, percentage points (the figure must rise).
pub const MIN_CV_GAIN_PP: f64 = 0.0;

/// One-sided 95 % quantiles of Student's t for 1..=12 degrees of freedom.
const T_95: [f64; 12] = [
    6.314, 2.920, 2.353, 2.132, 2.015, 1.943, 1.895, 1.860, 1.833, 1.812, 1.796, 1.782,
];

/// The acceptance test's `t` for a held-out gain paired over `blocks` blocks
/// ([`crate::folds::HeldOutGain`]): the one-sided 95 % quantile of Student's t with
/// `blocks − 1` degrees of freedom (1.645, the normal's, beyond 12; infinite below 2 blocks:
/// no scatter, no test passed).
pub fn gain_t(blocks: usize) -> f64 {
    match blocks {
        0 | 1 => f64::INFINITY,
        b if b - 1 <= T_95.len() => T_95[b - 2],
        _ => 1.645,
    }
}

/// Most revisions (changes kept) in one search.
pub const MAX_REVISIONS: usize = 4;

/// `R²` at and above which the drift is called unidentifiable: the fitted rate's variance
/// inflated a thousandfold, `t` affine in the command to within 0.1 % of its variance (a
/// monotone staircase needs about 30 equal levels to get there).
pub const UNIDENTIFIABLE_R2: f64 = 0.999;

/// Samples of delay at which the dead time's confounding check compares the command with
/// itself: the shortest delays the injection tests hide (2–6 samples) and a stand's logger adds.
pub const CONFOUNDING_SHIFT: usize = 2;

/// Exponent `n` of the strongest plausible supply dependence, thrust ∝ V^n: a propeller whose
/// speed follows the voltage (`ω ∝ K_v V`, thrust ∝ ω²).
pub const EXPONENT_MAX: f64 = 2.0;

/// Most effects named on a stand baseline ([`crate::stand`]): its catalogue frees one part of
/// the stand at a time, and a real stand shows several at once (a dead time, a load cell's
/// lag, the thrust curve, the supply).
pub const STAND_MAX_EFFECTS: usize = 6;

/// Which test an effect's held-out gain must pass to be taken ([`crate::folds::HeldOutGain::accepted`];
/// [`crate::Options::gate`]). Their false-alarm rates on clean simulated stands and what each
/// finds: `docs/detection.md`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Gate {
    /// The held-out figure rises ([`crate::folds::HeldOutGain::passes`]).
    #[default]
    Rising,
    /// The one-sided paired t-test against the folds' scatter ([`crate::folds::HeldOutGain::significant`]).
    Paired,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_acceptance_t_is_students_one_sided_95_percent_quantile() {
        assert_eq!(gain_t(1), f64::INFINITY);
        assert_eq!(gain_t(2), 6.314);
        assert_eq!(gain_t(5), 2.132);
        assert_eq!(gain_t(10), 1.833);
        assert_eq!(gain_t(13), 1.782);
        assert_eq!(gain_t(100), 1.645);
    }
}
