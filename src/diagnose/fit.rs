//! Fitting the output-error model of [`super::model`] to measured data.
//!
//! - [`linear_refit`]: the parameters that enter linearly (gain `K`, offset `c`, drift `r`, the
//!   sine/cosine coefficients `a, b`) by least squares, with the others held — used to score
//!   grid points of the nonlinear parameters cheaply.
//! - [`levenberg_marquardt`]: all free parameters by Levenberg–Marquardt (Marquardt 1963) on the
//!   simulation error `r = y − ŷ(θ)` over the estimation samples, with a forward-difference
//!   Jacobian and Marquardt's diagonal scaling, `(JᵀJ + λ diag JᵀJ) δ = Jᵀ r`. Frequencies and
//!   damping ratios are adjusted in logarithm so that they stay positive.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};

use super::model::{ix, simulate, Params, Signals, Spec};

/// A fitted model and its residual sum of squares on the estimation samples.
#[derive(Debug, Clone, Copy)]
pub struct Fit {
    /// Which parts are switched on.
    pub spec: Spec,
    /// Fitted values.
    pub params: Params,
    /// Sum of squared simulation errors over the estimation samples.
    pub sse: f64,
    /// Number of estimation samples counted in `sse`.
    pub n: usize,
}

/// Sum of squared simulation errors of `p` over `range` (missing outputs skipped).
pub fn sse(
    spec: &Spec,
    p: &Params,
    sig: &Signals,
    range: Range<usize>,
    buf: &mut Vec<f64>,
) -> (f64, usize) {
    buf.resize(sig.u.len(), 0.0);
    simulate(spec, p, sig, buf);
    let mut s = 0.0;
    let mut n = 0;
    for k in range {
        let e = sig.y[k] - buf[k];
        if e.is_finite() {
            s += e * e;
            n += 1;
        }
    }
    if s.is_finite() {
        (s, n)
    } else {
        (f64::INFINITY, n)
    }
}

/// Least squares for the linearly entering parameters with the others held (see module doc).
/// Returns the updated parameters and their SSE.
pub fn linear_refit(spec: &Spec, p: &Params, sig: &Signals, range: Range<usize>) -> (Params, f64) {
    let mut unit = *p;
    unit.v[ix::GAIN] = 1.0;
    unit.v[ix::OFFSET] = 0.0;
    unit.v[ix::DRIFT] = 0.0;
    unit.v[ix::SIN_A] = 0.0;
    unit.v[ix::SIN_B] = 0.0;
    let lin_spec = Spec {
        clip_sensor: None,
        ..*spec
    };
    let mut s1 = vec![0.0; sig.u.len()];
    simulate(&lin_spec, &unit, sig, &mut s1);
    let w = 2.0 * std::f64::consts::PI * p.v[ix::SIN_FREQ];
    let mut cols = 2;
    if spec.drift {
        cols += 1;
    }
    if spec.periodic {
        cols += 2;
    }
    let mut ata = DMatrix::<f64>::zeros(cols, cols);
    let mut aty = DVector::<f64>::zeros(cols);
    let mut row = vec![0.0; cols];
    for k in range.clone() {
        let yk = sig.y[k];
        if !yk.is_finite() {
            continue;
        }
        let t = k as f64 * sig.dt_s;
        row[0] = s1[k];
        row[1] = 1.0;
        let mut c = 2;
        if spec.drift {
            row[c] = t;
            c += 1;
        }
        if spec.periodic {
            row[c] = (w * t).sin();
            row[c + 1] = (w * t).cos();
        }
        for i in 0..cols {
            aty[i] += row[i] * yk;
            for j in 0..cols {
                ata[(i, j)] += row[i] * row[j];
            }
        }
    }
    let mut out = *p;
    let reg = 1e-12
        * (0..cols)
            .map(|i| ata[(i, i)])
            .fold(0.0, f64::max)
            .max(1e-300);
    for i in 0..cols {
        ata[(i, i)] += reg;
    }
    if let Some(sol) = ata.cholesky().map(|c| c.solve(&aty)) {
        if sol.iter().all(|v| v.is_finite()) {
            out.v[ix::GAIN] = sol[0];
            out.v[ix::OFFSET] = sol[1];
            let mut c = 2;
            if spec.drift {
                out.v[ix::DRIFT] = sol[c];
                c += 1;
            }
            if spec.periodic {
                out.v[ix::SIN_A] = sol[c];
                out.v[ix::SIN_B] = sol[c + 1];
            }
        }
    }
    let mut buf = Vec::new();
    let (s, _) = sse(spec, &out, sig, range, &mut buf);
    (out, s)
}

