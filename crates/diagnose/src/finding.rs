//! One named effect of a diagnosis ([`Finding`]): what `diagnose` publishes of each effect
//! found (an entry of `findings` in `propid diagnose --json`).

use propid_numerics::EffectName;
use serde::Serialize;
use serde_json::{Map, Value};

/// One named effect.
#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    /// Effect name (one of [`super::effects::REGISTRY`]).
    pub effect: EffectName,
    /// Test statistic `n ln(SSE_before / SSE_after)` (larger is stronger evidence).
    pub score: f64,
    /// Held-out gain of this addition: the held-out figure (`Validation`) of the model with
    /// it minus that of the model before it, percentage points (> 0 for every effect added by
    /// the search; an effect read straight from the data reports its gain, whatever its sign).
    pub cv_gain_pp: f64,
    /// The evidence in words.
    pub evidence: String,
    /// The effect's parameter estimates (`delay_s`, `exponent`, `fn_hz`, ...): an effect the
    /// search added reports its values in the final model, where every parameter is fitted
    /// jointly ([`super::search`]).
    #[serde(flatten)]
    pub params: Map<String, Value>,
    /// The evidence's sentence on how much the estimation residual fell when the effect was
    /// added (part of `evidence`; kept to rewrite the evidence with the final values).
    #[serde(skip)]
    pub drop: String,
}
