//! Residual spectrum: a Hann-windowed periodogram (one segment, `realfft`) and its peaks.
//!
//! `P(f_j) = |Σ_k w_k e_k e^{−2πi jk/N}|² / Σ_k w_k²` with `w_k = sin²(πk/N)` (Hann), on the
//! mean-removed residual; missing samples count as zero. Peaks are refined by parabolic
//! interpolation of the log-power over the three bins around the maximum (Smith & Serra 1987).
//!
//! A peak's **steady power** ([`steady_power`]) tells a line (a sinusoid of constant amplitude
//! and phase) from a bump of coloured residual at the same frequency: the sinusoid at `f` is
//! fitted by least squares on each half of the record, `x_k ≈ a_h sin(2π f t_k) + b_h cos(2π f
//! t_k) + m_h` on half `h` (one time origin for both), and `S = a_1 a_2 + b_1 b_2`, the real part
//! of the cross-product of the halves' complex amplitudes. A steady line of amplitude `A` gives
//! `S ≈ A²` (`a_h² + b_h² = A²` in both halves alike); a component whose phase or amplitude wanders
//! (a misfit driven by the input, noise) gives `S` near zero or negative, whatever its power.

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

/// Mean periodogram of `x` over the bins with frequency in `band` (Hz), leaving out the bins
/// within two bins of `skip_hz` when given (the main lobe of a line there); `None` when no bin
/// is left. For white noise of variance `σ²` it estimates `σ²` (the normalisation of
/// [`periodogram`]); for a coloured residual, its level in that band.
pub fn band_level(x: &[f64], dt_s: f64, band: [f64; 2], skip_hz: Option<f64>) -> Option<f64> {
    let (f, p) = periodogram(x, dt_s);
    let df = f.get(1).copied().unwrap_or(f64::INFINITY);
    let (s, c) = f
        .iter()
        .zip(&p)
        .skip(1)
        .filter(|(fj, _)| **fj >= band[0] && **fj <= band[1])
        .filter(|(fj, _)| skip_hz.map_or(true, |s| (**fj - s).abs() > 2.0 * df))
        .fold((0.0, 0usize), |(s, c), (_, pj)| (s + pj, c + 1));
    (c > 0).then(|| s / c as f64)
}

/// Steady power of `x` (sampled every `dt_s`, `NaN` = missing) at `f_hz` (module doc): the
/// product of the sinusoid's complex amplitudes fitted on the two halves; 0 when a half has
/// too few samples to fit it.
pub fn steady_power(x: &[f64], dt_s: f64, f_hz: f64) -> f64 {
    let half = x.len() / 2;
    let w = 2.0 * std::f64::consts::PI * f_hz;
    let amplitude = |range: std::ops::Range<usize>| -> Option<(f64, f64)> {
        let mut ata = nalgebra::Matrix3::<f64>::zeros();
        let mut atb = nalgebra::Vector3::<f64>::zeros();
        let mut count = 0;
        for k in range.filter(|&k| x[k].is_finite()) {
            let t = k as f64 * dt_s;
            let row = nalgebra::Vector3::new((w * t).sin(), (w * t).cos(), 1.0);
            ata += row * row.transpose();
            atb += row * x[k];
            count += 1;
        }
        if count < 4 {
            return None;
        }
        let c = ata.lu().solve(&atb)?;
        (c[0].is_finite() && c[1].is_finite()).then_some((c[0], c[1]))
    };
    match (amplitude(0..half), amplitude(half..x.len())) {
        (Some((a1, b1)), Some((a2, b2))) => a1 * a2 + b1 * b2,
        _ => 0.0,
    }
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

    /// A weak steady line beside a stronger bump whose sign turns half way (a misfit of the
    /// model, driven by the input): the bump has the larger periodogram peak, the line the
    /// larger steady power.
    #[test]
    fn a_steady_line_outranks_a_stronger_bump_whose_phase_wanders() {
        let dt = 0.01;
        let tau = 2.0 * std::f64::consts::PI;
        let x: Vec<f64> = (0..2000)
            .map(|k| {
                let t = k as f64 * dt;
                // 12.4 Hz at amplitude 0.5, its envelope turning sign half way...
                let bump = 0.5 * (tau * t / 40.0).cos() * (tau * 12.4 * t).sin();
                // ...and a steady 0.1 at 22.8 Hz.
                bump + 0.1 * (tau * 22.8 * t + 0.3).sin()
            })
            .collect();
        let pk = peaks(&x, dt, 1.0, 45.0, 4);
        let near = |f: f64| *pk.iter().find(|p| (p.0 - f).abs() < 0.1).expect("a peak");
        let (bump, line) = (near(12.4), near(22.8));
        assert!(bump.1 > line.1, "{pk:?}");
        let (bump, line) = (steady_power(&x, dt, bump.0), steady_power(&x, dt, line.0));
        assert!((line - 0.01).abs() < 0.002, "line {line}");
        assert!(bump < 0.2 * line, "bump {bump}, line {line}");
    }
}
