//! Candidates the search tried and did not take (issue 11: honest output). An effect whose fit
//! passed the in-sample score test ([`super::search::SCORE_THRESHOLD`]) but that the final
//! model leaves out is published with its score, the held-out change it brought and the
//! reason in words, so that a user reads "fits in-sample but lowers the held-out fit by
//! 1.3 pp: not taken" instead of silence. Candidates whose score stays below the threshold
//! explain nothing and are not listed.
//!
//! The search keeps a [`Ledger`]: the latest word on every candidate (a later forward step,
//! on a model with more effects, replaces an earlier one, and drops it when the candidate no
//! longer fits in-sample there: the effects added since explain what it did); at the end the
//! entries of the effects in the final model are dropped.

use serde::Serialize;

use crate::folds::HeldOutGain;
use propid_numerics::EffectName;

/// One candidate tried and not taken (`"rejected"`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rejected {
    /// Effect name (one of [`super::effects::REGISTRY`]).
    pub effect: EffectName,
    /// Its score `n ln(SSE_before / SSE_after)` on the model it was tried on.
    pub score: f64,
    /// The held-out figure's change it brought, percentage points (null when it was not
    /// cross-validated: it failed an in-sample test first).
    pub cv_gain_pp: Option<f64>,
    /// Why it was not taken, in words.
    pub reason: String,
}

impl Rejected {
    /// A candidate that passed the in-sample tests but changed the held-out figure by
    /// `cv_gain_pp` (≤ the search's minimum gain; not finite when a fold's prediction
    /// diverged: then null).
    pub fn held_out(effect: EffectName, score: f64, cv_gain_pp: f64) -> Rejected {
        if !cv_gain_pp.is_finite() {
            return Rejected {
                effect,
                score,
                cv_gain_pp: None,
                reason: "fits in-sample but its held-out prediction diverges: not taken".into(),
            };
        }
        let change = if cv_gain_pp < 0.0 {
            format!("lowers the held-out fit by {:.1} pp", -cv_gain_pp)
        } else {
            "does not raise the held-out fit".to_string()
        };
        Rejected {
            effect,
            score,
            cv_gain_pp: Some(cv_gain_pp),
            reason: format!("fits in-sample but {change}: not taken"),
        }
    }

    /// A candidate that raised the held-out figure, by no more than the folds' own scatter
    /// allows a refit's noise to ([`crate::folds::HeldOutGain`]).
    pub fn within_scatter(effect: EffectName, score: f64, gain: &HeldOutGain) -> Rejected {
        Rejected {
            effect,
            score,
            cv_gain_pp: Some(gain.gain_pp),
            reason: format!(
                "fits in-sample and raises the held-out fit, but only within the folds' own \
                 scatter ({}): not taken",
                gain.describe()
            ),
        }
    }

    /// A candidate that raised the held-out figure by `cv_gain_pp`, less than `by` did
    /// (`by_gain_pp`), which was taken in its place (`search::Selection::BestFigure`); a later
    /// step, on the model with `by`, gives the latest word on it.
    pub fn outranked(
        effect: EffectName,
        score: f64,
        cv_gain_pp: f64,
        by: EffectName,
        by_gain_pp: f64,
    ) -> Rejected {
        Rejected {
            effect,
            score,
            cv_gain_pp: Some(cv_gain_pp),
            reason: format!(
                "fits in-sample and raises the held-out fit by {cv_gain_pp:.2} pp, but {by} \
                 raised it more ({by_gain_pp:.2} pp) and was taken in its place: not taken"
            ),
        }
    }
}

/// The latest word on each candidate (module doc).
#[derive(Debug, Clone, Default)]
pub struct Ledger {
    entries: Vec<Rejected>,
}

impl Ledger {
    /// Records `r`, replacing an earlier entry of the same effect.
    pub fn note(&mut self, r: Rejected) {
        self.entries.retain(|e| e.effect != r.effect);
        self.entries.push(r);
    }

    /// Drops the entry of `effect` (tried again, it no longer fits in-sample).
    pub fn forget(&mut self, effect: EffectName) {
        self.entries.retain(|e| e.effect != effect);
    }

    /// The entries of the effects not in `taken`, in catalogue order.
    pub fn rejected(mut self, taken: &[EffectName]) -> Vec<Rejected> {
        self.entries.retain(|e| !taken.contains(&e.effect));
        self.entries.sort_by_key(|e| e.effect);
        self.entries
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_latest_word_wins_and_taken_effects_are_dropped() {
        let mut l = Ledger::default();
        l.note(Rejected::held_out(EffectName::SupplySag, 120.0, -1.3));
        l.note(Rejected::held_out(EffectName::DeadTime, 60.0, -0.2));
        l.note(Rejected::held_out(EffectName::SupplySag, 90.0, -2.0));
        let r = l.clone().rejected(&[]);
        assert_eq!(r.len(), 2);
        assert_eq!(
            (r[0].effect, r[1].effect),
            (EffectName::DeadTime, EffectName::SupplySag)
        );
        assert_eq!(r[1].cv_gain_pp, Some(-2.0));
        assert_eq!(
            r[1].reason,
            "fits in-sample but lowers the held-out fit by 2.0 pp: not taken"
        );
        let r = l.clone().rejected(&[EffectName::DeadTime]);
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].effect, EffectName::SupplySag);
        let diverged = Rejected::held_out(EffectName::Saturation, 63.0, f64::NEG_INFINITY);
        assert_eq!(diverged.cv_gain_pp, None);
        let second = Rejected::outranked(
            EffectName::AsymmetricDynamics,
            364.0,
            0.32,
            EffectName::DeadTime,
            0.8,
        );
        assert_eq!(second.cv_gain_pp, Some(0.32));
        assert_eq!(
            second.reason,
            "fits in-sample and raises the held-out fit by 0.32 pp, but dead_time raised it \
             more (0.80 pp) and was taken in its place: not taken"
        );
        assert!(diverged.reason.contains("diverges"), "{}", diverged.reason);
        l.forget(EffectName::SupplySag);
        assert_eq!(l.rejected(&[]).len(), 1);
    }
}
