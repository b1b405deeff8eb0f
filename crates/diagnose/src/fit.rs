//! Fitting the output-error model of [`super::model`] to measured data.
//!
//! - [`linear_refit`]: the parameters that enter linearly (gain `K`, offset `c`, and each
//!   term's linear coefficients, e.g. a drift rate or sine/cosine amplitudes) by least squares,
//!   with the others held — used to score grid points of the nonlinear parameters cheaply.
//! - [`levenberg_marquardt`]: all free parameters by Levenberg–Marquardt (Marquardt 1963) on the
//!   simulation error `r = y − ŷ(θ)` over the estimation samples, with a forward-difference
//!   Jacobian and Marquardt's diagonal scaling, `(JᵀJ + λ diag JᵀJ) δ = Jᵀ r`. Frequencies and
//!   damping ratios are adjusted in logarithm so that they stay positive. Where the output is
//!   affine in the core's gain and offset ([`Model::affine_in_gain_and_offset`]: `ŷ = K g + c + a`),
//!   their columns are analytic instead, `∂ŷ/∂c = 1` and `∂ŷ/∂K = g = (ŷ − c − a)/K`, from the
//!   simulation the fit has already made (two simulations fewer per Jacobian; a forward
//!   difference of an affine parameter differs from them by rounding only). A forward
//!   difference of a parameter acting after the input's stage (the core's `fn` and `ζ`, a core
//!   or series term's) starts from the stage the current simulation kept
//!   ([`crate::model::Stages`]): the shaped input, or the core's output, is not made again.
//! - [`Ctx::lm`], [`Ctx::best_of`], [`Ctx::residual`]: those steps on the data of one diagnosis.

use std::ops::Range;

use nalgebra::{DMatrix, DVector};

use super::ctx::Ctx;
use super::model::{
    simulate, simulate_places, simulate_staged, Model, Stages, Start, GAIN_INDEX, OFFSET_INDEX,
};
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

/// Residuals `y − ŷ` over the finite estimation samples; the simulation's stages kept in
/// `keep`.
fn residuals(
    m: &Model,
    sig: &Signals,
    range: &Range<usize>,
    buf: &mut Vec<f64>,
    r: &mut Vec<f64>,
    keep: Option<&mut Stages>,
) {
    buf.resize(sim_len(sig, range), 0.0);
    simulate_staged(m, sig, buf, true, Start::Input, keep);
    residuals_of(sig, buf, range, r);
}

/// `JᵀJ` and `Jᵀr` of the Jacobian's columns `cols` and `r`: each entry summed over the
/// samples in their order (the sums of column dot products, bit for bit). The samples are
/// taken in blocks that stay in the first-level cache while every entry's sum runs over them,
/// eight entries side by side.
fn normal_equations(cols: &[Vec<f64>], r: &[f64]) -> (DMatrix<f64>, DVector<f64>) {
    let m = cols.len();
    let mut pairs: Vec<(usize, usize)> = Vec::with_capacity(m * (m + 3) / 2);
    for a in 0..m {
        pairs.push((a, m));
        pairs.extend((a..m).map(|b| (a, b)));
    }
    let col = |j: usize| if j == m { r } else { &cols[j][..] };
    let n = r.len();
    let mut sums = vec![-0.0f64; pairs.len()];
    const BLOCK: usize = 256;
    for lo in (0..n).step_by(BLOCK) {
        let hi = (lo + BLOCK).min(n);
        let mut at = 0;
        while at < pairs.len() {
            let left = pairs.len() - at;
            let w = if left >= 8 {
                8
            } else if left >= 4 {
                4
            } else {
                1
            };
            let q = &pairs[at..at + w];
            let acc = &mut sums[at..at + w];
            match w {
                8 => accumulate::<8>(acc, q, &col, lo..hi),
                4 => accumulate::<4>(acc, q, &col, lo..hi),
                _ => accumulate::<1>(acc, q, &col, lo..hi),
            }
            at += w;
        }
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

/// Adds `Σ_k a_k b_k` over the samples `ks` to each of the `W` sums `acc` of the column pairs
/// `pairs` (each sum in sample order).
fn accumulate<'a, const W: usize>(
    acc: &mut [f64],
    pairs: &[(usize, usize)],
    col: &impl Fn(usize) -> &'a [f64],
    ks: Range<usize>,
) {
    let a: [&[f64]; W] = std::array::from_fn(|i| &col(pairs[i].0)[ks.clone()]);
    let b: [&[f64]; W] = std::array::from_fn(|i| &col(pairs[i].1)[ks.clone()]);
    let len = ks.len();
    // Every column cut to the block's length, so that the loop needs no bounds checks.
    let (a, b): ([&[f64]; W], [&[f64]; W]) = (
        std::array::from_fn(|i| &a[i][..len]),
        std::array::from_fn(|i| &b[i][..len]),
    );
    let mut s: [f64; W] = std::array::from_fn(|i| acc[i]);
    for k in 0..len {
        for i in 0..W {
            s[i] += a[i][k] * b[i][k];
        }
    }
    acc[..W].copy_from_slice(&s);
}

/// The simulations of `p0` and of each forward-difference step of its free parameters on the
/// whole record: the first Jacobian of every [`levenberg_marquardt_from`] that starts at `p0`
/// on the same input whatever outputs it masks (the folds' refits), computed once.
#[derive(Debug, Clone)]
pub struct FirstJacobian {
    /// `ŷ(θ₀)`.
    base: Vec<f64>,
    /// `ŷ(θ₀ + h_j e_j)` for each free parameter `j` (empty for an analytic column,
    /// [`analytic_column`]).
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
        let params: Vec<usize> = (0..z.len()).filter(|&j| !analytic_column(p0, j)).collect();
        // Each step's simulation is independent of the others': on every core.
        let sims = crate::par::map(&params, |&j| {
            let mut zj = z.clone();
            zj[j] += step(&z, &scales, j);
            let mut s = vec![0.0; n];
            simulate(&from_z(p0, &scales, &zj), sig, &mut s);
            s
        });
        let mut stepped = vec![Vec::new(); z.len()];
        for (&j, s) in params.iter().zip(sims) {
            stepped[j] = s;
        }
        FirstJacobian { base, stepped }
    }
}

