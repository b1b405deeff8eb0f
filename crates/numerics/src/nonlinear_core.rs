//! The 2nd-order core with the two nonlinear laws real stands show: a cubic restoring term (a
//! hardening or softening spring, the Silverbox benchmark, Wigren & Schoukens 2013) and a time
//! scale that depends on the direction the output is driven (a motor spins up driven by the ESC
//! but spins down by drag alone).
//!
//! ```text
//!   T'' + 2ζ ω T' + ω² (T + ε T³) = ω² k u,      ω = ωn / s_dir
//!   dir = up   while k u − T − ε T³ ≥ 0   (the input drives the output up: s_dir = s_up)
//!         down otherwise                  (the output falls back:        s_dir = s_down)
//! ```
//!
//! In mass-spring-damper form `m y'' + d y' + k1 y + k3 y³ = u` this is `ε = k3 / k1`,
//! `k = 1/k1`, `ωn² = k1/m`, `2ζωn = d/m`. With `ε = 0` and `s_up = s_down = 1` it is the
//! linear core of [`crate::discretise`].
//!
//! **Stepping.** The input is held over the sample (zero-order hold), cut into `substeps`
//! equal steps `h`. In each the cubic term is a forcing `w = k u − ε T³` added to the
//! linear part, which is stepped exactly ([`discretise_second_order`] at `h` and `h/2`):
//! the exponential midpoint rule (second order in `h`; Hochbruck & Ostermann 2010,
//! "Exponential integrators", Acta Numerica 19, §2.2):
//!
//! ```text
//!   x½ = A(h/2) x + B(h/2) w(x),    x⁺ = A(h) x + B(h) w(x½)
//! ```
//!
//! The direction is decided at the start of each step. The simulated plant (`propid-sim`) and
//! the models `propid diagnose` fits both use this stepper.

use nalgebra::{Matrix2, Vector2};

use crate::discretise::discretise_second_order;

/// The nonlinear laws of the core (see the module doc); the default is the linear core.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoreLaw {
    /// Cubic stiffness relative to the linear one, `ε = k3/k1`, per output unit squared
    /// (> 0 hardens, < 0 softens).
    pub cubic: f64,
    /// Time scale of the response while the output is driven up (1 = the core's own).
    pub up_scale: f64,
    /// Time scale of the response while the output falls back (1 = the core's own).
    pub down_scale: f64,
}

impl Default for CoreLaw {
    fn default() -> Self {
        CoreLaw {
            cubic: 0.0,
            up_scale: 1.0,
            down_scale: 1.0,
        }
    }
}

impl CoreLaw {
    /// True for the linear core (no cubic term, one time scale).
    pub fn is_linear(&self) -> bool {
        self.cubic == 0.0 && self.up_scale == self.down_scale && self.up_scale == 1.0
    }
}

/// Exact linear steps at `h` and `h/2` for one direction (unit input gain).
#[derive(Debug, Clone, Copy)]
struct Steps {
    a: Matrix2<f64>,
    b: Vector2<f64>,
    a_half: Matrix2<f64>,
    b_half: Vector2<f64>,
}

impl Steps {
    fn new(fn_hz: f64, zeta: f64, h: f64) -> Steps {
        let (a, b) = discretise_second_order(fn_hz, zeta, 1.0, h);
        let (a_half, b_half) = discretise_second_order(fn_hz, zeta, 1.0, 0.5 * h);
        Steps {
            a,
            b,
            a_half,
            b_half,
        }
    }
}

/// A core with its [`CoreLaw`], ready to step (see the module doc).
#[derive(Debug, Clone)]
pub struct NonlinearCore {
    up: Steps,
    down: Steps,
    k: f64,
    cubic: f64,
    substeps: usize,
}

impl NonlinearCore {
    /// The core `fn_hz`, `zeta`, static gain `k`, sampled every `dt_s`, with `law`, stepped in
    /// `substeps` (≥ 1) steps per sample. Time scales must be positive.
    pub fn new(
        fn_hz: f64,
        zeta: f64,
        k: f64,
        dt_s: f64,
        law: CoreLaw,
        substeps: usize,
    ) -> NonlinearCore {
        let m = substeps.max(1);
        let h = dt_s / m as f64;
        // A time scale shrunk below the sample (a fit driving `up_scale` towards 0) is no mode
        // the samples can show: its frequency is held at the sample's Nyquist frequency
        // (beyond it nalgebra's exponential of the huge-norm matrix may never return).
        let nyquist = 0.5 / dt_s;
        let scaled = |s: f64| (fn_hz / s).min(nyquist);
        NonlinearCore {
            up: Steps::new(scaled(law.up_scale), zeta, h),
            down: Steps::new(scaled(law.down_scale), zeta, h),
            k,
            cubic: law.cubic,
            substeps: m,
        }
    }

