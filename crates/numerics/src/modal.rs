//! Modal summary of a realised model: poles, natural frequency, damping, time constants, DC
//! gain and the mass–spring–damper equivalent.
//!
//! - Continuous poles `s = ln(z)/dt` (principal branch of the complex logarithm).
//! - For a pair of poles `s₁, s₂` (complex conjugate or both real): `ωn² = s₁ s₂`,
//!   `2 ζ ωn = −(s₁ + s₂)`, `fn = ωn / 2π`. For two real poles `ζ >= 1`.
//! - Time constants `τ = −1/s` for every real stable pole.
//! - DC gain `G(1) = D + C (I − A)^-1 B` (output units per unit input; with the one-sample
//!   Markov convention no `dt` enters).
//! - Mass–spring–damper (as in the seed article, `m ÿ + d ẏ + k y = F` with `F` one unit of
//!   throttle): matching `G(s) = K ωn² / (s² + 2ζωn s + ωn²)` to `1/(m s² + d s + k)` gives
//!   `k = 1/K`, `m = k / ωn²`, `d = 2 ζ ωn m` (from input 0 to output 0).

use nalgebra::Complex;

use super::linalg::solve_real;
use super::statespace::Abcd;

/// `s = ln(z)/dt`.
pub fn continuous(z: Complex<f64>, dt: f64) -> Complex<f64> {
    z.ln() / dt
}

/// `(fn_hz, zeta)` of a pole pair: `ωn² = s₁s₂`, `2ζωn = −(s₁+s₂)`.
pub fn fn_zeta(s1: Complex<f64>, s2: Complex<f64>) -> (f64, f64) {
    let wn2 = (s1 * s2).re;
    if !(wn2.is_finite() && wn2 > 0.0) {
        return (f64::NAN, f64::NAN);
    }
    let wn = wn2.sqrt();
    (
        wn / (2.0 * std::f64::consts::PI),
        -(s1 + s2).re / (2.0 * wn),
    )
}

/// DC gain `D + C (I − A)^-1 B` of `sys` into `out` (`q × p`, column-major). Scratch `m`
/// needs `n*n`, `x` needs `n*p`. Returns false when `I − A` is singular (a pole at z = 1).
pub fn dc_gain(sys: Abcd<'_>, m: &mut [f64], x: &mut [f64], out: &mut [f64]) -> bool {
    let Abcd {
        a,
        b,
        c,
        d,
        n,
        q,
        p,
    } = sys;
    for j in 0..n {
        for i in 0..n {
            m[i + j * n] = if i == j { 1.0 } else { 0.0 } - a[i + j * n];
        }
    }
    x[..n * p].copy_from_slice(&b[..n * p]);
    if !solve_real(m, n, x, p) {
        out[..q * p].fill(f64::NAN);
        return false;
    }
    for j in 0..p {
        for i in 0..q {
            let mut acc = d[i + j * q];
            for l in 0..n {
                acc += c[i + l * q] * x[l + j * n];
            }
            out[i + j * q] = acc;
        }
    }
    true
}

/// Poles of `s² + 2ζωn s + ωn²`, `[re, im]`, rad/s (ωn = 2π·`fn_hz`; two real poles for
/// ζ ≥ 1).
pub fn second_order_poles(fn_hz: f64, zeta: f64) -> [[f64; 2]; 2] {
    let wn = 2.0 * std::f64::consts::PI * fn_hz;
    if zeta < 1.0 {
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        [[-zeta * wn, wd], [-zeta * wn, -wd]]
    } else {
        let r = wn * (zeta * zeta - 1.0).sqrt();
        [[-zeta * wn + r, 0.0], [-zeta * wn - r, 0.0]]
    }
}

/// Mass–spring–damper equivalent `(m, d, k)` of a 2nd-order mode with DC gain `gain`.
pub fn mass_spring_damper(fn_hz: f64, zeta: f64, gain: f64) -> (f64, f64, f64) {
    let k = 1.0 / gain;
    let wn = 2.0 * std::f64::consts::PI * fn_hz;
    let m = k / (wn * wn);
    (m, 2.0 * zeta * wn * m, k)
}

/// True when `z` is (numerically) real.
pub fn is_real(z: Complex<f64>) -> bool {
    z.im.abs() <= 1e-12 * z.norm().max(1e-300)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pair_formulas() {
        // s = -ζωn ± iωn√(1-ζ²), ωn = 2π·10, ζ = 0.3.
        let wn = 2.0 * std::f64::consts::PI * 10.0;
        let (re, im) = (-0.3 * wn, wn * (1.0f64 - 0.09).sqrt());
        let (f, z) = fn_zeta(Complex::new(re, im), Complex::new(re, -im));
        assert!((f - 10.0).abs() < 1e-12 && (z - 0.3).abs() < 1e-12);
        // Real poles -2 and -8: ωn = 4, ζ = 10/8.
        let (f, z) = fn_zeta(Complex::new(-2.0, 0.0), Complex::new(-8.0, 0.0));
        assert!((f - 4.0 / (2.0 * std::f64::consts::PI)).abs() < 1e-12 && (z - 1.25).abs() < 1e-12);
        let (m, d, k) = mass_spring_damper(1.0 / (2.0 * std::f64::consts::PI), 0.5, 0.25);
        assert!((k - 4.0).abs() < 1e-12 && (m - 4.0).abs() < 1e-12 && (d - 4.0).abs() < 1e-12);
    }

    #[test]
    fn dc_gain_first_order() {
        // x+ = 0.5x + u, y = 2x + 0.1u → G(1) = 0.1 + 2/(1-0.5) = 4.1.
        let (mut m, mut x, mut out) = ([0.0; 1], [0.0; 1], [0.0; 1]);
        let sys = |a: &'static [f64]| Abcd {
            a,
            b: &[1.0],
            c: &[2.0],
            d: &[0.1],
            n: 1,
            q: 1,
            p: 1,
        };
        assert!(dc_gain(sys(&[0.5]), &mut m, &mut x, &mut out));
        assert!((out[0] - 4.1).abs() < 1e-14);
        assert!(!dc_gain(sys(&[1.0]), &mut m, &mut x, &mut out));
    }
}
