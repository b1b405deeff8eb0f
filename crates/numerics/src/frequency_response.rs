//! The frequency response of a stand from a swept-sine (chirp) record: Welch's averaged
//! spectra, the H1 estimator and its coherence, the peak, the bandwidth, the phase delay, and a
//! second-order-plus-dead-time model fitted to it.
//!
//! **Estimator** (Bendat & Piersol, *Random Data*, 4th ed., §9.2; Welch 1967): the input `u`
//! (the applied command) and the output `y` are cut into segments of `L` samples overlapping by
//! half, each made zero-mean and multiplied by a Hann window `w`, and transformed:
//! `U_m(f)`, `Y_m(f)`. Over the `M` segments
//!
//! ```text
//!   G_uu = Σ |U_m|²,   G_yy = Σ |Y_m|²,   G_uy = Σ conj(U_m)·Y_m
//!   H₁(f) = G_uy / G_uu                          (noise on y averages out)
//!   γ²(f) = |G_uy|² / (G_uu · G_yy)  ∈ [0, 1]     (1: y is linear in u, no noise)
//! ```
//!
//! `L` is the smallest power of two spanning two periods of the lowest frequency asked for
//! (`2/f_lo` seconds), at most half the record (three segments at least), at least
//! [`MIN_SEGMENT`]. Only bins within the swept band `[f_lo, f_hi]` are reported.
//!
//! **Figures**, on the bins whose coherence is at least [`MIN_COHERENCE`]:
//! - `gain_low`: `|H₁|` at the lowest such bin (the low-frequency gain the others refer to);
//! - `peak_hz`: the bin of largest `|H₁|`, refined by the parabola through it and its two
//!   neighbours on `ln|H₁|` (a resonance between bins);
//! - `bandwidth_hz`: the first frequency above which `|H₁|` stays below `gain_low/√2`
//!   (−3 dB), interpolated linearly between bins; `None` when the band never falls that far;
//! - `phase_delay_s` at a frequency `f`: `−∠H₁(f)/(2πf)`, the phase unwrapped from the
//!   lowest bin up; reported at the bandwidth (or the highest coherent bin without one).
//!
//! **Model** ([`fit_second_order`]): `H(s) = K ωₙ² e^{−sT} / (s² + 2ζωₙ s + ωₙ²)`, fitted by
//! Levenberg–Marquardt ([`crate::levenberg_marquardt`]) to the coherent bins on the complex
//! relative error `√γ²ᵢ (H(jωᵢ) − H₁ᵢ)/|H₁ᵢ|` (each bin by its share of the response, not its
//! size, and by how linear it is), from a few starts of ζ; the best kept.

use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use serde::Serialize;

use crate::discretise::discretise_second_order;
use crate::levenberg_marquardt::{minimise, LmOptions};
use crate::modal::{mass_spring_damper, second_order_poles};
use crate::report::{Gain, MassSpringDamper, ModeIndicators, ModelReport, Uncertainty};

/// Bins below this coherence are not used for the figures nor the fit.
pub const MIN_COHERENCE: f64 = 0.6;
/// Shortest segment, samples.
pub const MIN_SEGMENT: usize = 64;

/// One frequency bin of the response.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bin {
    /// Frequency, Hz.
    pub f_hz: f64,
    /// `|H₁|`, output unit per unit of input.
    pub gain: f64,
    /// `∠H₁`, degrees, unwrapped from the lowest bin.
    pub phase_deg: f64,
    /// `γ²`, 0..1.
    pub coherence: f64,
}

/// `K ωₙ² e^{−sT} / (s² + 2ζωₙ s + ωₙ²)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SecondOrder {
    /// Static gain `K`.
    pub gain: f64,
    /// Natural frequency `ωₙ/2π`, Hz.
    pub natural_hz: f64,
    /// Damping ratio `ζ`.
    pub damping: f64,
    /// Dead time `T`, s.
    pub dead_time_s: f64,
    /// RMS of the weighted relative residual (module doc) at the fit.
    pub rms_rel_error: f64,
}

