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

/// The samples a fit on `range` simulates: the simulation is causal (each sample of the output
/// depends on the input up to it, [`simulate`]), so those up to the range's end.
fn sim_len(sig: &Signals, range: &Range<usize>) -> usize {
    range.end.min(sig.u.len())
}

/// Sum of squared simulation errors of `p` over `range` (missing outputs skipped).
pub fn sse(m: &Model, sig: &Signals, range: Range<usize>, buf: &mut Vec<f64>) -> (f64, usize) {
    buf.resize(sim_len(sig, &range), 0.0);
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
    let mut s1 = vec![0.0; sim_len(sig, &range)];
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
    buf.resize(sim_len(sig, range), 0.0);
    simulate(m, sig, buf);
    residuals_of(sig, buf, range, r);
}

/// `JᵀJ` and `Jᵀr` of the Jacobian's columns `cols` and `r`: each entry summed over the
/// samples in their order (the sums of column dot products, bit for bit), four entries in one
/// pass so that their sums run side by side.
fn normal_equations(cols: &[Vec<f64>], r: &[f64]) -> (DMatrix<f64>, DVector<f64>) {
    let m = cols.len();
    let mut pairs: Vec<(usize, usize)> = Vec::with_capacity(m * (m + 3) / 2);
    for a in 0..m {
        pairs.push((a, m));
        pairs.extend((a..m).map(|b| (a, b)));
    }
    let col = |j: usize| if j == m { r } else { &cols[j][..] };
    let n = r.len();
    let mut sums = Vec::with_capacity(pairs.len());
    let mut quads = pairs.chunks_exact(4);
    for q in &mut quads {
        let (a0, b0) = (&col(q[0].0)[..n], &col(q[0].1)[..n]);
        let (a1, b1) = (&col(q[1].0)[..n], &col(q[1].1)[..n]);
        let (a2, b2) = (&col(q[2].0)[..n], &col(q[2].1)[..n]);
        let (a3, b3) = (&col(q[3].0)[..n], &col(q[3].1)[..n]);
        let mut s = [-0.0f64; 4];
        for k in 0..n {
            s[0] += a0[k] * b0[k];
            s[1] += a1[k] * b1[k];
            s[2] += a2[k] * b2[k];
            s[3] += a3[k] * b3[k];
        }
        sums.extend(s);
    }
    for &(a, b) in quads.remainder() {
        sums.push(col(a).iter().zip(col(b)).map(|(x, y)| x * y).sum());
    }
    let mut jtj = DMatrix::<f64>::zeros(m, m);
    let mut jtr = DVector::<f64>::zeros(m);
    for (&(a, b), v) in pairs.iter().zip(sums) {
        if b == m {
            jtr[a] = v;
        } else {
            jtj[(a, b)] = v;
            jtj[(b, a)] = v;
        }
    }
    (jtj, jtr)
}

/// The simulations of `p0` and of each forward-difference step of its free parameters on the
/// whole record: the first Jacobian of every [`levenberg_marquardt_from`] that starts at `p0`
/// on the same input whatever outputs it masks (the folds' refits), computed once.
#[derive(Debug, Clone)]
pub struct FirstJacobian {
    /// `ŷ(θ₀)`.
    base: Vec<f64>,
    /// `ŷ(θ₀ + h_j e_j)` for each free parameter `j`.
    stepped: Vec<Vec<f64>>,
}

impl FirstJacobian {
    /// The simulations of `p0` on `sig`'s input (see the type's doc).
    pub fn of(p0: &Model, sig: &Signals) -> FirstJacobian {
        let free = p0.free();
        let scales: Vec<Scale> = free.iter().map(|f| f.1).collect();
        let z = to_z(&free);
        let n = sig.u.len();
        let mut base = vec![0.0; n];
        simulate(p0, sig, &mut base);
        let params: Vec<usize> = (0..z.len()).collect();
        // Each step's simulation is independent of the others': on every core.
        let stepped = crate::par::map(&params, |&j| {
            let mut zj = z.clone();
            zj[j] += step(&z, &scales, j);
            let mut s = vec![0.0; n];
            simulate(&from_z(p0, &scales, &zj), sig, &mut s);
            s
        });
        FirstJacobian { base, stepped }
    }
}

/// The forward-difference step of parameter `j` at `z`.
fn step(z: &[f64], scales: &[Scale], j: usize) -> f64 {
    let floor = match scales[j] {
        Scale::Log => 1.0,
        Scale::Linear => 1e-3,
    };
    1e-6 * z[j].abs().max(floor)
}

/// `y − sim` over the finite outputs of `range`, into `r`.
fn residuals_of(sig: &Signals, sim: &[f64], range: &Range<usize>, r: &mut Vec<f64>) {
    r.clear();
    for k in range.clone() {
        if sig.y[k].is_finite() {
            r.push(sig.y[k] - sim[k]);
        }
    }
}

/// Levenberg–Marquardt on the free parameters of `p0` (see module doc); at most `max_iter`
/// accepted or rejected steps. Never returns a worse fit than `p0`.
pub fn levenberg_marquardt(p0: &Model, sig: &Signals, range: Range<usize>, max_iter: usize) -> Fit {
    levenberg_marquardt_from(p0, sig, range, max_iter, None)
}

/// [`levenberg_marquardt`] with the simulations at `p0` given (`first`, made by
/// [`FirstJacobian::of`] for `p0` on `sig`'s input): the same fit, without simulating them.
pub fn levenberg_marquardt_from(
    p0: &Model,
    sig: &Signals,
    range: Range<usize>,
    max_iter: usize,
    first: Option<&FirstJacobian>,
) -> Fit {
    let free = p0.free();
    let scales: Vec<Scale> = free.iter().map(|f| f.1).collect();
    let m = free.len();
    let mut buf = Vec::new();
    let mut r = Vec::new();
    let mut z = to_z(&free);
    let mut p = p0.clone();
    match first {
        Some(s) => residuals_of(sig, &s.base, &range, &mut r),
        None => residuals(&p, sig, &range, &mut buf, &mut r),
    }
    let n = r.len();
    let mut cost: f64 = r.iter().map(|e| e * e).sum();
    if !cost.is_finite() {
        cost = f64::INFINITY;
    }
    let mut lambda = 1e-3;
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); m];
    let mut rj = Vec::new();
    let mut zj = z.clone();
    for iter in 0..max_iter {
        if !cost.is_finite() || n == 0 || m == 0 {
            break;
        }
        // Forward-difference Jacobian of the residuals.
        for j in 0..m {
            let h = step(&z, &scales, j);
            match first.filter(|_| iter == 0) {
                Some(s) => residuals_of(sig, &s.stepped[j], &range, &mut rj),
                None => {
                    zj.copy_from_slice(&z);
                    zj[j] += h;
                    residuals(&from_z(p0, &scales, &zj), sig, &range, &mut buf, &mut rj);
                }
            }
            cols[j].clear();
            cols[j].extend(rj.iter().zip(&r).map(|(a, b)| (b - a) / h));
        }
        let (jtj, jtr) = normal_equations(&cols, &r);
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
        scored.truncate(keep.max(1));
        // The starts' fits are independent of one another: on every core.
        let fits = crate::par::map(&scored, |(_, p)| self.lm(p, 40));
        let mut best: Option<Fit> = None;
        for f in fits {
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
