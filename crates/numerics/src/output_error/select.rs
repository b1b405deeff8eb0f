//! The order, the start and the integrator of the output-error model, chosen by a free-run
//! check on the held-out tail of the estimation record ([`super`]).
//!
//! The record's last `holdout` share (a quarter by default) is held out: every candidate is
//! fitted on the samples before it and simulated over the whole record (its fitted initial
//! transient, no measured output fed back), and scored on the tail by
//! `score = mean_i RMS_i / std_i` (the held-out RMS of output `i` over that output's spread
//! there). Candidates: every order of the ERA stabilization diagram and of ARX fits of orders
//! `1..=max_order`, each with and without the integrator. The integrator is shown when the
//! best model without it pushes a real pole to a time constant of a tenth of the fitted record
//! or more (it imitates an integrator there and drifts beyond); then only models with it
//! compete, else only models without it. An integrating model competes only when the tail can
//! judge its other modes ([`modes_settle_within`]): each settles within a tenth of the tail
//! (`1/(1 − |z|)` samples), and a pair turns within the record. A slower mode is a second
//! integrator over the tail (force → velocity → position with almost no damping): the tail,
//! free-run from the same record's fitted start, cannot show its drift, but another record
//! integrates any offset of its input twice (EMPS: an integrating order 3 with its second pole
//! at `τ ≈ 1.7 s` on a 6.2 s tail scored best there and drifted by metres on the test record;
//! docs/benchmarks.md). When no integrating model passes, all of them compete. The lowest
//! order whose score is within `parsimony`
//! of the best wins; it is then refitted on the whole record from its own
//! poles. [`tail_score_abcd`] scores a given `(A, B, C, D)` (the ERA model) the same way, its
//! offset and initial state fitted on the samples before the tail.

use nalgebra::{Complex, DMatrix, DVector};

use super::fit::{fit, simulate, start_of, Data, FitOptions, Fitted, Structure};
use super::model::OeModel;
use crate::eig::eigenvalues;
use crate::stabilization::Stabilization;

/// Where a candidate's starting poles came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Start {
    /// The ERA realisation of that order.
    Era,
    /// An ARX least-squares fit of that order.
    Arx,
}

/// How candidates are made and chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectOptions {
    /// Share of the record held out at its end.
    pub holdout: f64,
    /// Highest order tried.
    pub max_order: usize,
    /// A lower order wins when its score is within this share of the best.
    pub parsimony: f64,
    /// The fits of the candidates.
    pub fit: FitOptions,
    /// The final refit on the whole record.
    pub refit: FitOptions,
}

impl Default for SelectOptions {
    fn default() -> Self {
        SelectOptions {
            holdout: 0.25,
            max_order: 8,
            parsimony: 0.02,
            fit: FitOptions {
                max_iter: 15,
                rel_tol: 1e-6,
            },
            refit: FitOptions::default(),
        }
    }
}

/// One candidate and its held-out figures.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Candidate {
    /// Model order (the integrator counted).
    pub order: usize,
    /// With the pole at `z = 1`.
    pub integrator: bool,
    /// Where its starting poles came from.
    pub start: Start,
    /// Held-out RMS per output.
    pub tail_rms: Vec<f64>,
    /// `mean_i RMS_i / std_i` on the tail.
    pub score: f64,
}

/// The chosen model.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// The model refitted on the whole record.
    pub model: OeModel,
    /// Every candidate fitted.
    pub candidates: Vec<Candidate>,
    /// Index of the chosen one in `candidates`.
    pub chosen: usize,
    /// Samples fitted before the tail.
    pub n_fit: usize,
}

impl Selection {
    /// The chosen candidate.
    pub fn best(&self) -> &Candidate {
        &self.candidates[self.chosen]
    }
}

/// The samples before the held-out tail.
pub fn split(n: usize, holdout: f64) -> usize {
    let tail = ((n as f64) * holdout.clamp(0.0, 0.9)).round() as usize;
    n - tail.min(n)
}