impl SecondOrder {
    /// The model as the identification core reports one (`propid identify --json`'s fields):
    /// order 2, the exact zero-order-hold discretisation at `dt_s`
    /// ([`crate::discretise::discretise_second_order`], state `[T, T']`, `C = [1, 0]`), its
    /// poles, DC gain `K`, the mass–spring–damper equivalent. The dead time has no place in
    /// `A, B, C, D` (the caller publishes it beside); nothing the fit does not give (mode
    /// indicators, jackknife spreads, singular values) is reported: NaN, empty, 0.
    pub fn to_report(&self, dt_s: f64) -> ModelReport {
        let (a, b) = discretise_second_order(self.natural_hz, self.damping, self.gain, dt_s);
        let poles_s = second_order_poles(self.natural_hz, self.damping).to_vec();
        let poles_z: Vec<[f64; 2]> = poles_s
            .iter()
            .map(|s| {
                let m = (s[0] * dt_s).exp();
                [m * (s[1] * dt_s).cos(), m * (s[1] * dt_s).sin()]
            })
            .collect();
        let mut time_constants_s: Vec<f64> = poles_s
            .iter()
            .filter(|s| s[1] == 0.0 && s[0] < 0.0)
            .map(|s| -1.0 / s[0])
            .collect();
        time_constants_s.sort_by(|a, b| b.total_cmp(a));
        let (m, d, k) = mass_spring_damper(self.natural_hz, self.damping, self.gain);
        let none = ModeIndicators {
            msv: f64::NAN,
            mac: f64::NAN,
            emac: f64::NAN,
            mpc: f64::NAN,
            cmi: f64::NAN,
        };
        ModelReport {
            order: 2,
            dt_s,
            fn_hz: self.natural_hz,
            zeta: self.damping,
            dc_gain: Gain::Scalar(self.gain),
            time_constants_s,
            poles_s,
            poles_z,
            a: vec![vec![a[(0, 0)], a[(0, 1)]], vec![a[(1, 0)], a[(1, 1)]]],
            b: vec![vec![b[0]], vec![b[1]]],
            c: vec![vec![1.0, 0.0]],
            d: vec![vec![0.0]],
            singular_values: Vec::new(),
            indicators: vec![none; 2],
            uncertainty: Uncertainty {
                fn_hz: f64::NAN,
                zeta: f64::NAN,
                dc_gain: Gain::Scalar(f64::NAN),
            },
            pulses: 0,
            pulses_skipped: 0,
            missing_samples: 0,
            noise_rms: f64::NAN,
            mass_spring_damper: MassSpringDamper { m, d, k },
            hankel_block_rows: 0,
            hankel_block_cols: 0,
            svd: "none".into(),
            order_stepped_down_from: None,
        }
    }

    /// The model's response at `f_hz`.
    pub fn at(&self, f_hz: f64) -> Complex<f64> {
        second_order(
            self.gain,
            self.natural_hz,
            self.damping,
            self.dead_time_s,
            f_hz,
        )
    }
}

/// The frequency response of a record and its figures (module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrequencyResponse {
    /// The bins within the band.
    pub bins: Vec<Bin>,
    /// Segment length, samples, and their count.
    pub segment: usize,
    /// Segments averaged.
    pub segments: usize,
    /// Low-frequency gain (`None` without a coherent bin).
    pub gain_low: Option<f64>,
    /// Frequency of the largest gain, Hz.
    pub peak_hz: Option<f64>,
    /// −3 dB frequency, Hz.
    pub bandwidth_hz: Option<f64>,
    /// Phase delay `−∠H/(2πf)` at `bandwidth_hz` (or the highest coherent bin), s.
    pub phase_delay_s: Option<f64>,
    /// The frequency the phase delay is read at, Hz.
    pub phase_delay_at_hz: Option<f64>,
    /// The fitted second-order-plus-dead-time model.
    pub model: Option<SecondOrder>,
}

