//! What `propid demo` prints beside each model of the motor plant: the plant linearised at the
//! model's level ([`PlantConfig::linearise`], formulas in `propid_sim::plant::linearise`), and
//! the figures that compare a model with it.
//!
//! The model's gain is its DC gain. Its dead time `θ` and time constant `τ` are read off its
//! unit-step response (`Σ Y_k`, from its own `A, B, C, D`) by the step figures' two-point
//! first-order-plus-dead-time fit ([`step_figures`]: `τ = 1.5 (t₆₃ − t₂₈)`, `θ = t₆₃ − τ`) —
//! the same rule applied to the truth's ideal pulse-averaged response gives the figures an
//! exact linear fit would have ([`Expected`]).
//!
//! Tolerances (measured over seeds in README's demo section): the gain within
//! [`GAIN_TOL`] of the truth `g`, `τ` between `(1 − TAU_TOL) τ_up` and `(1 + TAU_TOL) τ_down`,
//! `θ` within [`DEAD_TOL_SAMPLES`] sample periods of the truth. Two things keep a model off the
//! truth, both printed, never hidden: spin-down being slower than spin-up (a linear model
//! averages the two directions: gain above `g` by the asymmetry's factor, `τ` between the two),
//! and the daemon's 2nd-order model, which holds one sample of dead time (a first-order lag and
//! `d` samples of delay need order `d + 1`): with the demo's 2 samples its dead time reads one
//! sample short.

use crate::plant::{MotorLinear, PlantConfig};
use nalgebra::{DMatrix, DVector};
use propid_numerics::step_response::{step_figures, Step};
use propid_numerics::ModelReport;

/// Largest relative difference of a model's DC gain from the truth's `g`.
pub const GAIN_TOL: f64 = 0.15;
/// Margin on the time constant's range `[τ_up, τ_down]`, relative.
pub const TAU_TOL: f64 = 0.2;
/// Largest difference of a model's dead time from the truth, sample periods.
pub const DEAD_TOL_SAMPLES: f64 = 1.5;
/// Length of the responses compared, seconds (many time constants).
const RESPONSE_S: f64 = 1.0;
/// Samples before the step in the series handed to the step figures.
const PRE: usize = 20;

/// Gain, dead time and time constant of one linear response.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Figures {
    /// DC gain, N per unit throttle.
    pub gain: f64,
    /// Dead time θ, seconds (`None` when the step figures have none).
    pub dead_time_s: Option<f64>,
    /// Time constant τ, seconds.
    pub tau_s: Option<f64>,
}

/// The figures of a unit-pulse response (Markov parameters `Y_0, Y_1, …`) sampled every
/// `dt_s`, through its step response.
pub fn figures(markov: &[f64], dt_s: f64) -> Figures {
    let mut y = vec![0.0; PRE];
    let mut acc = 0.0;
    for &h in markov {
        acc += h;
        y.push(acc);
    }
    let step = Step {
        before_start: 0,
        at: PRE,
        after_end: y.len(),
        from: 0.0,
        to: 1.0,
    };
    let f = step_figures(&y, dt_s, &step);
    Figures {
        gain: acc,
        dead_time_s: f.dead_time_s,
        tau_s: f.time_constant_s,
    }
}

/// The first `len` Markov parameters `D, CB, CAB, …` of a single-input single-output model's
/// first output (empty when its matrices do not fit together).
pub fn markov(r: &ModelReport, len: usize) -> Vec<f64> {
    let n = r.order;
    let flat = |m: &[Vec<f64>]| m.iter().flatten().copied().collect::<Vec<f64>>();
    let (a, b, c) = (flat(&r.a), flat(&r.b), flat(&r.c));
    if n == 0 || a.len() != n * n || b.len() < n || c.len() < n {
        return Vec::new();
    }
    let a = DMatrix::from_row_slice(n, n, &a);
    // first input's column of B, first output's row of C
    let p = b.len() / n;
    let mut x = DVector::from_iterator(n, (0..n).map(|i| b[i * p]));
    let c = DVector::from_row_slice(&c[..n]);
    let mut out = Vec::with_capacity(len);
    out.push(
        r.d.first()
            .and_then(|row| row.first())
            .copied()
            .unwrap_or(0.0),
    );
    while out.len() < len {
        out.push(c.dot(&x));
        x = &a * x;
    }
    out
}

