//! Singular value decomposition of block Hankel matrices: the dispatch between the dense path
//! (one-sided Jacobi on preallocated storage, [`dense`]) and the truncated path (FFT Hankel
//! products + Lanczos, [`truncated`], the svd part's).
//!
//! Both paths produce the same thing (docs/ARCHITECTURE.md): the leading `k` singular triplets,
//! `sigma` descending, `U` (`r*q × k`, column-major), `V` (`c*p × k`, column-major), plus all
//! singular values they know.

pub mod dense;
pub mod hankel_op;
pub mod kernels;
pub mod subspace;
pub mod truncated;

use thiserror::Error;

/// Where an SVD writes its leading triplets: `sigma` (descending), `u` (`rows × k`) and `v`
/// (`cols × k`), column-major.
#[derive(Debug)]
pub struct Triplets<'a> {
    /// Singular values.
    pub sigma: &'a mut [f64],
    /// Left singular vectors.
    pub u: &'a mut [f64],
    /// Right singular vectors.
    pub v: &'a mut [f64],
}

impl<'a> Triplets<'a> {
    /// The three output buffers.
    pub fn new(sigma: &'a mut [f64], u: &'a mut [f64], v: &'a mut [f64]) -> Self {
        Self { sigma, u, v }
    }
}

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
/// path (see [`resolve`]). The svd part measures and tunes it (`docs/core.md`,
/// `/work/shared/SVD-MEASUREMENTS.md`: the dense Jacobi SVD grows as `m n²`, the truncated one
/// as `(m + n) log(m + n)` per Lanczos step).
///
/// Measured by `benches/svd.rs` (square SISO Hankel, noisy 2nd-order response, release build on
/// the 2-core machine; medians): dense Jacobi with `k = 2` takes 0.24 ms at 16, 0.86–1.9 ms at
/// 32, 4.9–11.5 ms at 64, 17–42 ms at 96, 41–91 ms at 128, 0.72 s at 256; the truncated path
/// takes 15–45 µs at 32 and 65 µs at 128 for `k = 2`, and 0.12 ms at 16, 0.56 ms at 32,
/// 0.81 ms at 64, 3.4 ms at 128, 4.7 ms at 256 for `k = 16` with 2 required
/// (`compute_at_least`, the automatic-order call). It is faster from 16 up; below 32 both take
/// well under a millisecond and the dense path also gives every singular value, so the switch
/// is at 32.
pub const TRUNCATED_CROSSOVER: usize = 32;

/// Largest dimension the dense path's buffers are allocated for (`rows × cols` doubles twice):
/// beyond it only the truncated path runs.
pub const DENSE_MAX_DIM: usize = 512;

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

/// Picks the path for a Hankel matrix of `rows × cols` given the dense path's capacity
/// `dense_rows × dense_cols`: `Auto` is dense below [`TRUNCATED_CROSSOVER`] and where it fits.
pub fn resolve(
    choice: SvdChoice,
    rows: usize,
    cols: usize,
    dense_rows: usize,
    dense_cols: usize,
) -> Result<SvdPath, SvdError> {
    let fits = rows <= dense_rows && cols <= dense_cols;
    match choice {
        SvdChoice::Dense if fits => Ok(SvdPath::Dense),
        SvdChoice::Dense => Err(SvdError::Dimensions(
            "Hankel matrix larger than the dense SVD's capacity (use the truncated SVD)",
        )),
        SvdChoice::Truncated => Ok(SvdPath::Truncated),
        SvdChoice::Auto if fits && rows.min(cols) < TRUNCATED_CROSSOVER => Ok(SvdPath::Dense),
        SvdChoice::Auto => Ok(SvdPath::Truncated),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_switches_at_the_crossover_and_the_capacity() {
        let c = TRUNCATED_CROSSOVER;
        assert_eq!(
            resolve(SvdChoice::Auto, c - 1, c - 1, 512, 512),
            Ok(SvdPath::Dense)
        );
        assert_eq!(
            resolve(SvdChoice::Auto, c, c, 512, 512),
            Ok(SvdPath::Truncated)
        );
        assert_eq!(
            resolve(SvdChoice::Auto, 10, 10, 8, 8),
            Ok(SvdPath::Truncated)
        );
        assert!(resolve(SvdChoice::Dense, 10, 10, 8, 8).is_err());
        assert_eq!(
            resolve(SvdChoice::Truncated, 4, 4, 8, 8),
            Ok(SvdPath::Truncated)
        );
    }
}