/// The response of `y` to `u` sampled every `dt_s` over the band `[f_lo, f_hi]` Hz (module
/// doc). `None` when the record is shorter than three [`MIN_SEGMENT`] segments or holds a
/// non-finite sample.
pub fn frequency_response(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    f_lo: f64,
    f_hi: f64,
) -> Option<FrequencyResponse> {
    let n = u.len().min(y.len());
    if n < 2 * MIN_SEGMENT
        || dt_s.is_nan()
        || dt_s <= 0.0
        || u[..n].iter().chain(&y[..n]).any(|v| !v.is_finite())
    {
        return None;
    }
    let want = (2.0 / (f_lo.max(1e-6) * dt_s)).ceil() as usize;
    let mut len = want.next_power_of_two().max(MIN_SEGMENT);
    while len > n / 2 && len > MIN_SEGMENT {
        len /= 2;
    }
    let hop = len / 2;
    let window: Vec<f64> = (0..len)
        .map(|k| 0.5 - 0.5 * (std::f64::consts::TAU * k as f64 / len as f64).cos())
        .collect();
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(len);
    let nb = len / 2 + 1;
    let (mut guu, mut gyy) = (vec![0.0; nb], vec![0.0; nb]);
    let mut guy = vec![Complex::new(0.0, 0.0); nb];
    let (mut bu, mut by) = (vec![0.0; len], vec![0.0; len]);
    let (mut su, mut sy) = (fft.make_output_vec(), fft.make_output_vec());
    let mut segments = 0;
    let mut start = 0;
    while start + len <= n {
        for (buf, x) in [
            (&mut bu, &u[start..start + len]),
            (&mut by, &y[start..start + len]),
        ] {
            let mean = x.iter().sum::<f64>() / len as f64;
            for k in 0..len {
                buf[k] = (x[k] - mean) * window[k];
            }
        }
        fft.process(&mut bu, &mut su).ok()?;
        fft.process(&mut by, &mut sy).ok()?;
        for k in 0..nb {
            guu[k] += su[k].norm_sqr();
            gyy[k] += sy[k].norm_sqr();
            guy[k] += su[k].conj() * sy[k];
        }
        segments += 1;
        start += hop;
    }
    let df = 1.0 / (len as f64 * dt_s);
    let mut bins = Vec::new();
    let mut last_phase: Option<f64> = None;
    for k in 1..nb {
        let f = k as f64 * df;
        if f < f_lo - 0.5 * df || f > f_hi + 0.5 * df || guu[k] <= 0.0 {
            continue;
        }
        let h = guy[k] / guu[k];
        let coh = if gyy[k] > 0.0 {
            (guy[k].norm_sqr() / (guu[k] * gyy[k])).min(1.0)
        } else {
            0.0
        };
        let mut ph = h.arg();
        if let Some(prev) = last_phase {
            ph += std::f64::consts::TAU * ((prev - ph) / std::f64::consts::TAU).round();
        }
        last_phase = Some(ph);
        bins.push(Bin {
            f_hz: f,
            gain: h.norm(),
            phase_deg: ph.to_degrees(),
            coherence: coh,
        });
    }
    let mut r = FrequencyResponse {
        bins,
        segment: len,
        segments,
        gain_low: None,
        peak_hz: None,
        bandwidth_hz: None,
        phase_delay_s: None,
        phase_delay_at_hz: None,
        model: None,
    };
    figures(&mut r);
    r.model = fit_second_order(&r);
    Some(r)
}

/// The figures of the coherent bins (module doc).
fn figures(r: &mut FrequencyResponse) {
    let ok: Vec<Bin> = r
        .bins
        .iter()
        .copied()
        .filter(|b| b.coherence >= MIN_COHERENCE)
        .collect();
    let Some(first) = ok.first() else { return };
    r.gain_low = Some(first.gain);
    let (i, top) = ok
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.gain.total_cmp(&b.1.gain))
        .map(|(i, b)| (i, *b))
        .unwrap_or((0, *first));
    let mut peak = top.f_hz;
    if i > 0 && i + 1 < ok.len() {
        let (a, b, c) = (ok[i - 1].gain.ln(), top.gain.ln(), ok[i + 1].gain.ln());
        let den = a - 2.0 * b + c;
        if den < 0.0 {
            let shift = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
            let step = if shift >= 0.0 {
                ok[i + 1].f_hz - top.f_hz
            } else {
                top.f_hz - ok[i - 1].f_hz
            };
            peak += shift * step;
        }
    }
    r.peak_hz = Some(peak);
    let half = first.gain / std::f64::consts::SQRT_2;
    // the first crossing below −3 dB after which the gain stays below
    let last_above = ok.iter().rposition(|b| b.gain >= half);
    if let Some(j) = last_above.filter(|&j| j + 1 < ok.len()) {
        let (a, b) = (ok[j], ok[j + 1]);
        let t = (a.gain - half) / (a.gain - b.gain);
        r.bandwidth_hz = Some(a.f_hz + t * (b.f_hz - a.f_hz));
    }
    let at = r.bandwidth_hz.unwrap_or(ok[ok.len() - 1].f_hz);
    // the phase at `at`, interpolated between the coherent bins around it
    let j = ok.iter().position(|b| b.f_hz >= at).unwrap_or(ok.len() - 1);
    let ph = if j > 0 && ok[j].f_hz > at {
        let (a, b) = (ok[j - 1], ok[j]);
        let t = (at - a.f_hz) / (b.f_hz - a.f_hz);
        a.phase_deg + t * (b.phase_deg - a.phase_deg)
    } else {
        ok[j].phase_deg
    };
    r.phase_delay_s = Some(-ph.to_radians() / (std::f64::consts::TAU * at));
    r.phase_delay_at_hz = Some(at);
}

