//! The output-error criterion of a modal structure, its normal equations from the sensitivity
//! equations, the linear start at given poles and the Levenberg–Marquardt fit ([`super`]).

use nalgebra::{Complex, DMatrix, DVector};

use super::model::OeModel;
use super::MAX_RADIUS;
use crate::levenberg_marquardt::{minimise_normal, LmOptions, NormalEquations};

/// A record to fit: one input, `q` outputs (NaN where not measured), all of one length.
#[derive(Debug, Clone, Copy)]
pub struct Data<'a> {
    /// Input.
    pub u: &'a [f64],
    /// Outputs.
    pub y: &'a [&'a [f64]],
    /// Samples left out of every criterion (empty: none).
    pub missing: &'a [bool],
}

impl Data<'_> {
    /// Samples.
    pub fn len(&self) -> usize {
        self.u.len()
    }

    /// Whether the record is empty.
    pub fn is_empty(&self) -> bool {
        self.u.is_empty()
    }

    /// The mean input.
    pub fn u_mean(&self) -> f64 {
        self.u.iter().sum::<f64>() / self.u.len().max(1) as f64
    }

    /// Whether output `i` at `k` enters the criterion.
    pub fn counts(&self, i: usize, k: usize) -> bool {
        self.y[i][k].is_finite() && !self.missing.get(k).copied().unwrap_or(false)
    }
}

/// How long the fit goes on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Most Levenberg–Marquardt iterations.
    pub max_iter: usize,
    /// Stop when a step lowers the criterion by less than this share of it.
    pub rel_tol: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            max_iter: 40,
            rel_tol: 1e-7,
        }
    }
}

/// The shape of a modal model: integrator or not, how many real poles and pairs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Structure {
    /// The pole at `z = 1`.
    pub integrator: bool,
    /// Real poles (fitted).
    pub real: usize,
    /// Complex pairs (fitted).
    pub pairs: usize,
    /// Outputs.
    pub q: usize,
}

impl Structure {
    /// Model order.
    pub fn n(&self) -> usize {
        usize::from(self.integrator) + self.real + 2 * self.pairs
    }
    /// Pole parameters.
    pub fn np(&self) -> usize {
        self.real + 2 * self.pairs
    }
    /// Free-response coefficients per output (the integrator's is the offset's).
    fn nw(&self) -> usize {
        self.real + 2 * self.pairs
    }
    /// Parameters per output: `C` (n), `D`, offset, `w`, ramp (integrator only).
    fn per_output(&self) -> usize {
        self.n() + 2 + self.nw() + usize::from(self.integrator)
    }
    /// All parameters.
    pub fn len(&self) -> usize {
        self.np() + self.q * self.per_output()
    }
    /// Whether there are no parameters.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    fn block(&self, i: usize) -> usize {
        self.np() + i * self.per_output()
    }
    /// Whether the poles in `theta` are inside [`MAX_RADIUS`].
    fn admissible(&self, theta: &[f64]) -> bool {
        let r2 = MAX_RADIUS * MAX_RADIUS;
        theta[..self.real].iter().all(|p| p * p < r2)
            && (0..self.pairs).all(|j| {
                let (s, w) = (theta[self.real + 2 * j], theta[self.real + 2 * j + 1]);
                s * s + w * w < r2
            })
    }
}

/// A fitted model and what the fit saw.
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    /// The model.
    pub model: OeModel,
    /// Its structure.
    pub structure: Structure,
    /// All parameters (poles, then per output `C, D, y_off, w, r`).
    pub theta: Vec<f64>,
    /// `Σ r²` on the fitted samples.
    pub cost: f64,
    /// Levenberg–Marquardt iterations.
    pub iterations: usize,
}

/// What one sweep computes.
enum Want<'a> {
    /// `Σ r²` on `[0, n_fit)`.
    Cost,
    /// `JᵀJ`, `Jᵀr`, `Σ r²` on `[0, n_fit)`, Jacobian columns `cols` only (`None`: all).
    Normal(Option<&'a [usize]>),
    /// `ŷ` on every sample.
    Simulate,
}

struct Sweep {
    cost: f64,
    jtj: DMatrix<f64>,
    jtr: DVector<f64>,
    yhat: Vec<Vec<f64>>,
}