/// RMS per output of `yhat` against `data` on `[from, N)` and the score (module doc).
pub fn tail_figures(data: &Data<'_>, yhat: &[Vec<f64>], from: usize) -> (Vec<f64>, f64) {
    let mut rms = Vec::with_capacity(data.y.len());
    let mut score = 0.0;
    for (i, yh) in yhat.iter().enumerate() {
        let ks: Vec<usize> = (from..data.len())
            .filter(|&k| data.counts(i, k) && yh[k].is_finite())
            .collect();
        if ks.is_empty() {
            return (vec![f64::NAN; data.y.len()], f64::INFINITY);
        }
        let m = ks.len() as f64;
        let mean = ks.iter().map(|&k| data.y[i][k]).sum::<f64>() / m;
        let e = (ks
            .iter()
            .map(|&k| (yh[k] - data.y[i][k]).powi(2))
            .sum::<f64>()
            / m)
            .sqrt();
        let sd = (ks
            .iter()
            .map(|&k| (data.y[i][k] - mean).powi(2))
            .sum::<f64>()
            / m)
            .sqrt();
        rms.push(e);
        score += e / sd.max(1e-300);
    }
    let score = score / yhat.len().max(1) as f64;
    (
        rms,
        if score.is_finite() {
            score
        } else {
            f64::INFINITY
        },
    )
}

/// The poles of an ARX fit of order `n` to output `y` (`y_k + Σ a_j y_{k−j} = Σ b_j u_{k−j}
/// + c`, least squares over the samples whose regressors are all measured): the roots of
/// `zⁿ + a₁ zⁿ⁻¹ + … + a_n`, as eigenvalues of its companion matrix.
pub fn arx_poles(data: &Data<'_>, n: usize, n_fit: usize) -> Option<Vec<Complex<f64>>> {
    let y = data.y.first()?;
    let p = 2 * n + 1;
    let mut ata = DMatrix::<f64>::zeros(p, p);
    let mut atb = DVector::<f64>::zeros(p);
    let mut phi = vec![0.0; p];
    let mut rows = 0;
    for k in n..n_fit.min(data.len()) {
        if !(0..=n).all(|j| data.counts(0, k - j)) {
            continue;
        }
        for j in 1..=n {
            phi[j - 1] = -y[k - j];
            phi[n + j - 1] = data.u[k - j];
        }
        phi[2 * n] = 1.0;
        for a in 0..p {
            atb[a] += phi[a] * y[k];
            for b in 0..p {
                ata[(a, b)] += phi[a] * phi[b];
            }
        }
        rows += 1;
    }
    if rows <= p {
        return None;
    }
    let dg: Vec<f64> = (0..p).map(|a| ata[(a, a)].sqrt().max(1e-300)).collect();
    let s = DMatrix::from_fn(p, p, |i, j| ata[(i, j)] / (dg[i] * dg[j]));
    let svd = s.svd(true, true);
    let tol = svd.singular_values.max() * 1e-12;
    let theta = svd
        .solve(&DVector::from_fn(p, |i, _| atb[i] / dg[i]), tol)
        .ok()?;
    // Companion matrix (column-major): first row −a, ones below the diagonal.
    let mut c = vec![0.0; n * n];
    for j in 0..n {
        c[j * n] = -theta[j] / dg[j];
        if j + 1 < n {
            c[(j + 1) + j * n] = 1.0;
        }
    }
    let mut z = vec![Complex::new(0.0, 0.0); n];
    eigenvalues(&mut c, n, &mut z).ok()?;
    z.iter()
        .all(|v| v.re.is_finite() && v.im.is_finite())
        .then_some(z)
}

