//! Residual spectrum: a Hann-windowed periodogram (one segment, `realfft`) and its peaks.
//!
//! `P(f_j) = |Σ_k w_k e_k e^{−2πi jk/N}|² / Σ_k w_k²` with `w_k = sin²(πk/N)` (Hann), on the
//! mean-removed residual; missing samples count as zero. Peaks are refined by parabolic
//! interpolation of the log-power over the three bins around the maximum (Smith & Serra 1987).

use realfft::RealFftPlanner;

/// One-sided periodogram of `x` sampled every `dt_s`: `(frequencies Hz, power)`.
pub fn periodogram(x: &[f64], dt_s: f64) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    if n < 4 {
        return (Vec::new(), Vec::new());
    }
    let finite: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    let mean = finite.iter().sum::<f64>() / finite.len().max(1) as f64;
    let mut buf: Vec<f64> = Vec::with_capacity(n);
    let mut wsum = 0.0;
    for (k, v) in x.iter().enumerate() {
        let w = (std::f64::consts::PI * k as f64 / n as f64).sin().powi(2);
        wsum += w * w;
        buf.push(if v.is_finite() { (v - mean) * w } else { 0.0 });
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    let mut spec = fft.make_output_vec();
    if fft.process(&mut buf, &mut spec).is_err() {
        return (Vec::new(), Vec::new());
    }
    let df = 1.0 / (n as f64 * dt_s);
    let freqs = (0..spec.len()).map(|j| j as f64 * df).collect();
    let power = spec
        .iter()
        .map(|c| c.norm_sqr() / wsum.max(1e-300))
        .collect();
    (freqs, power)
}

/// The `count` strongest local maxima of the periodogram of `x` between `f_lo` and `f_hi` Hz,
/// as `(frequency Hz, power)`, strongest first, frequency refined between bins.
pub fn peaks(x: &[f64], dt_s: f64, f_lo: f64, f_hi: f64, count: usize) -> Vec<(f64, f64)> {
    let (f, p) = periodogram(x, dt_s);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for j in 1..p.len().saturating_sub(1) {
        if f[j] < f_lo || f[j] > f_hi || p[j] < p[j - 1] || p[j] < p[j + 1] || p[j] <= 0.0 {
            continue;
        }
        let (a, b, c) = (
            p[j - 1].max(1e-300).ln(),
            p[j].ln(),
            p[j + 1].max(1e-300).ln(),
        );
        let den = a - 2.0 * b + c;
        let shift = if den.abs() > 1e-12 {
            (0.5 * (a - c) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        out.push((f[j] + shift * (f[1] - f[0]), p[j]));
    }
    out.sort_by(|a, b| b.1.total_cmp(&a.1));
    out.truncate(count);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_sinusoid_between_bins() {
        let dt = 1e-3;
        let x: Vec<f64> = (0..4000)
            .map(|k| (2.0 * std::f64::consts::PI * 37.3 * k as f64 * dt).sin())
            .collect();
        let pk = peaks(&x, dt, 1.0, 400.0, 1);
        assert!((pk[0].0 - 37.3).abs() < 0.05, "{:?}", pk);
    }
}
