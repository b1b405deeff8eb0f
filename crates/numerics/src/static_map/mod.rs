//! The static map of a stand: the steady output at each held command level, and the two curves
//! flight-controller set-ups use to describe it.
//!
//! - **Levels**: for each held command level, the mean, standard deviation and count of the
//!   output over the hold's last [`STEADY_SHARE`] (the transient after the step left out;
//!   missing samples, NaN, skipped per channel, so a sensor updated at its own rate is read at
//!   that rate).
//! - **Power law** `T = k·max(u − u₀, 0)^e` (thrust of a fixed-pitch propeller grows with the
//!   square of speed, speed about linearly with command above a dead band, so `e ≈ 2` is usual):
//!   `u₀` by a search that fits `ln T = ln k + e·ln(u − u₀)` by least squares for each candidate,
//!   then Gauss–Newton on the weighted squared error `Σ wᵢ (Tᵢ − T̂ᵢ)²` over all three
//!   parameters, `wᵢ = 1 / max(|Tᵢ|, RELATIVE_FLOOR · max|T|)²` ([`power_weights`]): the
//!   relative error of each level, levels under 5 % of full thrust counted as if at 5 % (their
//!   relative error means little). A real propeller's curve is no exact power law (it rolls off
//!   at the top as the supply sags), and a fit in the output's own unit lets the top levels
//!   decide: a generated staircase of a 5" propeller's table (30 … 1520 gf) had its
//!   15 %-of-full-thrust level 11.6 % off when fitted in newtons (a one-off check of the
//!   earlier fit); fitted by relative error, every level of that table from 7 % of full thrust
//!   up is within 10 % (this module's tests).
//!   The loop gain a controller derives from the map is wrong by the map's relative error,
//!   wherever on the curve it operates.
//!   Uncertainty: standard errors from `s²·(JᵀWJ)⁻¹`, `s² = Σ wᵢ rᵢ² / (n − 3)`.
//! - **Expo** `T/t_max = (1 − a)·x + a·x²` with `x` the command 0..1 (ArduPilot
//!   `MOT_THST_EXPO`, PX4 `THR_MDL_FAC`): linear least squares `T = c₁x + c₂x²`, then
//!   `t_max = c₁ + c₂`, `a = c₂/(c₁ + c₂)`; uncertainty by the delta method from the covariance
//!   of `(c₁, c₂)`.
//! - **Thrust coefficient** `T = k_t·ω²` (ω in rad/s), least squares through the origin.
//!
//! - **Slope** of the least-squares line through the levels ([`slope`]): the gain the steady
//!   states show, against which [`crate::quality`] judges a linear model's DC gain.
//! - **Repeats**: the commands held more than once and how far their later visits moved
//!   ([`repeats`]): whether the stand repeats itself.
//! - **Zero offset**: the output's reading at zero command when the levels show one (a load
//!   cell not tared, an ESC's idle current: [`zero_offset`]); the curves then describe the
//!   output above it.
//!
//! Fewer levels than parameters give no fit (`None`); exactly as many give the curve with no
//! uncertainty (`None` standard errors): the data cannot support a spread then.

pub mod offset;
pub mod repeats;
pub mod slope;

use serde::Serialize;

use crate::segment::Run;

pub use offset::{shifted, zero_offset, ZeroOffset};
pub use repeats::{not_repeatable, repeats, Repeat, MIN_SHARE, NOISE_FACTOR};
pub use slope::{level_slope, LevelSlope};

/// Share of a hold, from its end, taken as steady.
pub const STEADY_SHARE: f64 = 0.5;

/// One held command level of a channel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Level {
    /// Command, throttle 0..1.
    pub throttle: f64,
    /// Mean of the steady part, the channel's SI unit.
    pub mean: f64,
    /// Standard deviation of the steady part.
    pub std: f64,
    /// Measured samples in the steady part.
    pub samples: usize,
}

