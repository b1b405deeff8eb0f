//! The figures a propulsion engineer reads off a command step: dead time, time constant, 10–90 %
//! rise time, settling time and overshoot, per step and per direction.
//!
//! A step ([`crate::segment::steps`] finds them) `k0` goes from a held level (`before`, the samples `[b0, k0)`) to another (`after`,
//! `[k0, k1)`). The response's initial value `y₀` is the mean of the last part of the level
//! before, its final value `y₁` the mean of the last [`FINAL_SHARE`] of the hold after; the
//! normalised response is `r_k = (y_k − y₀)/(y₁ − y₀)` for `k ≥ k0`, and every crossing time is
//! linearly interpolated between samples, counted from the step's first sample (the first
//! sample taken with the new command).
//!
//! - **Dead time and time constant** by the two-point fit of a first-order-plus-dead-time model
//!   `r(t) = 1 − exp(−(t − θ)/τ)` through the 28.3 % and 63.2 % crossings (Smith 1972;
//!   Seborg, Edgar & Mellichamp, *Process Dynamics and Control*, §7.2):
//!   `τ = 1.5 (t₆₃ − t₂₈)`, `θ = t₆₃ − τ` (θ clipped at 0). A time constant shorter than one
//!   sample period cannot be told from a pure delay: it is reported as `None` with
//!   `resolvable = false`, never as a number. A dead time shorter than one sample period is
//!   within the uncertainty of when the command changed (anywhere between the sample before
//!   the step and the step's first): its value stays as a bound and
//!   `dead_time_below_sample` says so (the summary prints `< dt`), so that `0.000` is never
//!   read as a measured absence of delay.
//! - **Rise time** `t₉₀ − t₁₀`; **settling time** the time after which `r` stays within
//!   ±[`SETTLING_BAND`] of 1 until the end of the hold; **overshoot** `100·(max r − 1)` when
//!   positive, else 0.
//!
//! A step whose change `|y₁ − y₀|` is below [`MIN_SNR`] times the noise (the standard deviation
//! of the level before and after) supports none of these figures: they are all `None` and the
//! step says why. Pure functions on slices; no allocation beyond the returned values.

use serde::Serialize;

pub use crate::segment::Step;

/// Share of the hold after a step averaged for the final value.
pub const FINAL_SHARE: f64 = 1.0 / 3.0;
/// Samples of the level before a step averaged for the initial value (at most; fewer when the
/// level is shorter, at least half of it).
pub const INITIAL_SAMPLES: usize = 20;
/// Half-width of the settling band, as a share of the step.
pub const SETTLING_BAND: f64 = 0.1;
/// Smallest step, in noise standard deviations, whose figures are reported.
pub const MIN_SNR: f64 = 5.0;

/// Direction of a command step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// The command rose.
    Up,
    /// The command fell.
    Down,
}

/// The figures of one step's response.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepFigures {
    /// Time of the step, seconds from the record's start.
    pub t_s: f64,
    /// Command before.
    pub from: f64,
    /// Command after.
    pub to: f64,
    /// `up` or `down`.
    pub direction: Direction,
    /// Output before the step (mean of the level's end).
    pub initial: f64,
    /// Output after the step (mean of the hold's last third).
    pub r#final: f64,
    /// Dead time θ, s.
    pub dead_time_s: Option<f64>,
    /// `θ` is shorter than one sample period: a bound (`θ < dt`), not a measurement (omitted
    /// when false; module doc).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub dead_time_below_sample: bool,
    /// Time constant τ, s (`None` when not resolvable or not supported).
    pub time_constant_s: Option<f64>,
    /// Whether τ is longer than the sample period allows to tell (`false`: `τ < dt`).
    pub resolvable: bool,
    /// 10–90 % rise time, s.
    pub rise_10_90_s: Option<f64>,
    /// Time after which the response stays within ±10 % of the step, s.
    pub settling_90_s: Option<f64>,
    /// Overshoot beyond the final value, percent of the step.
    pub overshoot_pct: Option<f64>,
    /// Why figures are missing, when they are.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<&'static str>,
}

