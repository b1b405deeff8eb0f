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
