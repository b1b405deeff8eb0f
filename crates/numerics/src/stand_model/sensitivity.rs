//! Derivatives of the rotor's course ([`super::rotor_course`]) and of a sensor's lag
//! ([`super::lag`]) with respect to their parameters, by forward sensitivity recursions: the
//! stand fit's Jacobian without re-simulating the rotor once per parameter.
//!
//! # The rotor
//! Over a part `h` of a row the course steps `n⁺ = T + (n − T) E`, `E = e^{−h/τ}`, with the
//! target `T = n_ss(u, V)` and `τ = τ_dir (1 / max(n, n_ref/10))^γ` frozen at the part's start
//! (module doc of [`super`]; `n_ref = 1` in a fit). Differentiating the step with respect to
//! a parameter `q` (the sensitivity `s = ∂n/∂q` carried from row to row):
//!
//! ```text
//!   ∂n⁺ = ∂T (1 − E) + E s + (n − T) ∂E,       ∂E = E (h ∂τ / τ² − ∂h / τ)
//!   ∂τ  = τ [q = ln τ_dir] − τ ln(max(n, ⅒)) [q = γ] − γ τ / n · s [n > ⅒]
//!   ∂T  = a x^{a−1} (u − u_ref)/(u_ref − u₀)² · V/V_ref [q = u₀],   T ln x [q = a]   (x > 0)
//!   ∂h  = 1 (first part), −1 (second part)  [q = θ]
//! ```
//!
//! and the rate `n' = (T − n)/τ` gives `∂n' = (∂T − s)/τ − n' ∂τ/τ`. The dead time's whole
//! rows (`⌊θ/dt⌋`) are piecewise constant: only the fraction within a row has a derivative
//! (the one-sided one, towards a longer dead time, that a forward difference sees). The
//! supply is the measured voltage or a constant one (a fit has no resistance in the course).
//!
//! # A sensor's lag
//! `s⁺ = a s + (1 − a) x_k + ρ (x_{k+1} − x_k)` with `a = e^{−dt/τ}`, `ρ = 1 − τ(1 − a)/dt` is
//! linear in `x` (a derivative of `x` is lagged as `x` is), and with respect to `ln τ`:
//! `∂s⁺ = a ∂s + (a dt/τ)(s − x_k) + (a − τ(1 − a)/dt)(x_{k+1} − x_k)`, `∂s₀ = 0`.

use super::{fill_held, held_at, RotorCourse, StandParams};

/// A parameter of the rotor's course a sensitivity is carried for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RotorParam {
    /// The ESC's dead time `θ`, s.
    DeadTime,
    /// `ln τ_up` (and `ln τ_down` with it when `tied`).
    LnTauUp,
    /// `ln τ_down`.
    LnTauDown,
    /// `γ`.
    Gamma,
    /// The dead band `u₀`.
    CommandZero,
    /// The map's exponent `a`.
    MapExponent,
}

/// The course and, per parameter asked for, `∂n/∂q` and `∂n'/∂q` at every row.
#[derive(Debug, Clone, Default)]
pub struct CourseSensitivity {
    /// The course (as [`super::rotor_course`], to rounding).
    pub course: RotorCourse,
    /// `∂n_k/∂q` per parameter.
    pub d_speed: Vec<Vec<f64>>,
    /// `∂n'_k/∂q` per parameter.
    pub d_rate: Vec<Vec<f64>>,
}

