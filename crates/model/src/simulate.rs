//! Free-run simulation of a saved model on an input, and its score against measured outputs
//! (`propid compare`, `propid simulate`).
//!
//! **Simulation.** The output is computed from the input alone (no measured output fed back):
//!
//! ```text
//!   linear:    x_{k+1} = A x_k + B (u_k − u₀),   ŷ_k = y₀ + C x_k + D (u_k − u₀)
//!   extended:  propid_diagnose::model::simulate (core, terms, u_r, V_r)
//! ```
//!
//! Both start in steady state for the first input sample (linear:
//! `x_ss = (I − A)⁻¹ B (u_0 − u₀)`, zero when `I − A` is singular).
//!
//! **Initial state from the first N outputs.** With `N > 0` a correction `δ` of the state is
//! estimated by least squares on the observability map over the first `N` samples with a
//! finite output only: `min_δ Σ_{k<N} ‖y_k − ŷ_k − C Aᵏ δ‖²` (the free response of the state
//! added to the steady-state start; solved through the SVD, minimum norm where `N` samples do
//! not determine every state). For an extended model `A`, `C` are its 2nd-order core's
//! (`[T, T']`, output `T`): exact for a linear core with no series term, to first order
//! otherwise.
//!
//! **Score.** Per output over the samples `k ≥ N` with a finite output (the first `N` chose the
//! state and are not scored): `RMS = √(mean (y − ŷ)²)` in the output's unit and
//! `fit = 100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)`, percent (the figure `diagnose` reports).

use nalgebra::{DMatrix, DVector};
use propid_diagnose::signals::Signals;
use propid_numerics::discretise::discretise_second_order;
use serde::Serialize;

use crate::file::{Linear, ModelFile};
use crate::schema::ModelError;
use crate::terms::Extended;

/// Which of a file's models to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Which {
    /// The linear model.
    Linear,
    /// The extended (`diagnose`) model.
    Extended,
}

impl Which {
    /// The extended model when the file has one, else the linear.
    pub fn default_for(m: &ModelFile) -> Which {
        if m.extended.is_some() {
            Which::Extended
        } else {
            Which::Linear
        }
    }
}

/// The score of one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputScore {
    /// The output's name.
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// RMS of `y − ŷ`, in `unit`.
    pub rms: f64,
    /// `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)`, percent.
    pub fit_percent: f64,
    /// Samples scored.
    pub samples: usize,
}

/// Steady-state state of `x⁺ = A x + B v` for a constant `v` (zero when `I − A` is singular).
fn steady_state(a: &DMatrix<f64>, b: &DVector<f64>, v: f64) -> DVector<f64> {
    let n = a.nrows();
    let m = DMatrix::identity(n, n) - a;
    m.lu()
        .solve(&(b * v))
        .filter(|x| x.iter().all(|v| v.is_finite()))
        .unwrap_or_else(|| DVector::zeros(n))
}

