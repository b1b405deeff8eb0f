//! Jackknife standard deviations over pulses (Efron & Stein 1981; Quenouille 1956).
//!
//! For `N` pulses, the leave-one-out ensemble averages `Ȳ^(−i)` (every pulse but `i`) are
//! re-identified at the same order and Hankel size, giving `θ_i` (fn, ζ, DC gain). Then
//!
//! ```text
//! std(θ) = √( (N−1)/N · Σ_i (θ_i − θ̄)² ),   θ̄ = mean θ_i
//! ```
//!
//! The factor `(N−1)` makes up for each `θ_i` sharing `N−2` pulses with every other. The
//! re-identification starts the SVD from the full-data right singular vectors
//! ([`crate::svd::subspace`]), so it costs a few Hankel products per pulse.

/// Jackknife standard deviation of the leave-one-out estimates (NaN for fewer than two or a
/// non-finite value).
pub fn jackknife_std(values: &[f64]) -> f64 {
    let n = values.len();
    if n < 2 || values.iter().any(|v| !v.is_finite()) {
        return f64::NAN;
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let ss: f64 = values.iter().map(|v| (v - mean) * (v - mean)).sum();
    ((n - 1) as f64 / n as f64 * ss).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jackknife_of_the_mean_is_the_standard_error() {
        // For the mean, leave-one-out values are (S − x_i)/(N−1); the jackknife std equals the
        // usual standard error s/√N.
        let x = [1.0, 4.0, 2.0, 8.0, 5.0];
        let n = x.len() as f64;
        let s: f64 = x.iter().sum();
        let loo: Vec<f64> = x.iter().map(|v| (s - v) / (n - 1.0)).collect();
        let mean = s / n;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        assert!((jackknife_std(&loo) - (var / n).sqrt()).abs() < 1e-12);
        assert!(jackknife_std(&[1.0]).is_nan());
    }
}