/// The course of `p` (speed unit `n_ref = 1`, no supply resistance: `None` otherwise) under
/// `command` and `voltage` as [`super::rotor_course`] steps it, with the sensitivities of
/// `params` (module doc); `tied`: `τ_down` is `τ_up` (one parameter for both).
pub fn rotor_course_sensitivity(
    p: &StandParams,
    dt_s: f64,
    command: &[f64],
    voltage: Option<&[f64]>,
    params: &[RotorParam],
    tied: bool,
) -> Option<CourseSensitivity> {
    if p.supply.resistance_ohm != 0.0 || p.rotor.speed_ref != 1.0 || p.map.speed_ref != 1.0 {
        return None;
    }
    let len = command.len();
    let np = params.len();
    let u = fill_held(command, 0.0);
    let v_meas = voltage.map(|v| fill_held(v, p.map.voltage_ref));
    let delay = (p.dead_time_s / dt_s).max(0.0);
    let whole = delay.floor();
    let frac = delay - whole;
    let d = whole as isize;
    let map = &p.map;
    let rotor = &p.rotor;
    // n_ss and its derivatives.
    let target = |u: f64, v: f64, out: &mut [f64]| -> f64 {
        let span = map.command_ref - map.command_zero;
        let x = (u - map.command_zero).max(0.0) / span;
        let xa = if map.exponent == 1.0 {
            x
        } else {
            x.powf(map.exponent)
        };
        let scale = v / map.voltage_ref;
        let t = map.speed_ref * xa * scale;
        for (o, q) in out.iter_mut().zip(params) {
            *o = match q {
                RotorParam::CommandZero if x > 0.0 => {
                    let dx = (u - map.command_ref) / (span * span);
                    map.exponent * xa / x * dx * scale
                }
                RotorParam::MapExponent if x > 0.0 => t * x.ln(),
                _ => 0.0,
            };
        }
        t
    };
    // τ at n for a direction and its derivatives given ∂n = s.
    let floor = rotor.speed_ref / 10.0;
    let tau = |n: f64, up: bool, s: &[f64], out: &mut [f64]| -> f64 {
        let base = if up { rotor.tau_up_s } else { rotor.tau_down_s };
        let g = rotor.tau_speed_exponent;
        let m = n.max(floor);
        let factor = if g == 0.0 {
            1.0
        } else {
            (rotor.speed_ref / m).powf(g)
        };
        let t = base * factor;
        let dn = if g != 0.0 && n > floor {
            -g * t / n
        } else {
            0.0
        };
        for ((o, q), &sj) in out.iter_mut().zip(params).zip(s) {
            let own = match q {
                RotorParam::LnTauUp => up || tied,
                RotorParam::LnTauDown => !up,
                _ => false,
            };
            let mut x = if own { t } else { 0.0 };
            if *q == RotorParam::Gamma {
                x -= t * (m / rotor.speed_ref).ln();
            }
            *o = x + dn * sj;
        }
        t
    };
    let cmd = |j: isize| u[j.clamp(0, len as isize - 1) as usize];
    let mut out = CourseSensitivity {
        course: RotorCourse {
            speed: Vec::with_capacity(len),
            rate: Vec::with_capacity(len),
            voltage: Vec::with_capacity(len),
        },
        d_speed: vec![Vec::with_capacity(len); np],
        d_rate: vec![Vec::with_capacity(len); np],
    };
    if len == 0 {
        return Some(out);
    }
    let v0 = match &v_meas {
        Some(v) => held_at(v, 0, map.voltage_ref),
        None => p.supply.open_circuit_v,
    };
    let mut s = vec![0.0; np];
    let mut n = target(held_at(&u, 0, 0.0), v0, &mut s);
    let (mut d_tb, mut d_ta, mut d_tau) = (vec![0.0; np], vec![0.0; np], vec![0.0; np]);
    let mut s1 = vec![0.0; np];
    let h1 = frac * dt_s;
    let h2 = (1.0 - frac) * dt_s;
    for k in 0..len as isize {
        let (before, after) = (cmd(k - d - 1), cmd(k - d));
        let v = match &v_meas {
            Some(v) => v[k as usize],
            None => p.supply.open_circuit_v,
        };
        let tb = target(before, v, &mut d_tb);
        let ta = target(after, v, &mut d_ta);
        // The rate at the row's start.
        let (tn, d_tn) = if frac > 0.0 { (tb, &d_tb) } else { (ta, &d_ta) };
        let t0 = tau(n, tn >= n, &s, &mut d_tau);
        let rate = (tn - n) / t0;
        out.course.speed.push(n);
        out.course.rate.push(rate);
        out.course.voltage.push(v);
        for j in 0..np {
            out.d_speed[j].push(s[j]);
            out.d_rate[j].push((d_tn[j] - s[j]) / t0 - rate * d_tau[j] / t0);
        }
        // The first part (before the delayed command switches); none when frac = 0, but its
        // derivative towards a longer dead time is taken.
        let t1 = tau(n, tb >= n, &s, &mut d_tau);
        let e1 = if frac > 0.0 { (-h1 / t1).exp() } else { 1.0 };
        let n1 = if frac > 0.0 { tb + (n - tb) * e1 } else { n };
        for j in 0..np {
            let dh = if params[j] == RotorParam::DeadTime {
                1.0
            } else {
                0.0
            };
            let de = e1 * (h1 * d_tau[j] / (t1 * t1) - dh / t1);
            s1[j] = d_tb[j] * (1.0 - e1) + e1 * s[j] + (n - tb) * de;
        }
        // The second part.
        let t2 = tau(n1, ta >= n1, &s1, &mut d_tau);
        let e2 = (-h2 / t2).exp();
        let next = ta + (n1 - ta) * e2;
        for j in 0..np {
            let dh = if params[j] == RotorParam::DeadTime {
                -1.0
            } else {
                0.0
            };
            let de = e2 * (h2 * d_tau[j] / (t2 * t2) - dh / t2);
            s[j] = d_ta[j] * (1.0 - e2) + e2 * s1[j] + (n1 - ta) * de;
        }
        n = next;
    }
    Some(out)
}

/// [`super::lag`] of `x` and its derivative with respect to `ln τ` (module doc).
pub fn lag_d_ln_tau(x: &[f64], dt_s: f64, tau_s: f64) -> Vec<f64> {
    if x.is_empty() || tau_s.is_nan() || tau_s <= 0.0 {
        return vec![0.0; x.len()];
    }
    let a = (-dt_s / tau_s).exp();
    let ramp = 1.0 - tau_s * (1.0 - a) / dt_s;
    let da = a * dt_s / tau_s;
    let dramp = a - tau_s * (1.0 - a) / dt_s;
    let mut s = x[0];
    let mut ds = 0.0;
    let mut out = Vec::with_capacity(x.len());
    out.push(0.0);
    for w in x.windows(2) {
        ds = a * ds + da * (s - w[0]) + dramp * (w[1] - w[0]);
        s = a * s + (1.0 - a) * w[0] + ramp * (w[1] - w[0]);
        out.push(ds);
    }
    out
}