/// One pass over the record with the model `theta` of structure `st` (module doc of
/// [`super`]: modal states, free responses and their sensitivities, advanced together).
#[allow(clippy::too_many_lines)]
fn sweep(st: &Structure, theta: &[f64], data: &Data<'_>, n_fit: usize, want: Want<'_>) -> Sweep {
    let (n, nw, q) = (st.n(), st.nw(), st.q);
    let int = usize::from(st.integrator);
    let p_all = st.len();
    let n_eval = match want {
        Want::Simulate => data.len(),
        _ => n_fit.min(data.len()),
    };
    let normal = matches!(want, Want::Normal(_));
    let cols: Vec<usize> = match want {
        Want::Normal(Some(c)) => c.to_vec(),
        _ => (0..p_all).collect(),
    };
    // Position of each parameter in the reduced normal equations (usize::MAX: not wanted).
    let mut pos = vec![usize::MAX; p_all];
    for (j, &c) in cols.iter().enumerate() {
        pos[c] = j;
    }
    let m = cols.len();
    let mut jtj = DMatrix::<f64>::zeros(if normal { m } else { 0 }, if normal { m } else { 0 });
    let mut jtr = DVector::<f64>::zeros(if normal { m } else { 0 });
    let mut yhat = vec![Vec::new(); if matches!(want, Want::Simulate) { q } else { 0 }];
    let u_mean = data.u_mean();
    let big_n = data.len().max(1) as f64;
    // States (index s over n; the integrator first), free responses (index over nw: the
    // non-integrator states), sensitivities per pole parameter: for a real pole one (dx, dφ),
    // for a pair two 2-vectors each (∂/∂σ, ∂/∂ω).
    let mut x = vec![0.0; n];
    let mut phi = vec![0.0; nw];
    for j in 0..st.real {
        phi[j] = 1.0;
    }
    for j in 0..st.pairs {
        phi[st.real + 2 * j] = 1.0;
    }
    let mut dx = vec![0.0; 2 * nw]; // real: [dx_p]; pair: [dxσ(2), dxω(2)] per 2 states
    let mut dphi = vec![0.0; 2 * nw];
    let mut row = vec![0.0; p_all];
    let mut nz: Vec<usize> = Vec::with_capacity(p_all);
    let mut cost = 0.0;
    let (mut xn, mut phin, mut dxn, mut dphin) = (x.clone(), phi.clone(), dx.clone(), dphi.clone());
    for k in 0..n_eval {
        let v = data.u[k] - u_mean;
        for i in 0..q {
            let b = st.block(i);
            let c = &theta[b..b + n];
            let d = theta[b + n];
            let off = theta[b + n + 1];
            let w = &theta[b + n + 2..b + n + 2 + nw];
            let ramp = if st.integrator {
                theta[b + n + 2 + nw]
            } else {
                0.0
            };
            let t = k as f64 / big_n;
            let mut y = off + d * v + ramp * t;
            for s in 0..n {
                y += c[s] * x[s];
            }
            for s in 0..nw {
                y += w[s] * phi[s];
            }
            if let Want::Simulate = want {
                yhat[i].push(y);
                continue;
            }
            if !data.counts(i, k) {
                continue;
            }
            let r = y - data.y[i][k];
            cost += r * r;
            if !normal {
                continue;
            }
            nz.clear();
            // Pole parameters: C·∂x + w·∂φ over the mode's states.
            for j in 0..st.real {
                let s = int + j;
                row[j] = c[s] * dx[j] + w[j] * dphi[j];
                nz.push(j);
            }
            for j in 0..st.pairs {
                let s = int + st.real + 2 * j; // state index
                let f = st.real + 2 * j; // free-response / sensitivity index
                let base = 2 * f;
                // dx layout for a pair at base: [σ0, σ1, ω0, ω1].
                row[f] = c[s] * dx[base]
                    + c[s + 1] * dx[base + 1]
                    + w[f] * dphi[base]
                    + w[f + 1] * dphi[base + 1];
                row[f + 1] = c[s] * dx[base + 2]
                    + c[s + 1] * dx[base + 3]
                    + w[f] * dphi[base + 2]
                    + w[f + 1] * dphi[base + 3];
                nz.push(f);
                nz.push(f + 1);
            }
            for s in 0..n {
                row[b + s] = x[s];
                nz.push(b + s);
            }
            row[b + n] = v;
            row[b + n + 1] = 1.0;
            nz.push(b + n);
            nz.push(b + n + 1);
            for s in 0..nw {
                row[b + n + 2 + s] = phi[s];
                nz.push(b + n + 2 + s);
            }
            if st.integrator {
                row[b + n + 2 + nw] = t;
                nz.push(b + n + 2 + nw);
            }
            for (ai, &a) in nz.iter().enumerate() {
                let pa = pos[a];
                if pa == usize::MAX {
                    continue;
                }
                let ra = row[a];
                jtr[pa] += ra * r;
                for &bb in &nz[ai..] {
                    let pb = pos[bb];
                    if pb != usize::MAX {
                        jtj[(pa, pb)] += ra * row[bb];
                    }
                }
            }
        }
        // Advance states, free responses and sensitivities.
        if st.integrator {
            xn[0] = x[0] + v;
        }
        for j in 0..st.real {
            let p = theta[j];
            let s = int + j;
            xn[s] = p * x[s] + v;
            phin[j] = p * phi[j];
            dxn[j] = p * dx[j] + x[s];
            dphin[j] = p * dphi[j] + phi[j];
        }
        for j in 0..st.pairs {
            let f = st.real + 2 * j;
            let s = int + f;
            let (sg, om) = (theta[f], theta[f + 1]);
            let rot = |a: f64, b: f64| (sg * a + om * b, -om * a + sg * b);
            let (x0, x1) = rot(x[s], x[s + 1]);
            xn[s] = x0 + v;
            xn[s + 1] = x1;
            let (f0, f1) = rot(phi[f], phi[f + 1]);
            phin[f] = f0;
            phin[f + 1] = f1;
            let base = 2 * f;
            // ∂/∂σ: A ∂x + x;  ∂/∂ω: A ∂x + J x with J = [[0, 1], [−1, 0]].
            let (a0, a1) = rot(dx[base], dx[base + 1]);
            dxn[base] = a0 + x[s];
            dxn[base + 1] = a1 + x[s + 1];
            let (a0, a1) = rot(dx[base + 2], dx[base + 3]);
            dxn[base + 2] = a0 + x[s + 1];
            dxn[base + 3] = a1 - x[s];
            let (a0, a1) = rot(dphi[base], dphi[base + 1]);
            dphin[base] = a0 + phi[f];
            dphin[base + 1] = a1 + phi[f + 1];
            let (a0, a1) = rot(dphi[base + 2], dphi[base + 3]);
            dphin[base + 2] = a0 + phi[f + 1];
            dphin[base + 3] = a1 - phi[f];
        }
        std::mem::swap(&mut x, &mut xn);
        std::mem::swap(&mut phi, &mut phin);
        std::mem::swap(&mut dx, &mut dxn);
        std::mem::swap(&mut dphi, &mut dphin);
    }
    if normal {
        for a in 0..m {
            for b in 0..a {
                jtj[(a, b)] = jtj[(b, a)];
            }
        }
    }
    Sweep {
        cost: if cost.is_finite() {
            cost
        } else {
            f64::INFINITY
        },
        jtj,
        jtr,
        yhat,
    }
}