/// True for parameters adjusted in logarithm.
fn is_log(i: usize) -> bool {
    matches!(
        i,
        ix::FN | ix::ZETA | ix::MODE_FN | ix::MODE_ZETA | ix::SIN_FREQ
    )
}

fn to_z(p: &Params, free: &[usize]) -> Vec<f64> {
    free.iter()
        .map(|&i| {
            if is_log(i) {
                p.v[i].max(1e-9).ln()
            } else {
                p.v[i]
            }
        })
        .collect()
}

fn from_z(base: &Params, free: &[usize], z: &[f64]) -> Params {
    let mut p = *base;
    for (&i, &zi) in free.iter().zip(z) {
        p.v[i] = if is_log(i) { zi.exp() } else { zi };
    }
    p
}

/// Residuals `y − ŷ` over the finite estimation samples.
fn residuals(
    spec: &Spec,
    p: &Params,
    sig: &Signals,
    range: &Range<usize>,
    buf: &mut Vec<f64>,
    r: &mut Vec<f64>,
) {
    buf.resize(sig.u.len(), 0.0);
    simulate(spec, p, sig, buf);
    r.clear();
    for k in range.clone() {
        if sig.y[k].is_finite() {
            r.push(sig.y[k] - buf[k]);
        }
    }
}

/// Levenberg–Marquardt on the free parameters of `spec` from `p0` (see module doc); at most
/// `max_iter` accepted or rejected steps. Never returns a worse fit than `p0`.
pub fn levenberg_marquardt(
    spec: &Spec,
    p0: &Params,
    sig: &Signals,
    range: Range<usize>,
    max_iter: usize,
) -> Fit {
    let free = spec.free();
    let m = free.len();
    let mut buf = Vec::new();
    let mut r = Vec::new();
    let mut z = to_z(p0, &free);
    let mut p = *p0;
    residuals(spec, &p, sig, &range, &mut buf, &mut r);
    let n = r.len();
    let mut cost: f64 = r.iter().map(|e| e * e).sum();
    if !cost.is_finite() {
        cost = f64::INFINITY;
    }
    let mut lambda = 1e-3;
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); m];
    let mut rj = Vec::new();
    for _ in 0..max_iter {
        if !cost.is_finite() || n == 0 {
            break;
        }
        // Forward-difference Jacobian of the residuals.
        for j in 0..m {
            let h = 1e-6 * z[j].abs().max(if is_log(free[j]) { 1.0 } else { 1e-3 });
            let mut zj = z.clone();
            zj[j] += h;
            residuals(
                spec,
                &from_z(p0, &free, &zj),
                sig,
                &range,
                &mut buf,
                &mut rj,
            );
            cols[j].clear();
            cols[j].extend(rj.iter().zip(&r).map(|(a, b)| (b - a) / h));
        }
        let mut jtj = DMatrix::<f64>::zeros(m, m);
        let mut jtr = DVector::<f64>::zeros(m);
        for a in 0..m {
            jtr[a] = cols[a].iter().zip(&r).map(|(x, y)| x * y).sum();
            for b in a..m {
                let v: f64 = cols[a].iter().zip(&cols[b]).map(|(x, y)| x * y).sum();
                jtj[(a, b)] = v;
                jtj[(b, a)] = v;
            }
        }
        let mut improved = false;
        for _ in 0..8 {
            let mut lhs = jtj.clone();
            for a in 0..m {
                lhs[(a, a)] += lambda * jtj[(a, a)].max(1e-12);
            }
            let Some(delta) = lhs.lu().solve(&jtr) else {
                lambda *= 10.0;
                continue;
            };
            let zt: Vec<f64> = z.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
            let pt = from_z(p0, &free, &zt);
            residuals(spec, &pt, sig, &range, &mut buf, &mut rj);
            let ct: f64 = rj.iter().map(|e| e * e).sum();
            if ct.is_finite() && ct < cost {
                let rel = (cost - ct) / cost.max(1e-300);
                z = zt;
                p = pt;
                cost = ct;
                std::mem::swap(&mut r, &mut rj);
                lambda = (lambda * 0.3).max(1e-9);
                improved = rel > 1e-10;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Fit {
        spec: *spec,
        params: p,
        sse: cost,
        n,
    }
}