/// Mean and (population) standard deviation of a slice of finite values; NaN (missing) samples
/// are skipped. `None` when no finite value is there.
fn mean_std(y: &[f64]) -> Option<(f64, f64, usize)> {
    let (mut n, mut s) = (0usize, 0.0);
    for v in y.iter().filter(|v| v.is_finite()) {
        n += 1;
        s += v;
    }
    if n == 0 {
        return None;
    }
    let m = s / n as f64;
    let var = y
        .iter()
        .filter(|v| v.is_finite())
        .map(|v| (v - m) * (v - m))
        .sum::<f64>()
        / n as f64;
    Some((m, var.sqrt(), n))
}

/// First time (s from `at`) at which the normalised response reaches `level`, interpolated
/// linearly between the samples around the crossing. The sample at `at` is at time 0.
fn crossing(r: &[f64], level: f64, dt_s: f64) -> Option<f64> {
    let mut prev: Option<(usize, f64)> = None;
    for (k, &v) in r.iter().enumerate() {
        if !v.is_finite() {
            continue;
        }
        if v >= level {
            return Some(match prev {
                Some((j, p)) if v > p => (j as f64 + (level - p) / (v - p) * (k - j) as f64) * dt_s,
                _ => k as f64 * dt_s,
            });
        }
        prev = Some((k, v));
    }
    None
}

impl StepFigures {
    /// A step at `t_s` from command `from` to `to`, with no value and no figure yet.
    pub(crate) fn blank(t_s: f64, from: f64, to: f64) -> StepFigures {
        StepFigures {
            t_s,
            from,
            to,
            direction: if to >= from {
                Direction::Up
            } else {
                Direction::Down
            },
            initial: f64::NAN,
            r#final: f64::NAN,
            dead_time_s: None,
            dead_time_below_sample: false,
            time_constant_s: None,
            resolvable: false,
            rise_10_90_s: None,
            settling_90_s: None,
            overshoot_pct: None,
            note: None,
        }
    }

    /// Whether the step was found from the response, with no command levels (`from` and `to`
    /// NaN: [`crate::stand::response_step_figures`]).
    pub fn from_response(&self) -> bool {
        self.from.is_nan() && self.to.is_nan()
    }

    /// The step with no figure, only its time, levels and values, and `why` as its note.
    pub fn unsupported(self, why: &'static str) -> StepFigures {
        StepFigures {
            initial: self.initial,
            r#final: self.r#final,
            note: Some(why),
            ..StepFigures::blank(self.t_s, self.from, self.to)
        }
    }
}

