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

use nalgebra::Complex;

use crate::modal::continuous;

type C64 = Complex<f64>;

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

/// [`jackknife_std`] of the `n` values of an iterator (no allocation).
pub fn strided_jackknife(vals: impl Iterator<Item = f64> + Clone, n: usize) -> f64 {
    if n < 2 || vals.clone().any(|v| !v.is_finite()) {
        return f64::NAN;
    }
    let mean = vals.clone().sum::<f64>() / n as f64;
    let ss: f64 = vals.map(|v| (v - mean) * (v - mean)).sum();
    ((n - 1) as f64 / n as f64 * ss).sqrt()
}

/// The pair of discrete poles `poles`, as continuous poles `s = ln(z)/dt`, closest to the
/// continuous pair `base` (sum of the distances): which leave-one-out poles estimate the
/// model's fn and ζ.
pub fn closest_pair(poles: &[C64], base: (C64, C64), dt: f64) -> (C64, C64) {
    let n = poles.len();
    let mut best = (C64::new(f64::NAN, 0.0), C64::new(f64::NAN, 0.0));
    let mut err = f64::INFINITY;
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            let (s1, s2) = (continuous(poles[i], dt), continuous(poles[j], dt));
            let e = (s1 - base.0).norm() + (s2 - base.1).norm();
            if e < err {
                err = e;
                best = (s1, s2);
            }
        }
    }
    best
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
        assert_eq!(
            strided_jackknife(loo.iter().copied(), loo.len()),
            jackknife_std(&loo)
        );
    }

    #[test]
    fn closest_pair_matches_the_base_pair() {
        let dt = 0.01;
        let z = |s: C64| (s * dt).exp();
        let (a, b) = (C64::new(-2.0, 30.0), C64::new(-2.0, -30.0));
        let poles = [z(C64::new(-50.0, 0.0)), z(b), z(a)];
        let (s1, s2) = closest_pair(&poles, (a, b), dt);
        assert!(
            (s1 - a).norm() < 1e-9 && (s2 - b).norm() < 1e-9,
            "{s1} {s2}"
        );
        assert!(closest_pair(&poles[..1], (a, b), dt).0.re.is_nan());
    }
}