/// A model's figures.
pub fn model_figures(r: &ModelReport) -> Figures {
    let len = (RESPONSE_S / r.dt_s).ceil() as usize;
    figures(&markov(r, len), r.dt_s)
}

/// The truth at one model's level, and what an exact linear fit to pulses of both signs would
/// show there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Expected {
    /// The plant linearised at the level.
    pub truth: MotorLinear,
    /// The figures of the pulse-averaged linear response.
    pub linear_fit: Figures,
}

/// The truth at `level` for a model sampled every `dt_s` at device time `t_s` (`None` for
/// the 2nd-order plant).
pub fn expected(plant: &PlantConfig, level: f64, dt_s: f64, t_s: f64) -> Option<Expected> {
    let truth = plant.linearise(level, dt_s, t_s)?;
    let len = (RESPONSE_S / dt_s).ceil() as usize;
    Some(Expected {
        truth,
        linear_fit: figures(&truth.pulse_average(len), dt_s),
    })
}

/// Relative difference `model / truth − 1`.
pub fn off(model: f64, truth: f64) -> f64 {
    model / truth - 1.0
}

/// Whether a model's figures are within the stated tolerances of the truth.
pub fn within(f: &Figures, t: &MotorLinear) -> bool {
    let gain = off(f.gain, t.gain_n_per_throttle).abs() <= GAIN_TOL;
    let tau = f.tau_s.is_some_and(|tau| {
        tau >= (1.0 - TAU_TOL) * t.tau_up_s && tau <= (1.0 + TAU_TOL) * t.tau_down_s
    });
    let dead = f
        .dead_time_s
        .is_some_and(|d| (d - t.dead_time_s).abs() <= DEAD_TOL_SAMPLES * t.dt_s);
    gain && tau && dead
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::PlantKind;

    fn motor() -> PlantConfig {
        PlantConfig {
            kind: PlantKind::Motor,
            ..PlantConfig::default()
        }
    }

    #[test]
    fn first_order_plus_dead_time_figures_are_read_back() {
        // Y_k = g (1 − a) a^(k − 1 − d) from k = d + 1: θ = d dt, τ = −dt / ln a
        let (dt, tau, d, g): (f64, f64, usize, f64) = (0.004, 0.04, 2, 10.0);
        let a = (-dt / tau).exp();
        let h: Vec<f64> = (0..300)
            .map(|k| {
                if k > d {
                    g * (1.0 - a) * a.powi((k - 1 - d) as i32)
                } else {
                    0.0
                }
            })
            .collect();
        let f = figures(&h, dt);
        assert!((f.gain - g).abs() < 1e-6, "{f:?}");
        assert!((f.tau_s.unwrap() / tau - 1.0).abs() < 0.02, "{f:?}");
        assert!(
            (f.dead_time_s.unwrap() - d as f64 * dt).abs() < 0.2 * dt,
            "{f:?}"
        );
    }

    #[test]
    fn the_ideal_linear_fit_is_off_the_truth_by_the_asymmetry_only() {
        let e = expected(&motor(), 0.45, 0.004, 0.0).unwrap();
        let t = e.truth;
        let f = e.linear_fit;
        assert!((f.gain / t.gain_n_per_throttle - t.pulse_gain_factor).abs() < 1e-9);
        assert!(
            t.pulse_gain_factor > 1.0 && t.pulse_gain_factor < 1.1,
            "{t:?}"
        );
        let tau = f.tau_s.unwrap();
        assert!(tau > t.tau_up_s && tau < t.tau_down_s, "{f:?} {t:?}");
        assert!(within(&f, &t), "{f:?} {t:?}");
        // and a model with the step gain but no dead time is not
        let no_dead = Figures {
            dead_time_s: Some(0.0),
            ..f
        };
        assert!(!within(&no_dead, &t));
        assert!(expected(&PlantConfig::default(), 0.45, 0.004, 0.0).is_none());
    }
}
