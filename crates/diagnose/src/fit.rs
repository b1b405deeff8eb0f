//! Fitting the output-error model of [`super::model`] to measured data.
//!
//! - [`linear_refit`]: the parameters that enter linearly (gain `K`, offset `c`, and each
//!   term's linear coefficients, e.g. a drift rate or sine/cosine amplitudes) by least squares,
//!   with the others held — used to score grid points of the nonlinear parameters cheaply.
//! - [`levenberg_marquardt`]: all free parameters by Levenberg–Marquardt (Marquardt 1963) on the
//!   simulation error `r = y − ŷ(θ)` over the estimation samples, with a forward-difference
//!   Jacobian and Marquardt's diagonal scaling, `(JᵀJ + λ diag JᵀJ) δ = Jᵀ r`. Frequencies and
//!   damping ratios are adjusted in logarithm so that they stay positive.
//! - [`Ctx::lm`], [`Ctx::best_of`], [`Ctx::residual`]: those steps on the data of one diagnosis.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};

use super::ctx::Ctx;
use super::model::{simulate, simulate_places, Model};
use super::signals::{Core, Signals};
use super::term::Scale;

/// A fitted model and its residual sum of squares on the estimation samples.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The fitted model.
    pub model: Model,
    /// Sum of squared simulation errors over the estimation samples.
    pub sse: f64,
    /// Number of estimation samples counted in `sse`.
    pub n: usize,
}

/// Sum of squared simulation errors of `p` over `range` (missing outputs skipped).
pub fn sse(m: &Model, sig: &Signals, range: Range<usize>, buf: &mut Vec<f64>) -> (f64, usize) {
    buf.resize(sig.u.len(), 0.0);
    simulate(m, sig, buf);
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

/// Least squares for the linearly entering parameters with the others held (see module doc):
/// the output without limits is `ŷ = K s₁ + c + Σ θ_j φ_j(t)` with `s₁` the simulation at
/// `K = 1`, `c = 0`, `θ = 0`. Returns the updated model and its SSE (limits included).
pub fn linear_refit(m: &Model, sig: &Signals, range: Range<usize>) -> (Model, f64) {
    let mut unit = m.clone();
    unit.core.gain = 1.0;
    unit.core.offset = 0.0;
    for t in unit.terms_mut() {
        let zeros = vec![0.0; t.linear_count()];
        t.set_linear(&zeros);
    }
    let mut s1 = vec![0.0; sig.u.len()];
    simulate_places(&unit, sig, &mut s1, false);
    let cols = 2 + m.terms().map(|t| t.linear_count()).sum::<usize>();
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
        for term in m.terms() {
            let l = term.linear_count();
            term.linear_row(t, &mut row[c..c + l]);
            c += l;
        }
        for i in 0..cols {
            aty[i] += row[i] * yk;
            for j in 0..cols {
                ata[(i, j)] += row[i] * row[j];
            }
        }
    }
    let mut out = m.clone();
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
            out.core.gain = sol[0];
            out.core.offset = sol[1];
            let mut c = 2;
            for term in out.terms_mut() {
                let l = term.linear_count();
                term.set_linear(&sol.as_slice()[c..c + l]);
                c += l;
            }
        }
    }
    let mut buf = Vec::new();
    let (s, _) = sse(&out, sig, range, &mut buf);
    (out, s)
}

/// The free parameters in the coordinates the fit moves (logarithm where [`Scale::Log`]).
fn to_z(free: &[(f64, Scale)]) -> Vec<f64> {
    free.iter()
        .map(|&(v, scale)| match scale {
            Scale::Log => v.max(1e-9).ln(),
            Scale::Linear => v,
        })
        .collect()
}

/// `base` with its free parameters set from the fit's coordinates `z`.
fn from_z(base: &Model, scales: &[Scale], z: &[f64]) -> Model {
    let values: Vec<f64> = scales
        .iter()
        .zip(z)
        .map(|(scale, &zi)| match scale {
            Scale::Log => zi.exp(),
            Scale::Linear => zi,
        })
        .collect();
    let mut m = base.clone();
    m.set_free(&values);
    m
}

/// Residuals `y − ŷ` over the finite estimation samples.
fn residuals(m: &Model, sig: &Signals, range: &Range<usize>, buf: &mut Vec<f64>, r: &mut Vec<f64>) {
    buf.resize(sig.u.len(), 0.0);
    simulate(m, sig, buf);
    r.clear();
    for k in range.clone() {
        if sig.y[k].is_finite() {
            r.push(sig.y[k] - buf[k]);
        }
    }
}

/// Levenberg–Marquardt on the free parameters of `p0` (see module doc); at most `max_iter`
/// accepted or rejected steps. Never returns a worse fit than `p0`.
pub fn levenberg_marquardt(p0: &Model, sig: &Signals, range: Range<usize>, max_iter: usize) -> Fit {
    let free = p0.free();
    let scales: Vec<Scale> = free.iter().map(|f| f.1).collect();
    let m = free.len();
    let mut buf = Vec::new();
    let mut r = Vec::new();
    let mut z = to_z(&free);
    let mut p = p0.clone();
    residuals(&p, sig, &range, &mut buf, &mut r);
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
            let floor = match scales[j] {
                Scale::Log => 1.0,
                Scale::Linear => 1e-3,
            };
            let h = 1e-6 * z[j].abs().max(floor);
            let mut zj = z.clone();
            zj[j] += h;
            residuals(&from_z(p0, &scales, &zj), sig, &range, &mut buf, &mut rj);
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
            let pt = from_z(p0, &scales, &zt);
            residuals(&pt, sig, &range, &mut buf, &mut rj);
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
        model: p,
        sse: cost,
        n,
    }
}

/// The fitting steps every effect uses on the data of one diagnosis.
impl Ctx<'_> {
    /// Levenberg–Marquardt on the estimation samples from `start`, at most `iters` steps.
    pub fn lm(&self, start: &Model, iters: usize) -> Fit {
        levenberg_marquardt(start, &self.sig, self.est.clone(), iters)
    }

    /// Every start scored after a linear refit (gain, offset, linear terms), then
    /// Levenberg–Marquardt (40 steps) from the `keep` best; the best result wins. With no
    /// usable start: the first start with the default core and an infinite SSE.
    pub fn best_of(&self, starts: impl IntoIterator<Item = Model>, keep: usize) -> Fit {
        let starts: Vec<Model> = starts.into_iter().collect();
        let fallback = starts
            .first()
            .map_or_else(Model::default, |m| m.with_core(Core::default()));
        let mut scored: Vec<(f64, Model)> = starts
            .into_iter()
            .map(|p| {
                let (q, s) = linear_refit(&p, &self.sig, self.est.clone());
                (s, q)
            })
            .filter(|(s, _)| s.is_finite())
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best: Option<Fit> = None;
        for (_, p) in scored.into_iter().take(keep.max(1)) {
            let f = self.lm(&p, 40);
            if best.as_ref().map_or(true, |b| f.sse < b.sse) {
                best = Some(f);
            }
        }
        best.unwrap_or(Fit {
            model: fallback,
            sse: f64::INFINITY,
            n: 0,
        })
    }

    /// The simulation residual of a fit on the estimation samples.
    pub fn residual(&self, f: &Fit) -> Vec<f64> {
        let mut buf = vec![0.0; self.sig.u.len()];
        simulate(&f.model, &self.sig, &mut buf);
        self.est.clone().map(|k| self.sig.y[k] - buf[k]).collect()
    }
}
