//! The identification core's error type: every way bad input can fail, as a typed value.
//!
//! Nothing in `core` panics on input; every public entry returns `Result<_, IdentError>`.

use thiserror::Error;

use super::svd::SvdError;

/// Why an identification failed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum IdentError {
    /// The input is malformed in a way the caller controls (lengths, sample period, options).
    #[error("invalid input: {0}")]
    InvalidInput(&'static str),
    /// No pulse was found in the throttle signal (nor in the device events).
    #[error("no pulse found in the input (need short throttle pulses on top of a constant level)")]
    NoPulse,
    /// Pulses were found, but every one of them was left out (missing samples, short window).
    #[error("all {skipped} pulses were left out (missing samples in their windows or windows too short)")]
    AllPulsesSkipped {
        /// How many pulses were found and left out.
        skipped: usize,
    },
    /// An output channel is constant (or all zero) over the record: nothing to identify.
    #[error("output channel {channel} is constant (or all zero): nothing to identify")]
    ConstantOutput {
        /// Index of the output channel.
        channel: usize,
    },
    /// A sample that is not marked missing holds NaN or an infinite value.
    #[error("{signal} holds a non-finite value at sample {sample} that is not marked missing")]
    NonFinite {
        /// Which signal: "input", "output" or "markov".
        signal: &'static str,
        /// Channel index within that signal.
        channel: usize,
        /// Sample (or Markov block) index.
        sample: usize,
    },
    /// The record (or Markov sequence) is too short for the Hankel matrix it needs.
    #[error("record too short: the Hankel matrix needs {needed} Markov parameters, only {available} are usable")]
    RecordTooShort {
        /// Markov parameters (blocks) needed.
        needed: usize,
        /// Markov parameters available.
        available: usize,
    },
    /// The Hankel matrix has (numerically) lower rank than the requested order, or no singular
    /// value rises above the noise floor.
    #[error("rank-deficient Hankel matrix: {rank} singular value(s) above the noise floor, order {order} requested")]
    RankDeficient {
        /// Numerical rank found.
        rank: usize,
        /// Order that was asked for (0 when chosen automatically).
        order: usize,
    },
    /// The requested order is larger than the data (the Hankel size) supports.
    #[error("order {order} is larger than the data supports (at most {max})")]
    OrderTooHigh {
        /// Requested order.
        order: usize,
        /// Largest order the Hankel matrix supports.
        max: usize,
    },
    /// The input is larger than the workspace was built for.
    #[error("limit exceeded: {what} is {value}, the workspace allows {limit}")]
    LimitsExceeded {
        /// Which limit.
        what: &'static str,
        /// The value requested by the input.
        value: usize,
        /// The workspace's limit.
        limit: usize,
    },
    /// The singular value decomposition failed.
    #[error("singular value decomposition failed: {0}")]
    Svd(#[from] SvdError),
    /// The eigenvalue iteration for the poles did not converge.
    #[error("eigenvalues of the identified A matrix did not converge")]
    EigenNotConverged,
    /// The identified model has a pole at z = 1, so its DC gain is infinite.
    #[error("identified model has a pole at z = 1: DC gain undefined")]
    SingularDcGain,
}