struct Problem<'a> {
    st: Structure,
    data: Data<'a>,
    n_fit: usize,
}

impl NormalEquations for Problem<'_> {
    fn cost(&mut self, z: &[f64]) -> Option<f64> {
        if !self.st.admissible(z) {
            return None;
        }
        let c = sweep(&self.st, z, &self.data, self.n_fit, Want::Cost).cost;
        c.is_finite().then_some(c)
    }
    fn normal(&mut self, z: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>, f64)> {
        if !self.st.admissible(z) {
            return None;
        }
        let s = sweep(&self.st, z, &self.data, self.n_fit, Want::Normal(None));
        s.cost.is_finite().then_some((s.jtj, s.jtr, s.cost))
    }
}

/// The structure and pole parameters of a set of starting poles: pairs from the `Im > 0`
/// members, real poles from the (nearly) real ones, each moved inside [`MAX_RADIUS`] (radius
/// capped at 0.999); with `integrator`, the real pole nearest `z = 1` (if any above 0.5) is
/// the integrator's and left out.
pub fn start_of(poles: &[Complex<f64>], integrator: bool, q: usize) -> (Structure, Vec<f64>) {
    let cap = |z: Complex<f64>| {
        let r = z.norm();
        if r > 0.999 {
            z * (0.999 / r)
        } else {
            z
        }
    };
    let mut real: Vec<f64> = Vec::new();
    let mut pairs: Vec<(f64, f64)> = Vec::new();
    for &z in poles {
        if !(z.re.is_finite() && z.im.is_finite()) {
            continue;
        }
        if z.im.abs() <= 1e-9 * z.norm().max(1e-300) {
            real.push(cap(Complex::new(z.re, 0.0)).re);
        } else if z.im > 0.0 {
            let c = cap(z);
            pairs.push((c.re, c.im));
        }
    }
    if integrator {
        if let Some((j, _)) = real
            .iter()
            .enumerate()
            .filter(|(_, p)| **p > 0.5)
            .max_by(|a, b| a.1.total_cmp(b.1))
        {
            real.remove(j);
        }
    }
    let st = Structure {
        integrator,
        real: real.len(),
        pairs: pairs.len(),
        q,
    };
    let mut theta = vec![0.0; st.len()];
    theta[..real.len()].copy_from_slice(&real);
    for (j, (s, w)) in pairs.iter().enumerate() {
        theta[real.len() + 2 * j] = *s;
        theta[real.len() + 2 * j + 1] = *w;
    }
    (st, theta)
}

