//! Singular value decomposition of block Hankel matrices: the dispatch between the dense path
//! (one-sided Jacobi on preallocated storage, [`dense`]) and the truncated path (FFT Hankel
//! products + Lanczos, [`truncated`], the svd part's).
//!
//! Both paths produce the same thing (docs/ARCHITECTURE.md): the leading `k` singular triplets,
//! `sigma` descending, `U` (`r*q × k`, column-major), `V` (`c*p × k`, column-major), plus all
//! singular values they know.

pub mod dense;
pub mod hankel_op;
pub mod subspace;
pub mod truncated;

use thiserror::Error;

/// Which SVD to use for the Hankel matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SvdChoice {
    /// Dense below [`TRUNCATED_CROSSOVER`], truncated at and above it.
    #[default]
    Auto,
    /// One-sided Jacobi on the formed Hankel matrix: every singular value, exact to rounding.
    Dense,
    /// Leading triplets only, the Hankel matrix never formed (FFT products + Lanczos).
    Truncated,
}

/// Which path a decomposition actually took.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SvdPath {
    /// [`dense::DenseSvd`].
    Dense,
    /// [`truncated`].
    Truncated,
}

impl SvdPath {
    /// Lower-case name for reports.
    pub fn as_str(self) -> &'static str {
        match self {
            SvdPath::Dense => "dense",
            SvdPath::Truncated => "truncated",
        }
    }
}

/// Smallest Hankel dimension `min(r*q, c*p)` at which [`SvdChoice::Auto`] takes the truncated
/// path. Placeholder until the truncated path lands and the svd part measures the crossover;
/// until then `Auto` is always dense (see [`resolve`]).
pub const TRUNCATED_CROSSOVER: usize = 160;

/// True while `core::svd::truncated` is a placeholder.
const TRUNCATED_AVAILABLE: bool = false;

/// Why an SVD failed.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum SvdError {
    /// The iteration did not converge in its budget.
    #[error("SVD did not converge after {sweeps} sweeps")]
    NotConverged {
        /// Sweeps (or iterations) spent.
        sweeps: usize,
    },
    /// Dimensions or buffer sizes do not fit the preallocated storage or each other.
    #[error("SVD dimensions do not fit: {0}")]
    Dimensions(&'static str),
    /// The requested path is not available in this build.
    #[error("SVD path not available: {0}")]
    Unavailable(&'static str),
}

/// Picks the path for a Hankel matrix of `rows × cols`.
pub fn resolve(choice: SvdChoice, rows: usize, cols: usize) -> Result<SvdPath, SvdError> {
    match choice {
        SvdChoice::Dense => Ok(SvdPath::Dense),
        SvdChoice::Truncated if TRUNCATED_AVAILABLE => Ok(SvdPath::Truncated),
        SvdChoice::Truncated => Err(SvdError::Unavailable(
            "the truncated (FFT + Lanczos) SVD is not built yet",
        )),
        SvdChoice::Auto => {
            if TRUNCATED_AVAILABLE && rows.min(cols) >= TRUNCATED_CROSSOVER {
                Ok(SvdPath::Truncated)
            } else {
                Ok(SvdPath::Dense)
            }
        }
    }
}