/// The steady levels of channel `y` over `holds` ([`crate::segment::holds`]: runs of steady
/// command, each at its `value`), holds with no measured sample left out.
pub fn levels(y: &[f64], holds: &[Run]) -> Vec<Level> {
    holds
        .iter()
        .filter_map(|h| levels_over(y, h, STEADY_SHARE))
        .collect()
}

/// The level of `y` over the last `share` of `run` (`None` without a measured sample).
fn levels_over(y: &[f64], run: &Run, share: f64) -> Option<Level> {
    let end = run.end.min(y.len());
    if run.start >= end {
        return None;
    }
    let len = end - run.start;
    let from = end - ((len as f64 * share).ceil() as usize).clamp(1, len);
    let (mut n, mut s) = (0usize, 0.0);
    for v in y[from..end].iter().filter(|v| v.is_finite()) {
        n += 1;
        s += v;
    }
    if n == 0 {
        return None;
    }
    let mean = s / n as f64;
    let var = y[from..end]
        .iter()
        .filter(|v| v.is_finite())
        .map(|x| (x - mean) * (x - mean))
        .sum::<f64>()
        / n as f64;
    Some(Level {
        throttle: run.value,
        mean,
        std: var.sqrt(),
        samples: n,
    })
}

/// The levels of channel `y` over ramp windows ([`crate::segment::ramp_windows`]): each at the
/// window's mean command, with the mean output over the whole window (a slow ramp read as
/// quasi-static; no transient to leave out).
pub fn window_levels(y: &[f64], windows: &[crate::segment::Level]) -> Vec<Level> {
    windows
        .iter()
        .filter_map(|w| {
            let run = Run {
                lead: w.start,
                start: w.start,
                end: w.end,
                value: w.value,
            };
            levels_over(y, &run, 1.0)
        })
        .collect()
}

/// `T = k·max(u − u0, 0)^exponent`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PowerLaw {
    /// Gain, output unit.
    pub k: f64,
    /// Dead band: the command where the output starts, throttle.
    pub u0: f64,
    /// Exponent.
    pub exponent: f64,
    /// Standard errors (`None` without spare degrees of freedom).
    pub uncertainty: Option<PowerLawSd>,
}

/// Standard errors of a [`PowerLaw`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PowerLawSd {
    /// Of `k`.
    pub k: f64,
    /// Of `u0`.
    pub u0: f64,
    /// Of `exponent`.
    pub exponent: f64,
}

impl PowerLaw {
    /// The map's output at command `u`.
    pub fn predict(&self, u: f64) -> f64 {
        let d = u - self.u0;
        if d <= 0.0 {
            0.0
        } else {
            self.k * d.powf(self.exponent)
        }
    }
}

/// `T/t_max = (1 − a)·x + a·x²`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Expo {
    /// Curvature (0 linear, 1 quadratic).
    pub a: f64,
    /// Output at full command.
    pub t_max: f64,
    /// Standard errors (`None` without spare degrees of freedom).
    pub uncertainty: Option<ExpoSd>,
}

/// Standard errors of an [`Expo`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ExpoSd {
    /// Of `a`.
    pub a: f64,
    /// Of `t_max`.
    pub t_max: f64,
}

impl Expo {
    /// The map's output at command `x`.
    pub fn predict(&self, x: f64) -> f64 {
        self.t_max * ((1.0 - self.a) * x + self.a * x * x)
    }
}

/// `T = k_t·ω²`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ThrustCoefficient {
    /// N/(rad/s)².
    pub k_t: f64,
    /// Its standard error (`None` with one level).
    pub k_t_sd: Option<f64>,
}

fn finite(levels: &[Level]) -> impl Iterator<Item = &Level> {
    levels
        .iter()
        .filter(|l| l.throttle.is_finite() && l.mean.is_finite())
}