/// The least-squares `(C, D, y_off, w, r)` at the poles of `theta` (its linear parameters are
/// replaced; the criterion is linear in them, [`super`]).
pub fn linear_start(st: &Structure, theta: &mut [f64], data: &Data<'_>, n_fit: usize) {
    let lin: Vec<usize> = (st.np()..st.len()).collect();
    for &j in &lin {
        theta[j] = 0.0;
    }
    let s = sweep(st, theta, data, n_fit, Want::Normal(Some(&lin)));
    let m = lin.len();
    // Columns scaled to a unit diagonal, then the SVD's least-squares solution.
    let dg: Vec<f64> = (0..m).map(|a| s.jtj[(a, a)].sqrt().max(1e-300)).collect();
    let a = DMatrix::from_fn(m, m, |i, j| s.jtj[(i, j)] / (dg[i] * dg[j]));
    let b = DVector::from_fn(m, |i, _| -s.jtr[i] / dg[i]);
    let svd = a.svd(true, true);
    let tol = svd.singular_values.max() * 1e-12;
    if let Ok(z) = svd.solve(&b, tol) {
        for (a, &j) in lin.iter().enumerate() {
            let v = z[a] / dg[a];
            theta[j] = if v.is_finite() { v } else { 0.0 };
        }
    }
}

/// The model of `theta` (the offsets moved into `(u₀, y₀)`, [`super`]).
pub fn model_of(st: &Structure, theta: &[f64], data: &Data<'_>) -> OeModel {
    let (n, nw) = (st.n(), st.nw());
    let real = theta[..st.real].to_vec();
    let pairs: Vec<(f64, f64)> = (0..st.pairs)
        .map(|j| (theta[st.real + 2 * j], theta[st.real + 2 * j + 1]))
        .collect();
    let c: Vec<Vec<f64>> = (0..st.q)
        .map(|i| theta[st.block(i)..st.block(i) + n].to_vec())
        .collect();
    let d: Vec<f64> = (0..st.q).map(|i| theta[st.block(i) + n]).collect();
    let off: Vec<f64> = (0..st.q).map(|i| theta[st.block(i) + n + 1]).collect();
    let mut m = OeModel {
        integrator: st.integrator,
        real,
        pairs,
        c,
        d,
        u0: data.u_mean(),
        y0: off,
    };
    if st.integrator && st.q > 0 {
        // r·k/N = c_I·δ·k: a constant input offset δ integrated.
        let ramp = theta[st.block(0) + n + 2 + nw];
        let ci = m.c[0][0];
        if ci.abs() > 0.0 && ramp.is_finite() {
            let delta = ramp / (data.len().max(1) as f64 * ci);
            m.u0 -= delta;
            let stable = OeModel {
                integrator: false,
                c: m.c.iter().map(|r| r[1..].to_vec()).collect(),
                ..m.clone()
            };
            if let Some(g) = stable.dc_gain() {
                for (y0, g) in m.y0.iter_mut().zip(g) {
                    *y0 -= g * delta;
                }
            }
        }
    }
    m
}

/// `ŷ` of `theta` on every sample of `data` (the fitted initial transient included).
pub fn simulate(st: &Structure, theta: &[f64], data: &Data<'_>) -> Vec<Vec<f64>> {
    sweep(st, theta, data, data.len(), Want::Simulate).yhat
}

/// Fits the structure `st` from `theta0` (its linear part replaced by the least-squares
/// start) on the samples `[0, n_fit)` of `data`.
pub fn fit(
    st: Structure,
    theta0: &[f64],
    data: &Data<'_>,
    n_fit: usize,
    opts: &FitOptions,
) -> Option<Fitted> {
    let mut theta = theta0.to_vec();
    if !st.admissible(&theta) {
        return None;
    }
    linear_start(&st, &mut theta, data, n_fit);
    let mut prob = Problem {
        st,
        data: *data,
        n_fit,
    };
    let lm = LmOptions {
        max_iter: opts.max_iter,
        rel_tol: opts.rel_tol,
        ..LmOptions::default()
    };
    let res = minimise_normal(&mut prob, &theta, &lm)?;
    Some(Fitted {
        model: model_of(&st, &res.z, data),
        structure: st,
        theta: res.z,
        cost: res.cost,
        iterations: res.iterations,
    })
}