/// The figures of one step of output `y` sampled every `dt_s` (NaN = missing sample).
pub fn step_figures(y: &[f64], dt_s: f64, step: &Step) -> StepFigures {
    let mut out = StepFigures::blank(step.at as f64 * dt_s, step.from, step.to);
    let end = step.after_end.min(y.len());
    if !(dt_s.is_finite() && dt_s > 0.0) || step.before_start >= step.at || step.at >= end {
        out.note = Some("the step has no samples on one side");
        return out;
    }
    let before_len = step.at - step.before_start;
    let init_len = INITIAL_SAMPLES.min(before_len).max(before_len / 2).max(1);
    let hold = end - step.at;
    let final_len = ((hold as f64 * FINAL_SHARE).round() as usize).max(1);
    let (Some((y0, s0, _)), Some((y1, s1, _))) = (
        mean_std(&y[step.at - init_len..step.at]),
        mean_std(&y[end - final_len..end]),
    ) else {
        out.note = Some("no measured samples before or after the step");
        return out;
    };
    out.initial = y0;
    out.r#final = y1;
    let delta = y1 - y0;
    let noise = s0.max(s1);
    if delta.is_nan() || delta == 0.0 || delta.abs() <= MIN_SNR * noise {
        out.note = Some("the response's change is within the noise");
        return out;
    }
    // Normalised response from the step on (the hold only).
    let r: Vec<f64> = y[step.at..end].iter().map(|v| (v - y0) / delta).collect();
    let (t10, t28, t63, t90) = (
        crossing(&r, 0.1, dt_s),
        crossing(&r, 0.283, dt_s),
        crossing(&r, 0.632, dt_s),
        crossing(&r, 0.9, dt_s),
    );
    if let (Some(a), Some(b)) = (t10, t90) {
        out.rise_10_90_s = Some(b - a);
    }
    if let (Some(t28), Some(t63)) = (t28, t63) {
        let tau = 1.5 * (t63 - t28);
        out.dead_time_s = Some((t63 - tau).max(0.0));
        if tau >= dt_s {
            out.time_constant_s = Some(tau);
            out.resolvable = true;
        } else {
            // Both crossings fall within one sample: a delay and a step, τ below resolution.
            out.dead_time_s = Some(t63.max(0.0));
            out.note = Some("the time constant is shorter than one sample period");
        }
        out.dead_time_below_sample = out.dead_time_s.is_some_and(|d| d < dt_s);
    }
    // Settling: the last sample outside the band; settled from the next one.
    let last_out = r
        .iter()
        .rposition(|v| v.is_finite() && (v - 1.0).abs() > SETTLING_BAND);
    out.settling_90_s = match last_out {
        None => Some(0.0),
        Some(k) if k + 1 < r.len() => Some((k + 1) as f64 * dt_s),
        Some(_) => None, // never settled within the hold
    };
    let peak = r
        .iter()
        .filter(|v| v.is_finite())
        .fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    out.overshoot_pct = Some(((peak - 1.0) * 100.0).max(0.0));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A first-order-plus-dead-time response to a step at `at`, sampled at the *end* of each
    /// period: y_k = y0 + Δ·(1 − exp(−(k − at + 1 − θ/dt)·dt/τ)) once the delay has passed.
    fn fopdt(n: usize, at: usize, dt: f64, y0: f64, dy: f64, theta: f64, tau: f64) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = (k as f64 - at as f64) * dt - theta;
                if t <= 0.0 {
                    y0
                } else {
                    y0 + dy * (1.0 - (-t / tau).exp())
                }
            })
            .collect()
    }

    fn step(at: usize, end: usize, from: f64, to: f64) -> Step {
        Step {
            before_start: 0,
            at,
            after_end: end,
            from,
            to,
        }
    }

    #[test]
    fn first_order_plus_dead_time_is_recovered() {
        let dt = 0.001;
        let y = fopdt(2000, 500, dt, 2.0, 3.0, 0.012, 0.040);
        let f = step_figures(&y, dt, &step(500, 2000, 0.4, 0.6));
        assert_eq!(f.direction, Direction::Up);
        assert!((f.time_constant_s.unwrap() - 0.040).abs() < 1e-3, "{f:?}");
        assert!((f.dead_time_s.unwrap() - 0.012).abs() < 1e-3, "{f:?}");
        assert!(f.resolvable);
        // 10–90 % rise of a first-order lag: τ ln 9.
        assert!((f.rise_10_90_s.unwrap() - 0.040 * 9f64.ln()).abs() < 1e-3);
        // Settling into ±10 %: θ + τ ln 10.
        assert!((f.settling_90_s.unwrap() - (0.012 + 0.040 * 10f64.ln())).abs() < 2e-3);
        assert!(f.overshoot_pct.unwrap() < 1e-6);
        assert!((f.initial - 2.0).abs() < 1e-12 && (f.r#final - 5.0).abs() < 1e-6);
    }

    #[test]
    fn a_step_down_is_normalised_the_same_way() {
        let dt = 0.01;
        let y = fopdt(400, 100, dt, 5.0, -3.0, 0.03, 0.15);
        let f = step_figures(&y, dt, &step(100, 400, 0.6, 0.4));
        assert_eq!(f.direction, Direction::Down);
        assert!((f.time_constant_s.unwrap() - 0.15).abs() < 0.01, "{f:?}");
        assert!((f.dead_time_s.unwrap() - 0.03).abs() < 0.01, "{f:?}");
    }

    #[test]
    fn a_dead_time_below_one_sample_is_a_bound() {
        // No delay and half a sample of it: both below the sample period, flagged; two
        // samples of it: measured, not flagged.
        let dt = 0.02;
        for (theta, below) in [(0.0, true), (0.01, true), (0.04, false)] {
            let y = fopdt(300, 100, dt, 0.0, 1.0, theta, 0.1);
            let f = step_figures(&y, dt, &step(100, 300, 0.2, 0.5));
            assert_eq!(f.dead_time_below_sample, below, "{theta}: {f:?}");
            assert!(f.resolvable);
            let json = serde_json::to_value(&f).unwrap();
            assert_eq!(
                json.get("dead_time_below_sample").is_some(),
                below,
                "{json}"
            );
        }
    }

    #[test]
    fn a_time_constant_below_one_sample_is_not_a_number() {
        let dt = 0.02;
        let y = fopdt(300, 100, dt, 0.0, 1.0, 0.04, 0.002);
        let f = step_figures(&y, dt, &step(100, 300, 0.2, 0.5));
        assert_eq!(f.time_constant_s, None);
        assert!(!f.resolvable);
        assert!(f.note.is_some());
        assert!((f.dead_time_s.unwrap() - 0.04).abs() <= dt, "{f:?}");
    }

    #[test]
    fn an_underdamped_response_shows_its_overshoot() {
        // 2nd order, ζ = 0.3: overshoot exp(−πζ/√(1−ζ²)) = 37.2 %.
        let (dt, wn, z) = (0.001, 2.0 * std::f64::consts::PI * 5.0, 0.3f64);
        let wd = wn * (1.0 - z * z).sqrt();
        let y: Vec<f64> = (0..3000)
            .map(|k| {
                let t = (k as f64 - 500.0) * dt;
                if t <= 0.0 {
                    0.0
                } else {
                    1.0 - (-z * wn * t).exp() * ((wd * t).cos() + z * wn / wd * (wd * t).sin())
                }
            })
            .collect();
        let f = step_figures(&y, dt, &step(500, 3000, 0.3, 0.5));
        let want = 100.0 * (-std::f64::consts::PI * z / (1.0 - z * z).sqrt()).exp();
        assert!((f.overshoot_pct.unwrap() - want).abs() < 0.5, "{f:?}");
    }

    #[test]
    fn a_step_in_the_noise_gives_no_figures() {
        let y: Vec<f64> = (0..400)
            .map(|k| if k % 2 == 0 { 0.1 } else { -0.1 })
            .collect();
        let f = step_figures(&y, 0.01, &step(200, 400, 0.3, 0.31));
        assert_eq!(f.time_constant_s, None);
        assert_eq!(f.dead_time_s, None);
        assert_eq!(f.rise_10_90_s, None);
        assert_eq!(f.note, Some("the response's change is within the noise"));
    }

    #[test]
    fn degenerate_steps_never_panic() {
        let y = vec![1.0; 10];
        for s in [
            step(0, 10, 0.1, 0.2),
            step(5, 5, 0.1, 0.2),
            step(9, 100, 0.1, 0.2),
            step(5, 3, 0.1, 0.2),
        ] {
            let f = step_figures(&y, 0.01, &s);
            assert_eq!(f.time_constant_s, None);
        }
        let nan = vec![f64::NAN; 10];
        assert_eq!(
            step_figures(&nan, 0.01, &step(5, 10, 0.1, 0.2)).dead_time_s,
            None
        );
        assert_eq!(
            step_figures(&y, 0.0, &step(5, 10, 0.1, 0.2)).dead_time_s,
            None
        );
    }
}