    /// The state after one sample from `x = [T, T']` with input `u` held.
    pub fn step(&self, mut x: Vector2<f64>, u: f64) -> Vector2<f64> {
        let drive = self.k * u;
        for _ in 0..self.substeps {
            let w0 = drive - self.cubic * x[0] * x[0] * x[0];
            let s = if w0 - x[0] >= 0.0 {
                &self.up
            } else {
                &self.down
            };
            let half = s.a_half * x + s.b_half * w0;
            let w1 = drive - self.cubic * half[0] * half[0] * half[0];
            x = s.a * x + s.b * w1;
        }
        x
    }

    /// The steady state for input `u` held for ever: `T + ε T³ = k u` (the real root nearest
    /// the linear one, by Newton's method), `T' = 0`.
    pub fn settle(&self, u: f64) -> Vector2<f64> {
        Vector2::new(static_output(self.k * u, self.cubic), 0.0)
    }
}

/// The output `T` with `T + ε T³ = f`: Newton's method from the linear answer `T = f`, steps
/// kept within the branch through 0 (for a softening spring, beyond the fold
/// `T = ±1/√(3|ε|)` there is no steady state: the fold is returned).
pub fn static_output(f: f64, cubic: f64) -> f64 {
    if cubic == 0.0 || !f.is_finite() {
        return f;
    }
    let fold = if cubic < 0.0 {
        (1.0 / (3.0 * -cubic)).sqrt()
    } else {
        f64::INFINITY
    };
    // Start from the cube-root answer for a strong hardening spring, else from the linear one.
    let mut t = if cubic > 0.0 {
        let c = (f / cubic).cbrt();
        if c.abs() < f.abs() {
            c
        } else {
            f
        }
    } else {
        f.clamp(-fold, fold)
    };
    for _ in 0..60 {
        let g = t + cubic * t * t * t - f;
        let d = 1.0 + 3.0 * cubic * t * t;
        if d <= 1e-12 {
            break;
        }
        let next = (t - g / d).clamp(-fold, fold);
        if (next - t).abs() <= 1e-14 * (1.0 + t.abs()) {
            return next;
        }
        t = next;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_linear_law_is_the_exact_discretisation() {
        let (a, b) = discretise_second_order(8.0, 0.4, 2.0, 2e-3);
        let core = NonlinearCore::new(8.0, 0.4, 2.0, 2e-3, CoreLaw::default(), 3);
        let (mut x, mut z) = (Vector2::zeros(), Vector2::zeros());
        for k in 0..500 {
            let u = if (k / 50) % 2 == 0 { 0.3 } else { 0.7 };
            x = a * x + b * u;
            z = core.step(z, u);
            assert!((x - z).norm() < 1e-9, "k {k}: {x} vs {z}");
        }
    }

    #[test]
    fn a_hardening_spring_settles_below_the_linear_output_and_rings_faster() {
        let law = CoreLaw {
            cubic: 0.5,
            ..CoreLaw::default()
        };
        assert!((static_output(1.5, 0.5) - 1.0).abs() < 1e-12);
        let core = NonlinearCore::new(5.0, 0.05, 1.0, 1e-3, law, 2);
        let mut x = core.settle(0.0);
        for _ in 0..20_000 {
            x = core.step(x, 1.5);
        }
        assert!((x[0] - 1.0).abs() < 1e-6, "{x}");
        // Free oscillation about T = 1: stiffness 1 + 3ε = 2.5, frequency √2.5 × 5 Hz.
        let mut x = Vector2::new(1.01, 0.0);
        let mut crossings = Vec::new();
        let mut prev = x[0] - 1.0;
        for k in 0..2000 {
            x = core.step(x, 1.5);
            let now = x[0] - 1.0;
            if prev < 0.0 && now >= 0.0 {
                crossings.push(k);
            }
            prev = now;
        }
        let period_s = (crossings[3] - crossings[0]) as f64 * 1e-3 / 3.0;
        let want = 1.0 / (5.0 * 2.5f64.sqrt());
        assert!(
            (period_s - want).abs() < 0.02 * want,
            "{period_s} vs {want}"
        );
    }

    #[test]
    fn the_output_falls_back_on_its_own_time_scale() {
        let law = CoreLaw {
            up_scale: 1.0,
            down_scale: 3.0,
            ..CoreLaw::default()
        };
        let core = NonlinearCore::new(10.0, 1.0, 1.0, 1e-3, law, 1);
        let t_to = |from: f64, to: f64| {
            let mut x = core.settle(from);
            let target = from + 0.632 * (to - from);
            (1..5000)
                .find(|_| {
                    x = core.step(x, to);
                    (x[0] - target) * (to - from).signum() >= 0.0
                })
                .unwrap_or(0)
        };
        let (up, down) = (t_to(0.0, 1.0), t_to(1.0, 0.0));
        // Whole samples: ±1 sample on each.
        assert!((down as f64 / up as f64 - 3.0).abs() < 0.1, "{up} {down}");
    }

    #[test]
    fn a_softening_spring_beyond_its_fold_stops_at_the_fold() {
        let fold = (1.0f64 / 0.3).sqrt();
        assert!((static_output(10.0, -0.1) - fold).abs() < 1e-9);
        let t = static_output(0.5, -0.1);
        assert!((t - 0.1 * t * t * t - 0.5).abs() < 1e-12);
    }
}
