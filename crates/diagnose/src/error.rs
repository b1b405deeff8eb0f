//! Why a diagnosis could not be made.

use super::era_start::CoreRefusal;

/// Why a diagnosis could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    /// A channel the diagnosis needs is absent.
    #[error("the record has no `{0}` channel (diagnose needs the input and one output)")]
    MissingChannel(String),
    /// Too few samples.
    #[error("the record has {got} usable samples, diagnose needs at least {need}")]
    TooShort {
        /// Samples present.
        got: usize,
        /// Samples needed.
        need: usize,
    },
    /// A NaN or infinite value where the record does not mark a missing sample.
    #[error(
        "channel `{channel}` has a non-finite value at sample {index} that is not marked missing"
    )]
    NonFinite {
        /// Channel name.
        channel: String,
        /// Sample index.
        index: usize,
    },
    /// The sample period is not a positive number of at most
    /// [`MAX_SAMPLE_PERIOD_S`](super::MAX_SAMPLE_PERIOD_S).
    #[error(
        "the sample period {0} s is outside 0 < dt <= 490000 s (a time column in ns read as s?)"
    )]
    BadSamplePeriod(f64),
    /// A stand's command sampled more slowly than a motor–propeller settles
    /// ([`propid_numerics::quality::judge_sample_period`]): every sample is a steady state.
    #[error(
        "a sample every {0:.3} s is longer than a motor-propeller takes to settle (a third of a \
         second): every sample is a steady state and the record holds no dynamics to diagnose \
         (`propid identify` prints its static map)"
    )]
    SamplePeriodTooLong(f64),
    /// Input or output does not vary: nothing to identify.
    #[error("the {0} is constant on the estimation part: nothing to identify")]
    Constant(&'static str),
    /// The baseline fit failed (non-finite residuals).
    #[error("the 2nd-order baseline could not be fitted to this data")]
    FitFailed {
        /// Why the identification core gave no start either, when it gave none.
        #[source]
        core: Option<CoreRefusal>,
    },
}