/// The discrete poles of every order of a stabilization diagram (`z = e^{s dt}` from each
/// entry's `fn`, `ζ`; a real entry is `ζ = ±1`, an entry at Nyquist one negative real pole).
pub fn era_poles(stab: &Stabilization, dt: f64) -> Vec<Vec<Complex<f64>>> {
    let nyq = std::f64::consts::PI / dt;
    stab.orders
        .iter()
        .map(|o| {
            let mut z = Vec::new();
            for p in &o.poles {
                let wn = 2.0 * std::f64::consts::PI * p.fn_hz;
                if !(wn.is_finite() && p.zeta.is_finite()) {
                    continue;
                }
                if p.zeta.abs() >= 1.0 - 1e-12 {
                    z.push(Complex::new((-p.zeta * wn * dt).exp(), 0.0));
                    continue;
                }
                let s = Complex::new(-p.zeta * wn, wn * (1.0 - p.zeta * p.zeta).sqrt());
                if (s.im - nyq).abs() <= 1e-9 * nyq {
                    z.push(Complex::new(-(s.re * dt).exp(), 0.0));
                } else {
                    let zz = (s * dt).exp();
                    z.push(zz);
                    z.push(zz.conj());
                }
            }
            z
        })
        .collect()
}

/// Whether every mode of `m` but its integrator is one a held-out tail of `tail` samples (of a
/// record of `n`) can judge (module doc): its time constant `1/(1 − |z|)` below a tenth of the
/// tail, and a pair's period `2π/arg z` shorter than the record.
pub fn modes_settle_within(m: &OeModel, tail: usize, n: usize) -> bool {
    let slowest = tail as f64 / 10.0;
    let settles = |r: f64| r < 1.0 && 1.0 / (1.0 - r) < slowest;
    m.real.iter().all(|&p| p <= 0.0 || settles(p))
        && m.pairs.iter().all(|&(s, w)| {
            let z = Complex::new(s, w);
            settles(z.norm()) && z.arg().abs() > std::f64::consts::TAU / n as f64
        })
}

