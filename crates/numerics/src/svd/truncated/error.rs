//! Errors of the truncated (FFT + Lanczos) Hankel SVD.
//!
//! Every failure is reported as a typed value; no partial or unconverged triplet is ever handed
//! back as if it were a result.

/// Why a Hankel product or a truncated SVD was refused or failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TruncatedError {
    /// A dimension is zero or exceeds what the workspace was sized for in `new()`.
    #[error("{what} = {got} is outside 1..={max} (the workspace was sized for at most {max})")]
    Dimension {
        /// Which dimension.
        what: &'static str,
        /// The value asked for.
        got: usize,
        /// The largest allowed value.
        max: usize,
    },
    /// The Markov sequence has fewer samples than the Hankel matrix needs.
    #[error("the Hankel matrix needs {needed} Markov values, only {got} were given")]
    MarkovTooShort {
        /// Values needed (`(r + c + shift) * q * p`).
        needed: usize,
        /// Values given.
        got: usize,
    },
    /// An input or output slice has the wrong length.
    #[error("slice `{what}` has length {got}, expected at least {expected}")]
    SliceLength {
        /// Which slice.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length required.
        expected: usize,
    },
    /// A Markov value (or a vector to multiply) is NaN or infinite.
    #[error("non-finite value in `{what}` at index {index}")]
    NonFinite {
        /// Which slice.
        what: &'static str,
        /// The first bad index.
        index: usize,
    },
    /// More singular triplets were asked for than the matrix has.
    #[error("{k} singular triplets asked of a {rows} x {cols} matrix")]
    TooManyTriplets {
        /// Triplets asked for.
        k: usize,
        /// Rows of the matrix.
        rows: usize,
        /// Columns of the matrix.
        cols: usize,
    },
    /// The Lanczos iteration did not reach the requested accuracy within its step budget.
    #[error(
        "truncated SVD did not converge: {converged} of {k} triplets after {steps} steps, \
         worst relative residual {residual:e} > tolerance {tolerance:e}"
    )]
    NotConverged {
        /// Triplets asked for.
        k: usize,
        /// Leading triplets that did converge.
        converged: usize,
        /// Lanczos steps taken.
        steps: usize,
        /// Worst residual `‖Hᵀu − σv‖ / σ₁` among the requested triplets.
        residual: f64,
        /// The tolerance that was asked for.
        tolerance: f64,
    },
    /// The Hankel matrix is zero: there is no leading singular direction.
    #[error("the Hankel matrix is zero")]
    ZeroMatrix,
    /// A product was asked before any matrix was loaded by `HankelOp::prepare` (or after a
    /// failed one).
    #[error("no Hankel matrix prepared for the product")]
    NotPrepared,
    /// The FFT library refused a buffer (an internal sizing bug; never expected).
    #[error("internal FFT buffer error: {0}")]
    Fft(String),
}

impl From<TruncatedError> for super::super::SvdError {
    /// Maps onto the dispatch's coarser error (the details stay in the message of the
    /// [`TruncatedError`], which callers wanting them can keep instead).
    fn from(e: TruncatedError) -> Self {
        use super::super::SvdError;
        match e {
            TruncatedError::NotConverged { steps, .. } => SvdError::NotConverged { sweeps: steps },
            TruncatedError::Dimension { .. } => {
                SvdError::Dimensions("truncated SVD: dimension outside the workspace")
            }
            TruncatedError::MarkovTooShort { .. } => SvdError::Dimensions(
                "truncated SVD: Markov sequence too short for the Hankel matrix",
            ),
            TruncatedError::SliceLength { .. } => {
                SvdError::Dimensions("truncated SVD: output or input slice too short")
            }
            TruncatedError::NonFinite { .. } => {
                SvdError::Dimensions("truncated SVD: non-finite Markov value")
            }
            TruncatedError::TooManyTriplets { .. } => {
                SvdError::Dimensions("truncated SVD: more triplets than the matrix has")
            }
            TruncatedError::ZeroMatrix => {
                SvdError::Dimensions("truncated SVD: the Hankel matrix is zero")
            }
            TruncatedError::NotPrepared => {
                SvdError::Dimensions("truncated SVD: no Hankel matrix prepared")
            }
            TruncatedError::Fft(_) => {
                SvdError::Unavailable("truncated SVD: internal FFT buffer error")
            }
        }
    }
}