/// Solves the symmetric 3 × 3 (or smaller, `n` ≤ 3) system `M x = r` by Gaussian elimination
/// with partial pivoting; `None` when singular. Returns also the inverse's diagonal.
fn solve_sym(m: &[[f64; 3]; 3], r: &[f64; 3], n: usize) -> Option<([f64; 3], [f64; 3])> {
    let mut a = [[0.0; 6]; 3];
    for i in 0..n {
        for j in 0..n {
            a[i][j] = m[i][j];
        }
        a[i][n + i] = 1.0;
    }
    let scale = (0..n).map(|i| m[i][i].abs()).fold(0.0, f64::max);
    for c in 0..n {
        let p = (c..n).max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))?;
        if a[p][c].abs() <= 1e-14 * scale.max(f64::MIN_POSITIVE) || a[p][c].is_nan() {
            return None;
        }
        a.swap(c, p);
        for row in 0..n {
            if row != c {
                let f = a[row][c] / a[c][c];
                for col in 0..2 * n {
                    a[row][col] -= f * a[c][col];
                }
            }
        }
    }
    let mut inv_diag = [0.0; 3];
    let mut x = [0.0; 3];
    for i in 0..n {
        inv_diag[i] = a[i][n + i] / a[i][i];
        x[i] = (0..n).map(|j| a[i][n + j] / a[i][i] * r[j]).sum();
    }
    Some((x, inv_diag))
}

/// Share of the largest level below which a level's relative error is counted as if it were
/// that large ([`power_weights`]).
pub const RELATIVE_FLOOR: f64 = 0.05;

/// The power law's weights of outputs `t`: `1 / max(|t|, RELATIVE_FLOOR · max|t|)²` (the module
/// doc); all 1 when every output is 0.
pub fn power_weights(t: &[f64]) -> Vec<f64> {
    let top = t.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let floor = RELATIVE_FLOOR * top;
    t.iter()
        .map(|v| match floor > 0.0 {
            true => 1.0 / v.abs().max(floor).powi(2),
            false => 1.0,
        })
        .collect()
}

