//! Whether an identified model may be published as a model: the rule is the core's
//! ([`propid_numerics::quality`], shared with `propid identify`); here the hint the daemon
//! publishes with a failing model.
//!
//! The worker publishes a model that fails as a `model_unreliable` warning instead (with its
//! numbers and the reasons), outside the gain schedule.

pub use propid_numerics::quality::Flaw;

use propid_numerics::quality;
use propid_numerics::ModelReport;

/// The flaws of a window's model by `propid identify`'s rules that apply to one window
/// ([`quality::judge`]: poles, DC-gain scatter, the plausibility bound on the DC gain;
/// [`quality::judge_sample_period`]: a stand's command sampled too slowly to show dynamics).
/// The check against the record's steady levels needs several levels, which one window at one
/// operating point does not have.
pub fn judge(model: &ModelReport) -> Vec<Flaw> {
    let mut flaws = quality::judge(model);
    flaws.extend(quality::judge_sample_period(model.dt_s));
    flaws
}

/// Hint published with an unreliable model.
pub const HINT: &str = "the pulse responses are not resolved above the noise: use wider pulses \
    ([experiment] pulse_width_samples, e.g. 1 ms worth of samples), larger pulse_amplitudes, \
    or more pulses per model ([identify] pulses_per_model)";
