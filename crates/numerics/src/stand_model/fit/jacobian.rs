//! The stand fit's Jacobian from the model's sensitivities instead of one re-simulation per
//! parameter: the rotor's course once per point with its derivatives
//! ([`crate::stand_model::sensitivity`]), each channel's bases and sensor differentiated from
//! them, and the amplitudes' re-solution differentiated as variable projection does.
//!
//! Per channel, `r = (y − A β)/σ` at the readings with `β = G⁻¹ Aᵀ y`, `G = AᵀA` (+ the fit's
//! ridge); for a nonlinear parameter `q` (Golub & Pereyra 1973, the full derivative of the
//! projection):
//!
//! ```text
//!   ∂β = G⁻¹ (∂Aᵀ (y − A β) − Aᵀ ∂A β),     ∂r = −(∂A β + A ∂β) / σ
//! ```
//!
//! `∂A` has columns only for the sensed bases (offset, creep and a sinusoid's columns do not
//! move). Bases: `∂ν = s`, `∂νᵉ = e νᵉ⁻¹ s` and `νᵉ ln ν` for `e`, `∂(ν ν') = s ν' + ν ∂ν'`;
//! a resonance and a lag are linear (their derivative is the derivative passed through them),
//! a lag's own `ln τ_s` and a delay's `δ` by [`lag_d_ln_tau`] and [`delayed_at_d_delay`]. The
//! command's clip, the speed map's voltage exponent, a sinusoid's frequency and a resonance's
//! own parameters keep a forward difference.

use nalgebra::{DMatrix, DVector};

use super::{Problem, Quantity, P};
use crate::levenberg_marquardt::Residuals;
use crate::stand_model::sensitivity::{
    delayed_at_d_delay, lag_d_ln_tau, rotor_course_sensitivity, RotorParam,
};
use crate::stand_model::{delayed_at, lag, speed_power};

/// A base's derivatives: (parameter's index in the layout, the derivative at every row).
type Derivatives = Vec<(usize, Vec<f64>)>;

/// The search's residuals and Jacobian ([`Problem::jacobian`]).
pub(super) struct Search<'a>(pub &'a Problem);

impl Residuals for Search<'_> {
    fn residuals(&mut self, z: &[f64], r: &mut Vec<f64>) -> bool {
        self.0.residuals(&self.0.values(z), None, r)
    }

    fn jacobian(
        &mut self,
        z: &[f64],
        r: &[f64],
        bounds: &[(f64, f64)],
        diff_step: f64,
    ) -> Option<DMatrix<f64>> {
        self.0.jacobian(z, r, bounds, diff_step)
    }
}