/// Least-squares fit of ln T = ln k + e ln(u − u0) for a fixed `u0`; returns (k, e, the
/// weighted squared error `Σ w (T − T̂)²` with weights `w`).
fn log_fit(pts: &[(f64, f64)], w: &[f64], u0: f64) -> Option<(f64, f64, f64)> {
    let xs: Vec<(f64, f64)> = pts
        .iter()
        .filter(|(u, t)| *u > u0 && *t > 0.0)
        .map(|(u, t)| ((u - u0).ln(), t.ln()))
        .collect();
    if xs.len() < 2 {
        return None;
    }
    let n = xs.len() as f64;
    let (mx, my) = (
        xs.iter().map(|p| p.0).sum::<f64>() / n,
        xs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = xs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx.is_nan() || sxx <= 0.0 {
        return None;
    }
    let e = xs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / sxx;
    let k = (my - e * mx).exp();
    let law = PowerLaw {
        k,
        u0,
        exponent: e,
        uncertainty: None,
    };
    let sse = pts
        .iter()
        .zip(w)
        .map(|((u, t), w)| w * (t - law.predict(*u)).powi(2))
        .sum();
    Some((k, e, sse))
}

/// Whether the output falls as the command rises: the least-squares slope of the levels
/// ([`level_slope`]) is negative. A load cell mounted the other way round, a pusher propeller
/// pulling on it, a torque sensor under a motor turning the other way: the magnitude still
/// grows with the command, and [`fit_power_law`] and [`fit_expo`] fit the magnitude, `k` and
/// `t_max` then negative.
pub fn falls_with_command(levels: &[Level]) -> bool {
    level_slope(levels).is_some_and(|s| s.slope < 0.0)
}

/// The levels with their means (the output) negated.
fn mirrored(levels: &[Level]) -> Vec<Level> {
    levels
        .iter()
        .map(|l| Level {
            mean: -l.mean,
            ..*l
        })
        .collect()
}

/// Fits the power law to the levels (see the module doc); `None` with fewer than three levels
/// or no output above zero. An output that falls as the command rises
/// ([`falls_with_command`]) is fitted by its magnitude: `k` negative.
pub fn fit_power_law(levels: &[Level]) -> Option<PowerLaw> {
    if falls_with_command(levels) {
        return fit_rising_power_law(&mirrored(levels)).map(|p| PowerLaw { k: -p.k, ..p });
    }
    fit_rising_power_law(levels)
}

/// [`fit_power_law`] of an output that rises with the command.
fn fit_rising_power_law(levels: &[Level]) -> Option<PowerLaw> {
    let pts: Vec<(f64, f64)> = finite(levels).map(|l| (l.throttle, l.mean)).collect();
    let w = power_weights(&pts.iter().map(|p| p.1).collect::<Vec<_>>());
    let first_on = pts
        .iter()
        .filter(|(_, t)| *t > 0.0)
        .map(|(u, _)| *u)
        .fold(f64::INFINITY, f64::min);
    if pts.len() < 3 || !first_on.is_finite() {
        return None;
    }
    let u_max = pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let span = (u_max - first_on).max(1e-6);
    // Candidate dead bands from well below the first positive level up to just under it.
    let (lo, hi) = (
        first_on - 2.0 * span.max(first_on.abs()),
        first_on - 1e-3 * span,
    );
    let mut best: Option<(f64, f64, f64, f64)> = None;
    for i in 0..=400 {
        let u0 = lo + (hi - lo) * i as f64 / 400.0;
        if let Some((k, e, sse)) = log_fit(&pts, &w, u0) {
            if best.map_or(true, |b| sse < b.3) {
                best = Some((k, u0, e, sse));
            }
        }
    }
    let (mut k, mut u0, mut e, mut sse) = best?;
    // Gauss–Newton with step halving on the weighted squared error.
    let jac = |k: f64, u0: f64, e: f64, u: f64| -> [f64; 3] {
        let d = u - u0;
        if d <= 0.0 {
            return [0.0; 3];
        }
        let p = d.powf(e);
        [p, -k * e * d.powf(e - 1.0), k * p * d.ln()]
    };
    let sse_of = |k: f64, u0: f64, e: f64| -> f64 {
        let law = PowerLaw {
            k,
            u0,
            exponent: e,
            uncertainty: None,
        };
        pts.iter()
            .zip(&w)
            .map(|((u, t), w)| w * (t - law.predict(*u)).powi(2))
            .sum()
    };
    let normal = |k: f64, u0: f64, e: f64| {
        let mut m = [[0.0; 3]; 3];
        let mut r = [0.0; 3];
        let law = PowerLaw {
            k,
            u0,
            exponent: e,
            uncertainty: None,
        };
        for (&(u, t), &wi) in pts.iter().zip(&w) {
            let j = jac(k, u0, e, u);
            let res = t - law.predict(u);
            for a in 0..3 {
                r[a] += wi * j[a] * res;
                for b in 0..3 {
                    m[a][b] += wi * j[a] * j[b];
                }
            }
        }
        (m, r)
    };
    for _ in 0..50 {
        let (m, r) = normal(k, u0, e);
        let Some((dx, _)) = solve_sym(&m, &r, 3) else {
            break;
        };
        let mut step = 1.0;
        let mut improved = false;
        for _ in 0..20 {
            let (k1, u1, e1) = (k + step * dx[0], u0 + step * dx[1], e + step * dx[2]);
            let s1 = sse_of(k1, u1, e1);
            if k1 > 0.0 && e1 > 0.0 && u1 < first_on && s1 < sse {
                (k, u0, e, sse) = (k1, u1, e1, s1);
                improved = true;
                break;
            }
            step *= 0.5;
        }
        if !improved {
            break;
        }
    }
    let n = pts.len();
    let uncertainty = if n > 3 {
        let (m, _) = normal(k, u0, e);
        solve_sym(&m, &[0.0; 3], 3).map(|(_, d)| {
            let s2 = sse / (n - 3) as f64;
            PowerLawSd {
                k: (s2 * d[0]).max(0.0).sqrt(),
                u0: (s2 * d[1]).max(0.0).sqrt(),
                exponent: (s2 * d[2]).max(0.0).sqrt(),
            }
        })
    } else {
        None
    };
    Some(PowerLaw {
        k,
        u0,
        exponent: e,
        uncertainty,
    })
}

/// Fits the expo curve to the levels (see the module doc); `None` with fewer than two levels or
/// a degenerate fit (`t_max` not positive). An output that falls as the command rises
/// ([`falls_with_command`]) is fitted by its magnitude: `t_max` negative, `a` the magnitude's.
pub fn fit_expo(levels: &[Level]) -> Option<Expo> {
    if falls_with_command(levels) {
        return fit_rising_expo(&mirrored(levels)).map(|e| Expo {
            t_max: -e.t_max,
            ..e
        });
    }
    fit_rising_expo(levels)
}

/// [`fit_expo`] of an output that rises with the command.
fn fit_rising_expo(levels: &[Level]) -> Option<Expo> {
    let pts: Vec<(f64, f64)> = finite(levels).map(|l| (l.throttle, l.mean)).collect();
    if pts.len() < 2 {
        return None;
    }
    let mut m = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    for &(x, t) in &pts {
        let j = [x, x * x];
        for a in 0..2 {
            r[a] += j[a] * t;
            for b in 0..2 {
                m[a][b] += j[a] * j[b];
            }
        }
    }
    let (c, _) = solve_sym(&m, &r, 2)?;
    let t_max = c[0] + c[1];
    if t_max.is_nan() || t_max <= 0.0 {
        return None;
    }
    let a = c[1] / t_max;
    let n = pts.len();
    let uncertainty = if n > 2 {
        let sse: f64 = pts
            .iter()
            .map(|&(x, t)| (t - c[0] * x - c[1] * x * x).powi(2))
            .sum();
        let s2 = sse / (n - 2) as f64;
        // Full 2 × 2 inverse for the covariance of (c1, c2).
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        (det > 0.0).then(|| {
            let (v11, v22, v12) = (s2 * m[1][1] / det, s2 * m[0][0] / det, -s2 * m[0][1] / det);
            // t_max = c1 + c2; a = c2/(c1 + c2): ∂a/∂c1 = −c2/S², ∂a/∂c2 = c1/S².
            let var_t = v11 + v22 + 2.0 * v12;
            let (g1, g2) = (-c[1] / (t_max * t_max), c[0] / (t_max * t_max));
            let var_a = g1 * g1 * v11 + g2 * g2 * v22 + 2.0 * g1 * g2 * v12;
            ExpoSd {
                a: var_a.max(0.0).sqrt(),
                t_max: var_t.max(0.0).sqrt(),
            }
        })
    } else {
        None
    };
    Some(Expo {
        a,
        t_max,
        uncertainty,
    })
}

/// Fits `T = k_t·ω²` to matching thrust (N) and speed (rad/s) levels (paired by index).
pub fn fit_thrust_coefficient(thrust: &[Level], omega: &[Level]) -> Option<ThrustCoefficient> {
    let pts: Vec<(f64, f64)> = thrust
        .iter()
        .zip(omega)
        .filter(|(t, w)| t.mean.is_finite() && w.mean.is_finite())
        .map(|(t, w)| (w.mean * w.mean, t.mean))
        .collect();
    let sww: f64 = pts.iter().map(|p| p.0 * p.0).sum();
    if pts.is_empty() || sww.is_nan() || sww <= 0.0 {
        return None;
    }
    let k_t = pts.iter().map(|p| p.0 * p.1).sum::<f64>() / sww;
    let n = pts.len();
    let k_t_sd = (n > 1).then(|| {
        let sse: f64 = pts.iter().map(|p| (p.1 - k_t * p.0).powi(2)).sum();
        (sse / (n - 1) as f64 / sww).sqrt()
    });
    Some(ThrustCoefficient { k_t, k_t_sd })
}

#[cfg(test)]
mod tests;