/// Whether the Jacobian's column of free parameter `j` of `m` is analytic (module doc): the
/// gain's and the offset's of a model affine in them, the gain's only while it is not zero.
fn analytic_column(m: &Model, j: usize) -> bool {
    m.affine_in_gain_and_offset()
        && (j == OFFSET_INDEX || (j == GAIN_INDEX && m.core.gain.abs() > 1e-12))
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
    // `ŷ` at `p` (for the analytic columns) and its stages (the forward differences of the
    // parameters after the input's stage start from them: `Model::start_of_free`).
    let mut sim = Vec::new();
    let (mut stages, mut trial_stages) = (Stages::default(), Stages::default());
    let mut staged = first.is_none();
    match first {
        Some(s) => {
            residuals_of(sig, &s.base, &range, &mut r);
            sim.extend_from_slice(&s.base[..sim_len(sig, &range)]);
        }
        None => {
            residuals(&p, sig, &range, &mut buf, &mut r, Some(&mut stages));
            sim.clone_from(&buf);
        }
    }
    let mut added = Vec::new();
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
        // The Jacobian of the simulation: analytic columns where the model allows, forward
        // differences elsewhere.
        if p.affine_in_gain_and_offset() {
            p.output_added(sig, sim.len(), &mut added);
        }
        for j in 0..m {
            if analytic_column(&p, j) {
                let (gain, offset) = (p.core.gain, p.core.offset);
                let measured = range.clone().filter(|&k| sig.y[k].is_finite());
                cols[j].clear();
                if j == OFFSET_INDEX {
                    cols[j].extend(measured.map(|_| 1.0));
                } else {
                    cols[j].extend(measured.map(|k| (sim[k] - offset - added[k]) / gain));
                }
                continue;
            }
            let h = step(&z, &scales, j);
            match first.filter(|_| iter == 0) {
                Some(s) => residuals_of(sig, &s.stepped[j], &range, &mut rj),
                None => {
                    zj.copy_from_slice(&z);
                    zj[j] += h;
                    let mj = from_z(p0, &scales, &zj);
                    let start = match staged {
                        true => p.start_of_free(j, &stages),
                        false => Start::Input,
                    };
                    buf.resize(sim_len(sig, &range), 0.0);
                    simulate_staged(&mj, sig, &mut buf, true, start, None);
                    residuals_of(sig, &buf, &range, &mut rj);
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
            residuals(&pt, sig, &range, &mut buf, &mut rj, Some(&mut trial_stages));
            let ct: f64 = rj.iter().map(|e| e * e).sum();
            if ct.is_finite() && ct < cost {
                let rel = (cost - ct) / cost.max(1e-300);
                z = zt;
                p = pt;
                cost = ct;
                std::mem::swap(&mut r, &mut rj);
                std::mem::swap(&mut sim, &mut buf);
                std::mem::swap(&mut stages, &mut trial_stages);
                staged = true;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::baseline_drift::BaselineDriftParams;
    use crate::effects::dead_time::DeadTimeParams;
    use crate::effects::extra_mode::ExtraModeParams;
    use crate::effects::static_nonlinearity::StaticNonlinearityParams;
    use crate::signals::Core;

    fn staircase(n: usize) -> Vec<f64> {
        (0..n).map(|k| 0.3 + 0.1 * ((k / 60) % 5) as f64).collect()
    }

    fn model() -> Model {
        Model::new(Core {
            fn_hz: 4.0,
            zeta: 0.6,
            gain: 2.5,
            offset: 0.3,
            lead: 0.4,
        })
        .with(DeadTimeParams::throttle(3))
        .with(StaticNonlinearityParams { exponent: 1.7 })
        .with(ExtraModeParams {
            fn_hz: 20.0,
            zeta: 0.1,
            gain: 0.2,
        })
        .with(BaselineDriftParams { rate_per_s: 0.05 })
    }

    #[test]
    fn the_gain_and_offset_columns_are_the_forward_differences() {
        let u = staircase(600);
        let y = vec![0.0; u.len()];
        let sig = Signals {
            dt_s: 0.01,
            u: &u,
            y: &y,
            voltage: None,
            u_ref: 0.5,
            v_ref: 0.0,
        };
        let m = model();
        assert!(m.affine_in_gain_and_offset());
        assert!(analytic_column(&m, GAIN_INDEX) && analytic_column(&m, OFFSET_INDEX));
        assert!(!analytic_column(&m, 0) && !analytic_column(&m, 4));
        let sim = |m: &Model| {
            let mut s = vec![0.0; u.len()];
            simulate(m, &sig, &mut s);
            s
        };
        let base = sim(&m);
        let mut added = Vec::new();
        m.output_added(&sig, u.len(), &mut added);
        let h = 1e-6;
        let (mut dk, mut dc) = (m.clone(), m.clone());
        dk.core.gain += h;
        dc.core.offset += h;
        let (sk, sc) = (sim(&dk), sim(&dc));
        for k in 0..u.len() {
            let gain = (base[k] - m.core.offset - added[k]) / m.core.gain;
            assert!(((sk[k] - base[k]) / h - gain).abs() < 1e-6, "{k}");
            assert!(((sc[k] - base[k]) / h - 1.0).abs() < 1e-6, "{k}");
        }
        // A core that changes its law, or a limit on the output: forward differences.
        use crate::effects::saturation::{Clipped, SaturationParams};
        let clipped = m.with(SaturationParams {
            level: 1.0,
            clipped: Clipped::Sensor { samples: 10 },
        });
        assert!(!clipped.affine_in_gain_and_offset());
        assert!(!analytic_column(&clipped, OFFSET_INDEX));
    }

    #[test]
    fn the_normal_equations_are_the_column_dot_products_in_sample_order() {
        for m in [1, 3, 5, 6] {
            let n = 1000;
            let cols: Vec<Vec<f64>> = (0..m)
                .map(|j| {
                    (0..n)
                        .map(|k| ((k * (j + 3)) % 17) as f64 * 0.37 - 2.9)
                        .collect()
                })
                .collect();
            let r: Vec<f64> = (0..n)
                .map(|k| ((k * 7) % 13) as f64 * 1.3e-3 - 0.01)
                .collect();
            let (jtj, jtr) = normal_equations(&cols, &r);
            let dot = |a: &[f64], b: &[f64]| {
                let mut s = -0.0;
                for k in 0..n {
                    s += a[k] * b[k];
                }
                s
            };
            for a in 0..m {
                assert_eq!(jtr[a].to_bits(), dot(&cols[a], &r).to_bits());
                for b in 0..m {
                    assert_eq!(jtj[(a, b)].to_bits(), dot(&cols[a], &cols[b]).to_bits());
                }
            }
        }
    }

    #[test]
    fn a_fit_recovers_the_model_that_made_the_data() {
        let u = staircase(1200);
        // The gain and offset analytic, the core's fn and ζ from the kept stage, the
        // exponent's from the input.
        let truth = Model::new(Core {
            fn_hz: 4.0,
            zeta: 0.6,
            gain: 2.5,
            offset: 0.3,
            lead: 0.0,
        })
        .with(DeadTimeParams::throttle(3))
        .with(StaticNonlinearityParams { exponent: 1.7 });
        let mut y = vec![0.0; u.len()];
        let sig0 = Signals {
            dt_s: 0.01,
            u: &u,
            y: &[],
            voltage: None,
            u_ref: 0.5,
            v_ref: 0.0,
        };
        simulate(&truth, &sig0, &mut y);
        let sig = Signals { y: &y, ..sig0 };
        let mut start = truth.clone();
        start.core.fn_hz = 3.6;
        start.core.zeta = 0.7;
        start.core.gain = 2.2;
        start.core.offset = 0.2;
        let f = levenberg_marquardt(&start, &sig, 0..u.len(), 60);
        let c = f.model.core;
        assert!(f.sse < 1e-10, "{}", f.sse);
        assert!(
            (c.fn_hz - 4.0).abs() < 1e-3 && (c.zeta - 0.6).abs() < 1e-3,
            "{c:?}"
        );
        assert!(
            (c.gain - 2.5).abs() < 1e-3 && (c.offset - 0.3).abs() < 1e-3,
            "{c:?}"
        );
    }
}