/// The derivative of [`super::delayed_at`] with respect to the delay at row `k` (the one-sided
/// one towards a longer delay at a whole number of rows; 0 where the delayed time is clamped
/// to the record).
pub fn delayed_at_d_delay(x: &[f64], dt_s: f64, delay_s: f64, k: usize) -> f64 {
    let len = x.len();
    if len < 2 {
        return 0.0;
    }
    let t = k as f64 - delay_s / dt_s;
    if t <= 0.0 || t > (len - 1) as f64 {
        return 0.0;
    }
    let i = t.floor() as usize;
    let f = t - i as f64;
    let i = if f == 0.0 { i - 1 } else { i };
    -(x[i + 1] - x[i]) / dt_s
}

#[cfg(test)]
mod tests {
    use super::super::{delayed_at, lag, rotor_course, CurrentLaw, RotorLaw, SpeedMap, Supply};
    use super::*;

    fn stand(p: &[f64; 6]) -> StandParams {
        StandParams {
            dead_time_s: p[0],
            map: SpeedMap {
                speed_ref: 1.0,
                command_zero: p[4],
                command_ref: 0.9,
                exponent: p[5],
                voltage_ref: 16.0,
            },
            rotor: RotorLaw {
                tau_up_s: p[1].exp(),
                tau_down_s: p[2].exp(),
                tau_speed_exponent: p[3],
                speed_ref: 1.0,
            },
            thrust_exponent: 2.0,
            k_t: 1.0,
            k_q: 1.0,
            current: CurrentLaw::default(),
            supply: Supply {
                open_circuit_v: 16.0,
                resistance_ohm: 0.0,
            },
        }
    }

    #[test]
    fn sensitivities_are_the_difference_quotients() {
        let dt = 0.002;
        let u: Vec<f64> = (0..600)
            .map(|k| [0.3, 0.7, 0.5, 0.9, 0.2][(k / 120) % 5])
            .collect();
        let z = [0.0131, 0.03f64.ln(), 0.05f64.ln(), 0.6, 0.08, 1.3];
        let params = [
            RotorParam::DeadTime,
            RotorParam::LnTauUp,
            RotorParam::LnTauDown,
            RotorParam::Gamma,
            RotorParam::CommandZero,
            RotorParam::MapExponent,
        ];
        let sens = rotor_course_sensitivity(&stand(&z), dt, &u, None, &params, false).unwrap();
        let base = rotor_course(&stand(&z), dt, &u, None);
        for k in 0..u.len() {
            assert!((sens.course.speed[k] - base.speed[k]).abs() < 1e-12);
        }
        for j in 0..params.len() {
            let h = 1e-7;
            let mut zh = z;
            zh[j] += h;
            let moved = rotor_course(&stand(&zh), dt, &u, None);
            for k in 0..u.len() {
                let fd = (moved.speed[k] - base.speed[k]) / h;
                let fr = (moved.rate[k] - base.rate[k]) / h;
                let scale = 1.0 + fd.abs();
                assert!(
                    (sens.d_speed[j][k] - fd).abs() < 1e-4 * scale,
                    "{:?} row {k}: {} vs {fd}",
                    params[j],
                    sens.d_speed[j][k]
                );
                assert!(
                    (sens.d_rate[j][k] - fr).abs() < 1e-3 * (1.0 + fr.abs()),
                    "{:?} rate row {k}: {} vs {fr}",
                    params[j],
                    sens.d_rate[j][k]
                );
            }
        }
    }

    #[test]
    fn a_lag_and_a_delay_differentiate_as_their_quotients() {
        let dt = 0.01;
        let x: Vec<f64> = (0..200).map(|k| ((k as f64) * 0.07).sin()).collect();
        let tau: f64 = 0.04;
        let h = 1e-7;
        let d = lag_d_ln_tau(&x, dt, tau);
        let (a, b) = (lag(&x, dt, tau), lag(&x, dt, (tau.ln() + h).exp()));
        for k in 0..x.len() {
            assert!((d[k] - (b[k] - a[k]) / h).abs() < 1e-5, "row {k}");
        }
        for delay in [0.0, 0.013, 0.02] {
            for k in [0usize, 1, 5, 100, 199] {
                let fd = (delayed_at(&x, dt, delay + h, k) - delayed_at(&x, dt, delay, k)) / h;
                let got = delayed_at_d_delay(&x, dt, delay, k);
                assert!(
                    (got - fd).abs() < 1e-4,
                    "delay {delay} row {k}: {got} vs {fd}"
                );
            }
        }
    }
}