/// Fits every candidate of the starts (each a pole set, labelled) on the samples before the
/// tail, scores them there and refits the chosen one on the whole record (module doc).
/// `None` when no candidate could be fitted.
pub fn select(
    data: &Data<'_>,
    starts: &[(Start, Vec<Complex<f64>>)],
    opts: &SelectOptions,
) -> Option<Selection> {
    let q = data.y.len();
    let n_fit = split(data.len(), opts.holdout);
    let mut fitted: Vec<(Candidate, Fitted)> = Vec::new();
    let mut seen: Vec<(Start, Structure)> = Vec::new();
    for (start, poles) in starts {
        for integrator in [false, true] {
            let (st, theta) = start_of(poles, integrator, q);
            if st.n() == 0 || st.n() > opts.max_order || seen.contains(&(*start, st)) {
                continue;
            }
            seen.push((*start, st));
            let Some(f) = fit(st, &theta, data, n_fit, &opts.fit) else {
                continue;
            };
            let yhat = simulate(&st, &f.theta, data);
            let (tail_rms, score) = tail_figures(data, &yhat, n_fit);
            fitted.push((
                Candidate {
                    order: st.n(),
                    integrator,
                    start: *start,
                    tail_rms,
                    score,
                },
                f,
            ));
        }
    }
    // Integrator or not: shown when the best model without one pushes a real pole to a time
    // constant of a tenth of the fitted record or more (it imitates an integrator over the
    // record and drifts beyond it); then only models with the pole at z = 1 compete.
    let shown = fitted
        .iter()
        .filter(|(c, _)| !c.integrator)
        .min_by(|a, b| a.0.score.total_cmp(&b.0.score))
        .is_some_and(|(_, f)| {
            f.model
                .real
                .iter()
                .any(|&p| p > 0.0 && 1.0 / (1.0 - p) > n_fit as f64 / 10.0)
        });
    // An integrating model's other modes must be ones the tail can judge (module doc).
    let tail = data.len() - n_fit;
    let judged = |c: &Candidate, f: &Fitted| {
        !c.integrator || modes_settle_within(&f.model, tail, data.len())
    };
    let any_judged = fitted
        .iter()
        .any(|(c, f)| c.integrator == shown && judged(c, f));
    let allowed =
        |c: &Candidate, f: &Fitted| c.integrator == shown && (!any_judged || judged(c, f));
    let best = fitted
        .iter()
        .filter(|(c, f)| allowed(c, f))
        .map(|(c, _)| c.score)
        .fold(f64::INFINITY, f64::min);
    if !best.is_finite() {
        return None;
    }
    let chosen = fitted
        .iter()
        .enumerate()
        .filter(|(_, (c, f))| allowed(c, f) && c.score <= best * (1.0 + opts.parsimony))
        .min_by(|a, b| {
            (a.1 .0.order, a.1 .0.score)
                .partial_cmp(&(b.1 .0.order, b.1 .0.score))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .map(|(i, _)| i)?;
    let f = &fitted[chosen].1;
    let model = fit(f.structure, &f.theta, data, data.len(), &opts.refit)
        .map_or_else(|| f.model.clone(), |r| r.model);
    Some(Selection {
        model,
        candidates: fitted.into_iter().map(|(c, _)| c).collect(),
        chosen,
        n_fit,
    })
}

/// The held-out score of a given model `(A, B, C, D)` (rows; one input) on `data`'s tail:
/// simulated from rest with `v = u − ū`, its output offset and initial state fitted by least
/// squares on the samples before the tail (module doc). `(RMS per output, score)`.
pub fn tail_score_abcd(
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    c: &[Vec<f64>],
    d: &[Vec<f64>],
    data: &Data<'_>,
    holdout: f64,
) -> (Vec<f64>, f64) {
    let n = a.len();
    let q = c.len().min(data.y.len());
    let n_fit = split(data.len(), holdout);
    let u_mean = data.u_mean();
    let am = DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let bm = DVector::from_fn(n, |i, _| b[i].first().copied().unwrap_or(0.0));
    let cm = DMatrix::from_fn(q, n, |i, j| c[i][j]);
    // Forced response and the free responses C Aᵏ e_j, all samples.
    let mut x = DVector::<f64>::zeros(n);
    let mut f = DMatrix::<f64>::identity(n, n);
    let mut forced = vec![Vec::with_capacity(data.len()); q];
    let mut free = vec![Vec::with_capacity(data.len()); q];
    for k in 0..data.len() {
        let v = data.u[k] - u_mean;
        let y = &cm * &x;
        let cf = &cm * &f;
        for i in 0..q {
            forced[i].push(y[i] + d[i].first().copied().unwrap_or(0.0) * v);
            free[i].push(cf.row(i).iter().copied().collect::<Vec<f64>>());
        }
        x = &am * x + &bm * v;
        f = &am * f;
    }
    let mut yhat = vec![vec![0.0; data.len()]; q];
    for i in 0..q {
        // Least squares for [offset, x0] on the fitted samples.
        let p = n + 1;
        let mut ata = DMatrix::<f64>::zeros(p, p);
        let mut atb = DVector::<f64>::zeros(p);
        let mut row = vec![0.0; p];
        for k in 0..n_fit {
            if !data.counts(i, k) || !forced[i][k].is_finite() {
                continue;
            }
            row[0] = 1.0;
            row[1..].copy_from_slice(&free[i][k]);
            let r = data.y[i][k] - forced[i][k];
            for s in 0..p {
                atb[s] += row[s] * r;
                for t in 0..p {
                    ata[(s, t)] += row[s] * row[t];
                }
            }
        }
        let svd = ata.svd(true, true);
        let tol = svd.singular_values.max() * 1e-12;
        let z = svd.solve(&atb, tol).unwrap_or_else(|_| DVector::zeros(p));
        for k in 0..data.len() {
            let fr: f64 = free[i][k]
                .iter()
                .zip(z.iter().skip(1))
                .map(|(a, b)| a * b)
                .sum();
            yhat[i][k] = forced[i][k] + z[0] + fr;
        }
    }
    tail_figures(data, &yhat, n_fit)
}