fn matrix(rows: &[Vec<f64>]) -> DMatrix<f64> {
    let (r, c) = (rows.len(), rows.first().map_or(0, Vec::len));
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

/// The linear model simulated on `u` from state `x0` (steady state when `None`): one vector
/// per output.
pub fn simulate_linear(l: &Linear, u: &[f64], x0: Option<&DVector<f64>>) -> Vec<Vec<f64>> {
    let (a, c) = (matrix(&l.a), matrix(&l.c));
    let b = DVector::from_iterator(l.b.len(), l.b.iter().map(|r| r[0]));
    let d: Vec<f64> = l.d.iter().map(|r| r[0]).collect();
    let u0 = l.operating_point.input;
    let mut x = match x0 {
        Some(x) => x.clone(),
        None => steady_state(&a, &b, u.first().map_or(0.0, |v| v - u0)),
    };
    let q = c.nrows();
    let mut out = vec![Vec::with_capacity(u.len()); q];
    for &uk in u {
        let v = uk - u0;
        let y = &c * &x;
        for i in 0..q {
            out[i].push(l.operating_point.outputs[i] + y[i] + d[i] * v);
        }
        x = &a * &x + &b * v;
    }
    out
}

/// The extended model simulated on `u` (and the supply voltage, when it has a supply term).
pub fn simulate_extended(
    e: &Extended,
    dt_s: f64,
    u: &[f64],
    voltage: Option<&[f64]>,
) -> Result<Vec<f64>, ModelError> {
    let m = crate::terms::model(e)?;
    let sig = Signals {
        dt_s,
        u,
        y: &[],
        voltage,
        u_ref: e.u_ref,
        v_ref: e.v_ref,
    };
    let mut out = vec![0.0; u.len()];
    propid_diagnose::model::simulate(&m, &sig, &mut out);
    Ok(out)
}

/// The `(A, C)` whose free response `C Aᵏ δ` the initial state corrects.
fn free_response_pair(m: &ModelFile, which: Which) -> (DMatrix<f64>, DMatrix<f64>) {
    match (which, &m.extended, &m.linear) {
        (Which::Extended, Some(e), _) => {
            let (a, _) = discretise_second_order(e.core.fn_hz, e.core.zeta, 1.0, m.dt_s);
            (
                DMatrix::from_fn(2, 2, |i, j| a[(i, j)]),
                DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
            )
        }
        (_, _, Some(l)) => (matrix(&l.a), matrix(&l.c)),
        _ => (DMatrix::zeros(0, 0), DMatrix::zeros(0, 0)),
    }
}

/// The model `which` of `m` simulated on input `u` (and `voltage`), its initial state
/// corrected from the first `init_samples` of the measured outputs `y` (one vector per output,
/// NaN where missing; module doc). One vector per output.
#[allow(clippy::needless_range_loop)] // samples and outputs indexed together
pub fn free_run(
    m: &ModelFile,
    which: Which,
    u: &[f64],
    voltage: Option<&[f64]>,
    y: &[Vec<f64>],
    init_samples: usize,
) -> Result<Vec<Vec<f64>>, ModelError> {
    let mut sim = match which {
        Which::Extended => {
            let e = m
                .extended
                .as_ref()
                .ok_or_else(|| ModelError::Invalid("the file holds no extended model".into()))?;
            vec![simulate_extended(e, m.dt_s, u, voltage)?]
        }
        Which::Linear => {
            let l = m
                .linear
                .as_ref()
                .ok_or_else(|| ModelError::Invalid("the file holds no linear model".into()))?;
            simulate_linear(l, u, None)
        }
    };
    let n_init = init_samples.min(u.len());
    if n_init == 0 {
        return Ok(sim);
    }
    let (a, c) = free_response_pair(m, which);
    let (n, q) = (a.nrows(), c.nrows().min(sim.len()).min(y.len()));
    // Rows of the observability map `C Aᵏ` at the finite outputs, and the residuals there.
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut rhs = Vec::new();
    let mut ak = DMatrix::<f64>::identity(n, n);
    for k in 0..n_init {
        let cak = &c * &ak;
        for i in 0..q {
            let yk = y[i].get(k).copied().unwrap_or(f64::NAN);
            if yk.is_finite() && sim[i][k].is_finite() {
                rows.push(cak.row(i).iter().copied().collect());
                rhs.push(yk - sim[i][k]);
            }
        }
        ak = &a * ak;
    }
    if rows.is_empty() || n == 0 {
        return Ok(sim);
    }
    let o = DMatrix::from_fn(rows.len(), n, |r, j| rows[r][j]);
    let r = DVector::from_vec(rhs);
    let svd = o.svd(true, true);
    let tol = svd.singular_values.max() * 1e-10;
    let delta = match svd.solve(&r, tol) {
        Ok(d) if d.iter().all(|v| v.is_finite()) => d,
        _ => return Ok(sim),
    };
    let mut x = delta;
    for k in 0..u.len() {
        let corr = &c * &x;
        for i in 0..q {
            sim[i][k] += corr[i];
        }
        x = &a * x;
    }
    Ok(sim)
}

/// RMS and fit of `yhat` against `y` over the samples from `from` with a finite `y`.
pub fn score(y: &[f64], yhat: &[f64], from: usize) -> (f64, f64, usize) {
    let ok: Vec<usize> = (from..y.len().min(yhat.len()))
        .filter(|&k| y[k].is_finite() && yhat[k].is_finite())
        .collect();
    let m = ok.len();
    if m == 0 {
        return (f64::NAN, f64::NAN, 0);
    }
    let mean = ok.iter().map(|&k| y[k]).sum::<f64>() / m as f64;
    let e2: f64 = ok.iter().map(|&k| (y[k] - yhat[k]).powi(2)).sum();
    let d2: f64 = ok.iter().map(|&k| (y[k] - mean).powi(2)).sum();
    let rms = (e2 / m as f64).sqrt();
    (rms, 100.0 * (1.0 - (e2 / d2.max(1e-300)).sqrt()), m)
}

/// Scores of every output of a free run (`sim` from [`free_run`]).
pub fn scores(m: &ModelFile, y: &[Vec<f64>], sim: &[Vec<f64>], from: usize) -> Vec<OutputScore> {
    m.outputs
        .iter()
        .zip(y.iter().zip(sim))
        .map(|(ch, (y, s))| {
            let (rms, fit_percent, samples) = score(y, s, from);
            OutputScore {
                name: ch.name.clone(),
                unit: ch.unit.clone(),
                rms,
                fit_percent,
                samples,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::file::tests::sample;

    fn input(n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| if (k / 37) % 2 == 0 { 0.4 } else { 0.65 } + 0.01 * ((k * 7) % 5) as f64)
            .collect()
    }

    #[test]
    fn the_linear_model_starts_in_steady_state_at_its_operating_point() {
        let m = sample();
        let l = m.linear.as_ref().unwrap();
        let out = simulate_linear(l, &[0.5; 20], None);
        assert!(out[0].iter().all(|v| (v - 3.0).abs() < 1e-12), "{out:?}");
    }

    #[test]
    fn the_initial_state_is_found_from_the_first_outputs() {
        let m = sample();
        let l = m.linear.as_ref().unwrap();
        let u = input(300);
        // The "measured" output starts from another state than the steady one.
        let x0 = DVector::from_vec(vec![0.7, -0.4]);
        let y = simulate_linear(l, &u, Some(&x0));
        let plain = free_run(&m, Which::Linear, &u, None, &y, 0).unwrap();
        let (rms0, _, _) = score(&y[0], &plain[0], 10);
        assert!(rms0 > 1e-3, "{rms0}");
        let fixed = free_run(&m, Which::Linear, &u, None, &y, 10).unwrap();
        let (rms, fit, n) = score(&y[0], &fixed[0], 10);
        assert!(rms < 1e-9, "{rms}");
        assert!(fit > 99.9999, "{fit}");
        assert_eq!(n, 290);
    }

    #[test]
    fn fit_and_rms_are_hand_checked() {
        // y = 0, 2; ŷ = 1, 1: RMS 1, ‖y − ŷ‖ = √2 = ‖y − ȳ‖: fit 0.
        let (rms, fit, n) = score(&[0.0, 2.0, f64::NAN], &[1.0, 1.0, 5.0], 0);
        assert_eq!((rms, n), (1.0, 2));
        assert!(fit.abs() < 1e-12, "{fit}");
    }

    #[test]
    fn the_extended_model_simulates_as_diagnose_does() {
        use crate::terms::CoreSpec;
        use crate::terms::TermSpec;
        let e = Extended {
            core: CoreSpec {
                fn_hz: 4.0,
                zeta: 0.7,
                gain: 10.0,
                offset: 0.5,
                lead: 0.0,
            },
            terms: vec![TermSpec::DeadTime {
                delay_samples: 3,
                sensor_samples: 0,
            }],
            u_ref: 0.5,
            v_ref: 0.0,
        };
        let u = input(200);
        let out = simulate_extended(&e, 0.01, &u, None).unwrap();
        let m = crate::terms::model(&e).unwrap();
        let sig = Signals {
            dt_s: 0.01,
            u: &u,
            y: &[],
            voltage: None,
            u_ref: 0.5,
            v_ref: 0.0,
        };
        let mut want = vec![0.0; u.len()];
        propid_diagnose::model::simulate(&m, &sig, &mut want);
        assert_eq!(out, want);
        // Steady at the start: offset + K u.
        assert!((out[0] - (0.5 + 10.0 * u[0])).abs() < 1e-9, "{}", out[0]);
    }
}