fn second_order(k: f64, fn_hz: f64, zeta: f64, t: f64, f_hz: f64) -> Complex<f64> {
    let w = std::f64::consts::TAU * f_hz;
    let wn = std::f64::consts::TAU * fn_hz;
    let s = Complex::new(0.0, w);
    let delay = Complex::new(0.0, -w * t).exp();
    delay * (k * wn * wn) / (s * s + 2.0 * zeta * wn * s + wn * wn)
}

/// Fits the second-order-plus-dead-time model to the coherent bins of `r` (module doc);
/// `None` with fewer than 5 coherent bins.
pub fn fit_second_order(r: &FrequencyResponse) -> Option<SecondOrder> {
    let ok: Vec<Bin> = r
        .bins
        .iter()
        .copied()
        .filter(|b| b.coherence >= MIN_COHERENCE && b.gain > 0.0)
        .collect();
    if ok.len() < 5 {
        return None;
    }
    let meas: Vec<(f64, Complex<f64>, f64)> = ok
        .iter()
        .map(|b| {
            let h = Complex::from_polar(b.gain, b.phase_deg.to_radians());
            (b.f_hz, h, b.coherence.sqrt())
        })
        .collect();
    let k0 = r.gain_low?;
    let sign = if meas[0].1.re < 0.0 { -1.0 } else { 1.0 };
    let (f_lo, f_hi) = (ok[0].f_hz, ok[ok.len() - 1].f_hz);
    let peak = r.peak_hz.unwrap_or(f_hi);
    let resonant = ok.iter().any(|b| b.gain > 1.1 * k0);
    let fn0 = if resonant {
        peak
    } else {
        r.bandwidth_hz.unwrap_or(f_hi)
    };
    let mut residuals = |z: &[f64], out: &mut Vec<f64>| {
        out.clear();
        for &(f, h, w) in &meas {
            let e = (second_order(z[0], z[1], z[2], z[3], f) - h) / h.norm();
            out.push(w * e.re);
            out.push(w * e.im);
        }
        true
    };
    let bounds = [
        (-1e12, 1e12),
        (f_lo / 20.0, f_hi * 20.0),
        (0.005, 20.0),
        (0.0, 1.0),
    ];
    let peak_gain = ok.iter().map(|b| b.gain).fold(0.0, f64::max);
    let zeta_guess = (k0 / (2.0 * peak_gain)).clamp(0.02, 1.0);
    let mut best: Option<(f64, Vec<f64>)> = None;
    for zeta in [zeta_guess, 0.3, 0.7, 1.5] {
        let z0 = [sign * k0, fn0, zeta, 0.0];
        let Some(fit) = minimise(&mut residuals, &z0, &bounds, &LmOptions::default()) else {
            continue;
        };
        if best.as_ref().map_or(true, |b| fit.cost < b.0) {
            best = Some((fit.cost, fit.z));
        }
    }
    let (cost, z) = best?;
    Some(SecondOrder {
        gain: z[0],
        natural_hz: z[1],
        damping: z[2],
        dead_time_s: z[3],
        rms_rel_error: (cost / (2 * meas.len()) as f64).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fitted_model_reports_as_an_identified_one() {
        let m = SecondOrder {
            gain: 2.5,
            natural_hz: 8.0,
            damping: 0.3,
            dead_time_s: 0.01,
            rms_rel_error: 0.02,
        };
        let r = m.to_report(1e-3);
        assert_eq!((r.order, r.fn_hz, r.zeta), (2, 8.0, 0.3));
        // DC gain of the discrete model: C (I − A)⁻¹ B = K
        let (a, b) = (&r.a, &r.b);
        let det = (1.0 - a[0][0]) * (1.0 - a[1][1]) - a[0][1] * a[1][0];
        let x0 = ((1.0 - a[1][1]) * b[0][0] + a[0][1] * b[1][0]) / det;
        assert!((x0 - 2.5).abs() < 1e-9, "{x0}");
        // the discrete poles are the eigenvalues of A: their product is det A
        let pz = |k: usize| Complex::new(r.poles_z[k][0], r.poles_z[k][1]);
        let det_a = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        assert!(((pz(0) * pz(1)).re - det_a).abs() < 1e-12);
        assert!(
            r.time_constants_s.is_empty(),
            "complex poles: no real time constant"
        );
    }

    /// A log chirp through the discretised `K ωₙ²/(s² + 2ζωₙ s + ωₙ²)` (semi-implicit Euler at
    /// a fine step), with a pure delay of `delay` samples and white noise of `noise`.
    fn chirp_through(
        fn_hz: f64,
        zeta: f64,
        k: f64,
        delay: usize,
        noise: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let dt = 1e-3;
        let (f0, f1, t_end): (f64, f64, f64) = (0.5, 30.0, 40.0);
        let n = (t_end / dt) as usize;
        let r = (f1 / f0).ln();
        let wn = std::f64::consts::TAU * fn_hz;
        let (mut x, mut v) = (0.0, 0.0);
        let mut rng = 12345u64;
        let mut gauss = || {
            // Box–Muller on a 64-bit LCG
            let mut next = || {
                rng = rng
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((rng >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (next(), next());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        };
        let mut u = Vec::with_capacity(n);
        let mut ys = Vec::with_capacity(n);
        for i in 0..n {
            let t = i as f64 * dt;
            let ph = std::f64::consts::TAU * f0 * t_end / r * ((r * t / t_end).exp() - 1.0);
            u.push(0.5 + 0.1 * ph.sin());
        }
        for i in 0..n {
            let ui = u[i.saturating_sub(delay)];
            for _ in 0..10 {
                let h = dt / 10.0;
                v += h * (wn * wn * (k * ui - x) - 2.0 * zeta * wn * v);
                x += h * v;
            }
            ys.push(x + noise * gauss());
        }
        (u, ys)
    }

    #[test]
    fn the_peak_of_a_resonant_second_order_is_found_within_a_few_per_cent() {
        let (fn_hz, zeta) = (8.0, 0.15);
        let (u, y) = chirp_through(fn_hz, zeta, 12.0, 0, 0.02);
        let r = frequency_response(&u, &y, 1e-3, 0.5, 30.0).unwrap();
        let want = fn_hz * (1.0 - 2.0 * zeta * zeta).sqrt();
        let peak = r.peak_hz.unwrap();
        assert!((peak - want).abs() < 0.05 * want, "peak {peak} for {want}");
        let low = r.gain_low.unwrap();
        assert!((low - 12.0).abs() < 0.05 * 12.0, "gain {low}");
        let m = r.model.unwrap();
        assert!((m.natural_hz - fn_hz).abs() < 0.03 * fn_hz, "{m:?}");
        assert!((m.damping - zeta).abs() < 0.03, "{m:?}");
        assert!((m.gain - 12.0).abs() < 0.03 * 12.0, "{m:?}");
        assert!(r
            .bins
            .iter()
            .filter(|b| b.f_hz < 20.0)
            .all(|b| b.coherence > 0.9));
    }

    #[test]
    fn a_well_damped_plant_has_its_bandwidth_and_a_dead_time_its_phase_delay() {
        // ζ = 1: |H| = K/(1 + (f/fn)²), −3 dB at fn·√(√2 − 1)
        let (u, y) = chirp_through(4.0, 1.0, 2.0, 20, 0.0);
        let r = frequency_response(&u, &y, 1e-3, 0.5, 30.0).unwrap();
        let bw = r.bandwidth_hz.unwrap();
        let want = 4.0 * (2f64.sqrt() - 1.0).sqrt();
        assert!((bw - want).abs() < 0.05 * want, "bandwidth {bw} for {want}");
        let m = r.model.unwrap();
        assert!((m.dead_time_s - 0.020).abs() < 0.002, "{m:?}");
        assert!((m.natural_hz - 4.0).abs() < 0.1, "{m:?}");
        // the phase delay at the bandwidth: the lag's 2·atan(f/fn)/ω plus the 20 ms
        let f = r.phase_delay_at_hz.unwrap();
        let w = std::f64::consts::TAU * f;
        let want = 2.0 * (f / 4.0).atan() / w + 0.020;
        let got = r.phase_delay_s.unwrap();
        assert!((got - want).abs() < 0.05 * want, "{got} for {want}");
    }

    #[test]
    fn too_short_a_record_gives_none() {
        assert!(frequency_response(&[0.0; 100], &[0.0; 100], 1e-3, 1.0, 10.0).is_none());
    }
}
