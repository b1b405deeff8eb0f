//! What the search needs from an effect: the [`Effect`] trait (its catalogue entry, one unit
//! struct per file under [`crate::effects`]): its published name, how it is detected (fitted
//! on top of the current model, or read straight off the data: [`Detected`]), whether the data
//! can tell it apart, and what it says about a record it is not found in.
//!
//! The registry [`crate::effects::REGISTRY`] lists the effects; the engine names none. The
//! search scores a fitted extension generically (`n ln(SSE_M / SSE_{M+e})`, see
//! [`crate::search`]); an effect read off the data brings its own score ([`Detected`]).

use propid_numerics::EffectName;

use crate::ctx::Ctx;
use crate::fit::Fit;
use crate::term::Term;
use crate::verdict::Warning;

/// An effect recognised straight from the data, before any fit.
#[derive(Debug)]
pub struct Detected {
    /// Its term, to be part of every model fitted afterwards.
    pub term: Box<dyn Term>,
    /// Its score (the effect's own statistic, e.g. the number of clipped samples).
    pub score: f64,
}

/// A catalogue entry: one physical effect the 2nd-order model may be missing.
pub trait Effect: Sync {
    /// The published name (`"dead_time"`, ...): a public interface, never renamed.
    fn name(&self) -> EffectName;

    /// Recognises the effect straight from the data (before the baseline is fitted); `None`
    /// when it is not there or not recognisable that way (the default).
    fn detect(&self, _ctx: &Ctx) -> Option<Detected> {
        None
    }

    /// Fits the model `cur` extended by this effect on the estimation samples; `None` when the
    /// effect does not apply to this data (e.g. no voltage channel).
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit>;

    /// Whether the data can tell this effect, as fitted in `after` on top of `before`, apart
    /// from what the model already holds or a simpler effect explains; `Err` with the reason
    /// in words when it cannot (the search then does not take it and says why). Default: it
    /// can.
    fn identifiable(&self, _ctx: &Ctx, _before: &Fit, _after: &Fit) -> Result<(), String> {
        Ok(())
    }

    /// The model the search ended with, `cur`, settled for this effect (refitted on what it
    /// decides, e.g. which signal the supply scales); `None` (the default) when nothing is
    /// settled. The search keeps it when the held-out figure does not fall.
    fn settle(&self, _ctx: &Ctx, _cur: &Fit) -> Option<Fit> {
        None
    }

    /// A warning about this record (`model`: `"baseline"` or `"extended"`, the model published
    /// last; `cur` its fit; `found`: the effect is one of the findings): the effect cannot be
    /// told apart from the model here, or could not have shown. `None` (the default): nothing
    /// to say.
    fn warning(
        &self,
        _ctx: &Ctx,
        _cur: &Fit,
        _found: bool,
        _model: &'static str,
    ) -> Option<Warning> {
        None
    }
}