impl Problem {
    /// `∂r/∂z` of the weighted residuals `r` at `z` (module doc); a forward difference for the
    /// parameters without a sensitivity.
    pub(super) fn jacobian(
        &self,
        z: &[f64],
        r: &[f64],
        bounds: &[(f64, f64)],
        diff_step: f64,
    ) -> Option<DMatrix<f64>> {
        let v = self.values(z);
        let rotor: Vec<(usize, RotorParam)> = self
            .layout
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                let q = match p {
                    P::Dead => RotorParam::DeadTime,
                    P::TauUp => RotorParam::LnTauUp,
                    P::TauDown => RotorParam::LnTauDown,
                    P::Gamma => RotorParam::Gamma,
                    P::Zero => RotorParam::CommandZero,
                    P::MapExp => RotorParam::MapExponent,
                    _ => return None,
                };
                Some((i, q))
            })
            .collect();
        let params: Vec<RotorParam> = rotor.iter().map(|&(_, q)| q).collect();
        let clipped: Vec<f64>;
        let command = match v.limit {
            Some(l) => {
                clipped = self.u.iter().map(|&x| x.min(l)).collect();
                &clipped
            }
            None => &self.u,
        };
        let sens = rotor_course_sensitivity(
            &self.relative(&v),
            self.dt,
            command,
            self.drive_voltage(&v).as_deref(),
            &params,
            v.tau_down.is_none(),
        )?;
        let design = self.design(&v)?;
        let lin = self.solve(&design);
        let nz = z.len();
        let mut jac = DMatrix::<f64>::zeros(r.len(), nz);
        let (speed, rate) = (&sens.course.speed, &sens.course.rate);
        let e = v.exp;
        let exp_at = self.layout.iter().position(|&p| p == P::Exp);
        let mut row0 = 0;
        for (c, ch) in self.channels.iter().enumerate() {
            // The channel's bases at every row and, per parameter, their derivatives.
            let mut bases: Vec<(Vec<f64>, Derivatives)> = Vec::new();
            let through = |x: Vec<f64>| match (ch.quantity, v.mode) {
                (Quantity::Thrust | Quantity::Torque, Some((f, zeta))) => {
                    super::resonance(&x, self.dt, f, zeta)
                }
                _ => x,
            };
            match ch.quantity {
                Quantity::Speed => {
                    let d = rotor
                        .iter()
                        .enumerate()
                        .map(|(j, &(i, _))| (i, sens.d_speed[j].clone()))
                        .collect();
                    bases.push((speed.clone(), d));
                }
                Quantity::Thrust | Quantity::Torque | Quantity::Current => {
                    let e = e + v.exp_shift[c];
                    let pow = if ch.quantity == Quantity::Current {
                        e + 1.0
                    } else {
                        e
                    };
                    let b: Vec<f64> = speed.iter().map(|&n| speed_power(n, pow)).collect();
                    let slope: Vec<f64> = speed
                        .iter()
                        .map(|&n| {
                            if n > 0.0 {
                                pow * speed_power(n, pow - 1.0)
                            } else {
                                0.0
                            }
                        })
                        .collect();
                    let mut d: Vec<(usize, Vec<f64>)> = rotor
                        .iter()
                        .enumerate()
                        .map(|(j, &(i, _))| {
                            let x = slope.iter().zip(&sens.d_speed[j]).map(|(a, s)| a * s);
                            (i, through(x.collect()))
                        })
                        .collect();
                    let shift_at = self.layout.iter().position(|&p| p == P::ExpShift(c));
                    if exp_at.is_some() || shift_at.is_some() {
                        let x = b
                            .iter()
                            .zip(speed)
                            .map(|(&b, &n)| if n > 0.0 { b * n.ln() } else { 0.0 });
                        let x = through(x.collect());
                        for i in [exp_at, shift_at].into_iter().flatten() {
                            d.push((i, x.clone()));
                        }
                    }
                    bases.push((through(b), d));
                    if ch.quantity == Quantity::Current {
                        let b2 = speed.iter().zip(rate).map(|(&n, &r)| n.max(0.0) * r);
                        let d2 = rotor
                            .iter()
                            .enumerate()
                            .map(|(j, &(i, _))| {
                                let x = (0..speed.len()).map(|k| {
                                    let n = speed[k];
                                    if n > 0.0 {
                                        sens.d_speed[j][k] * rate[k] + n * sens.d_rate[j][k]
                                    } else {
                                        0.0
                                    }
                                });
                                (i, x.collect())
                            })
                            .collect();
                        bases.push((b2.collect(), d2));
                    }
                }
            }
            // Sensed at the readings: ∂A per parameter (columns of the bases only).
            let m = design[c].len();
            let nr = ch.rows.len();
            let mut d_a: Vec<Vec<Vec<f64>>> = vec![Vec::new(); nz];
            let (tau_s, delay_s) = (v.lag[c], v.delay[c]);
            let at_rows = |x: &[f64]| -> Vec<f64> {
                ch.rows
                    .iter()
                    .map(|&k| delayed_at(x, self.dt, delay_s, k))
                    .collect()
            };
            let lag_at = self.layout.iter().position(|&p| p == P::Lag(c));
            let delay_at = self.layout.iter().position(|&p| p == P::Delay(c));
            for (b_i, (b, d)) in bases.iter().enumerate() {
                let grow = |cols: &mut Vec<Vec<f64>>| {
                    while cols.len() <= b_i {
                        cols.push(vec![0.0; nr]);
                    }
                };
                for (i, db) in d {
                    grow(&mut d_a[*i]);
                    d_a[*i][b_i] = at_rows(&lag(db, self.dt, tau_s));
                }
                if let Some(i) = lag_at {
                    grow(&mut d_a[i]);
                    d_a[i][b_i] = at_rows(&lag_d_ln_tau(b, self.dt, tau_s));
                }
                if let Some(i) = delay_at {
                    grow(&mut d_a[i]);
                    let sensed = lag(b, self.dt, tau_s);
                    d_a[i][b_i] = ch
                        .rows
                        .iter()
                        .map(|&k| delayed_at_d_delay(&sensed, self.dt, delay_s, k))
                        .collect();
                }
            }
            // The projection's derivative (module doc).
            let a = &design[c];
            let beta = &lin[c];
            let chol = super::ridged_gram(a).cholesky();
            let fitted: Vec<f64> = (0..nr)
                .map(|k| a.iter().zip(beta).map(|(col, b)| col[k] * b).sum())
                .collect();
            let resid: Vec<f64> = ch
                .rows
                .iter()
                .zip(&fitted)
                .map(|(&k, f)| ch.y[k] - f)
                .collect();
            for (j, da) in d_a.iter().enumerate() {
                if da.is_empty() {
                    continue;
                }
                // ∂A β at the readings.
                let mut dab = vec![0.0; nr];
                for (col, b) in da.iter().zip(beta) {
                    for (x, y) in dab.iter_mut().zip(col) {
                        *x += y * b;
                    }
                }
                let mut rhs = DVector::<f64>::zeros(m);
                for (i, col) in da.iter().enumerate() {
                    rhs[i] += col.iter().zip(&resid).map(|(p, q)| p * q).sum::<f64>();
                }
                for i in 0..m {
                    rhs[i] -= a[i].iter().zip(&dab).map(|(p, q)| p * q).sum::<f64>();
                }
                let d_beta = match &chol {
                    Some(ch) => ch.solve(&rhs),
                    None => DVector::zeros(m),
                };
                for k in 0..nr {
                    let ad: f64 = (0..m).map(|i| a[i][k] * d_beta[i]).sum();
                    jac[(row0 + k, j)] = -(dab[k] + ad) / ch.sigma;
                }
            }
            row0 += nr;
        }
        // A forward difference for the rest.
        let mut zj = z.to_vec();
        let mut rj = Vec::with_capacity(r.len());
        for (j, p) in self.layout.iter().enumerate() {
            if !matches!(p, P::Limit | P::Freq | P::ModeFn | P::ModeZeta | P::VoltExp) {
                continue;
            }
            let mut h = diff_step * z[j].abs().max(1.0);
            if z[j] + h > bounds[j].1 {
                h = -h;
            }
            zj[j] = z[j] + h;
            let ok = self.residuals(&self.values(&zj), None, &mut rj);
            zj[j] = z[j];
            if !ok || rj.len() != r.len() {
                return None;
            }
            for i in 0..r.len() {
                jac[(i, j)] = (rj[i] - r[i]) / h;
            }
        }
        jac.iter().all(|x| x.is_finite()).then_some(jac)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{fit_rows, Channel, FitInput, Structure};
    use crate::levenberg_marquardt::jacobian as forward_difference;
    use crate::segment::SegmentRules;
    use crate::stand_model::{
        simulate, CurrentLaw, Quantity, RotorLaw, Sensor, SpeedMap, StandParams, Supply,
    };

    #[test]
    fn the_sensitivities_give_the_difference_quotients_jacobian() {
        let dt = 0.005;
        let u: Vec<f64> = (0..1200)
            .map(|k| [0.2, 0.6, 0.4, 0.9, 0.3][(k / 240) % 5])
            .collect();
        let voltage: Vec<f64> = (0..u.len())
            .map(|k| 16.0 + 0.2 * (k as f64 * 0.01).sin())
            .collect();
        let p = StandParams {
            dead_time_s: 0.012,
            map: SpeedMap {
                speed_ref: 20_000.0,
                command_zero: 0.05,
                command_ref: 0.9,
                exponent: 1.1,
                voltage_ref: 16.0,
            },
            rotor: RotorLaw {
                tau_up_s: 0.03,
                tau_down_s: 0.05,
                tau_speed_exponent: 0.4,
                speed_ref: 20_000.0,
            },
            thrust_exponent: 2.0,
            k_t: 15.0 / 4e8,
            k_q: 0.2 / 4e8,
            current: CurrentLaw {
                idle_a: 0.4,
                per_power: 20.0 / 8e12,
                per_acceleration: 1e-8,
            },
            supply: Supply {
                open_circuit_v: 16.0,
                resistance_ohm: 0.0,
            },
        };
        let load_cell = Sensor {
            delay_s: 0.02,
            tau_s: 0.03,
            refresh_s: 0.0,
            offset: 0.1,
            creep_per_s: 0.001,
        };
        let sensors = [
            (Quantity::Speed, Sensor::default()),
            (Quantity::Thrust, load_cell),
            (
                Quantity::Current,
                Sensor {
                    delay_s: 0.007,
                    tau_s: 0.01,
                    ..Sensor::default()
                },
            ),
        ];
        let ys = simulate(&p, dt, &u, Some(&voltage), &sensors);
        let keys = ["rpm", "thrust", "current"];
        let channels: Vec<Channel<'_>> = ys
            .iter()
            .zip(&sensors)
            .zip(keys)
            .map(|((y, (q, _)), key)| Channel {
                key,
                quantity: *q,
                y,
                interpolated: &[],
            })
            .collect();
        let input = FitInput {
            dt_s: dt,
            command: &u,
            voltage: Some(&voltage),
            channels: &channels,
            rules: SegmentRules::for_record(dt, true),
        };
        let with_fd_parts = Structure {
            mode: Some((12.0, 0.2)),
            command_limit: true,
            ..Structure::full()
        };
        for st in [Structure::full(), with_fd_parts] {
            let (_, problem, z) = fit_rows(&input, &st, None, None).unwrap();
            // Away from the optimum and the bounds.
            let z: Vec<f64> = z
                .iter()
                .zip(&problem.bounds)
                .map(|(&x, &(lo, hi))| {
                    let x = x + 0.03 * (hi - lo);
                    // (not a whole number of rows of dead time: θ's derivative is one-sided)
                    if x < lo + 0.1 * (hi - lo) || x > hi - 0.1 * (hi - lo) {
                        lo + 0.1237 * (hi - lo)
                    } else {
                        x
                    }
                })
                .collect();
            let mut r = Vec::new();
            assert!(problem.residuals(&problem.values(&z), None, &mut r));
            let mut f =
                |zz: &[f64], out: &mut Vec<f64>| problem.residuals(&problem.values(zz), None, out);
            let fd = forward_difference(&mut f, &z, &r, &problem.bounds, 1e-7).unwrap();
            let got = problem.jacobian(&z, &r, &problem.bounds, 1e-7).unwrap();
            for j in 0..z.len() {
                let err = (got.column(j) - fd.column(j)).norm();
                let size = fd.column(j).norm().max(1e-9);
                assert!(
                    err <= 2e-3 * size,
                    "{:?}: {err} against {size}",
                    problem.layout[j]
                );
            }
        }
    }
}
