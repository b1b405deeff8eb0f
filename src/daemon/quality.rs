//! Whether an identified model may be published as a model: the rule is the core's
//! ([`propid_numerics::quality`], shared with `propid identify`); here the hint the daemon
//! publishes with a failing model.
//!
//! The worker publishes a model that fails as a `model_unreliable` warning instead (with its
//! numbers and the reasons), outside the gain schedule.

pub use propid_numerics::quality::{judge, Flaw};

/// Hint published with an unreliable model.
pub const HINT: &str = "the pulse responses are not resolved above the noise: use wider pulses \
    ([experiment] pulse_width_samples, e.g. 1 ms worth of samples), larger pulse_amplitudes, \
    or more pulses per model ([identify] pulses_per_model)";
