//! The allocation-free identification entry point: a [`Workspace`] built once from [`Limits`]
//! holds every buffer; [`Workspace::identify`] (pulse experiments) and
//! [`Workspace::identify_markov`] (given Markov parameters, e.g. from OKID) fill its
//! [`Model`] without touching the heap (proven by `tests/alloc_free.rs`).
//!
//! ```no_run
//! use propid_numerics::workspace::{IdentOptions, Limits, Workspace};
//! use propid_numerics::pulses::PulseInput;
//! # let (u, thrust) = (vec![0.0; 10], vec![0.0; 10]);
//! let mut ws = Workspace::new(&Limits::default()).unwrap();
//! let y = [&thrust[..]];
//! let input = PulseInput { dt_s: 0.001, u: &u, y: &y, missing: &[], pulse_starts: None };
//! let model = ws.identify(&input, &IdentOptions::default()).unwrap();
//! println!("{}", serde_json::to_string(&model.to_report()).unwrap());
//! ```

use nalgebra::Complex;

use super::eig::eigenvalues;
use super::era::{h1_times_v, realize};
use super::grouped::{input_matrix, WidthGroups, MAX_GROUPS};
use super::hankel::HankelDims;
use super::modal::{continuous, dc_gain, fn_zeta};
use super::model::Model;
use super::pulses::{PulseEnsemble, PulseInput};
use super::sizing;
use super::svd::dense::DenseSvd;
use super::svd::subspace::SubspaceSvd;
use super::svd::truncated::TruncatedSvd;
use super::svd::{self, SvdChoice, SvdPath};
use super::uncertainty::jackknife_std;
use super::{IdentError, MarkovSeq};

type C64 = Complex<f64>;

/// Extra singular triplets beyond the order kept for the jackknife's subspace iteration (dense
/// path).
const EXTRA_TRIPLETS: usize = 4;

/// Subspace iterations per jackknife re-identification.
const JACKKNIFE_ITERS: usize = 4;

/// Sizes a [`Workspace`] is built for. Inputs beyond them give [`IdentError::LimitsExceeded`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Limits {
    /// Longest record (samples) or Markov sequence (blocks).
    pub max_samples: usize,
    /// Most output channels `q` (at most 64).
    pub max_outputs: usize,
    /// Most inputs `p` (pulse experiments have 1).
    pub max_inputs: usize,
    /// Highest model order.
    pub max_order: usize,
    /// Most Hankel block rows `r`.
    pub max_block_rows: usize,
    /// Most Hankel block columns `c`.
    pub max_block_cols: usize,
    /// Most pulses in one record.
    pub max_pulses: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_samples: 8192,
            max_outputs: 3,
            max_inputs: 1,
            max_order: 12,
            max_block_rows: 128,
            max_block_cols: 128,
            max_pulses: 256,
        }
    }
}

/// Options of one identification.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentOptions {
    /// Model order; `None` chooses it from the singular values against the noise floor.
    pub order: Option<usize>,
    /// SVD path.
    pub svd: SvdChoice,
    /// Hankel block rows and columns `(r, c)`; `None` sizes them automatically.
    pub hankel_blocks: Option<(usize, usize)>,
    /// Widest throttle pulse (samples); wider level changes are operating-point steps
    /// ([`crate::segment::SegmentRules::max_pulse_samples`]).
    pub max_pulse_width: usize,
    /// Compute the jackknife uncertainty (one re-identification per pulse).
    pub jackknife: bool,
}

impl Default for IdentOptions {
    fn default() -> Self {
        Self {
            order: None,
            svd: SvdChoice::Auto,
            hankel_blocks: None,
            max_pulse_width: crate::segment::SegmentRules::DEFAULT.max_pulse_samples,
            jackknife: true,
        }
    }
}

/// Everything an identification needs, allocated once.
#[derive(Debug)]
pub struct Workspace {
    limits: Limits,
    ensemble: PulseEnsemble,
    groups: WidthGroups,
    markov: MarkovSeq,
    grouped: MarkovSeq,
    jk_markov: MarkovSeq,
    jk_weights: [f64; MAX_GROUPS],
    engine: Engine,
}

/// SVD, realisation and jackknife buffers (split from the Markov storage for borrowing).
#[derive(Debug)]
struct Engine {
    limits: Limits,
    kmax: usize,
    dense_rows: usize,
    dense_cols: usize,
    hbuf: Vec<f64>,
    dense: DenseSvd,
    trunc: TruncatedSvd,
    sub: SubspaceSvd,
    u: Vec<f64>,
    v: Vec<f64>,
    jk_sigma: Vec<f64>,
    jk_u: Vec<f64>,
    jk_v: Vec<f64>,
    era_scratch: Vec<f64>,
    noise: Vec<f64>,
    lite: Lite,
    theta_fn: Vec<f64>,
    theta_zeta: Vec<f64>,
    theta_dc: Vec<f64>,
    model: Model,
}

/// A bare `(A, B, C, D)` with pole and DC-gain scratch, for jackknife re-identifications.
#[derive(Debug, Clone)]
struct Lite {
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    d: Vec<f64>,
    m: Vec<f64>,
    s: Vec<f64>,
    nrm: Vec<f64>,
    b1: Vec<f64>,
    x: Vec<f64>,
    poles: Vec<C64>,
    dc: Vec<f64>,
}

impl Workspace {
    /// Allocates every buffer for `limits`.
    pub fn new(limits: &Limits) -> Result<Self, IdentError> {
        let l = *limits;
        if l.max_samples < 4
            || l.max_outputs == 0
            || l.max_outputs > 64
            || l.max_inputs == 0
            || l.max_order == 0
            || l.max_block_rows == 0
            || l.max_block_cols == 0
            || l.max_pulses == 0
        {
            return Err(IdentError::InvalidInput(
                "limits: every size must be >= 1 (max_samples >= 4, max_outputs <= 64)",
            ));
        }
        let markov_cap = l.max_samples;
        Ok(Self {
            limits: l,
            ensemble: PulseEnsemble::new(l.max_samples, l.max_outputs, l.max_pulses),
            groups: WidthGroups::new(l.max_samples, l.max_outputs, l.max_pulses),
            markov: MarkovSeq::zeros(l.max_outputs, l.max_inputs, markov_cap),
            grouped: MarkovSeq::zeros(l.max_outputs, max_p(&l), markov_cap),
            jk_markov: MarkovSeq::zeros(l.max_outputs, max_p(&l), markov_cap),
            jk_weights: [0.0; MAX_GROUPS],
            engine: Engine::new(&l),
        })
    }

    /// The limits this workspace was built for.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// The last identified model (valid after a successful identification).
    pub fn model(&self) -> &Model {
        &self.engine.model
    }

    /// The averaged, width-deconvolved Markov parameters `Y_0 .. Y_{L-1}` of the last pulse
    /// identification (for plots and export; ERA itself runs on the per-width responses, see
    /// [`crate::grouped`], which equal these for one-sample pulses).
    pub fn markov(&self) -> &MarkovSeq {
        &self.markov
    }

    /// The allocating report of the last model.
    pub fn to_report(&self) -> super::ModelReport {
        self.engine.model.to_report()
    }

    /// Identifies from a pulse experiment: pulses → per-width averaged responses → ERA →
    /// input matrix, modal summary, indicators, jackknife uncertainty. No heap allocation.
    pub fn identify(
        &mut self,
        input: &PulseInput<'_>,
        opts: &IdentOptions,
    ) -> Result<&Model, IdentError> {
        self.identify_model(input, opts)?;
        if opts.jackknife {
            self.jackknife_model(input)?;
        }
        Ok(&self.engine.model)
    }

    /// The jackknife uncertainty of the model [`identify_model`](Self::identify_model) just
    /// identified from `input` (the second half of [`identify`](Self::identify)).
    pub fn jackknife_model(&mut self, input: &PulseInput<'_>) -> Result<&Model, IdentError> {
        let base = self.engine.model.pair_s();
        self.jackknife(input, base)?;
        Ok(&self.engine.model)
    }

    /// [`identify`](Self::identify) without the jackknife (`uncertainty` stays NaN; see
    /// [`jackknife_only`](Self::jackknife_only) to compute it beside). No heap allocation.
    pub fn identify_model(
        &mut self,
        input: &PulseInput<'_>,
        opts: &IdentOptions,
    ) -> Result<&Model, IdentError> {
        self.prepare_pulses(input, opts)?;
        let q = input.y.len();
        let rms = (self
            .ensemble
            .output_noise()
            .iter()
            .map(|s| s * s)
            .sum::<f64>()
            / q as f64)
            .sqrt();
        let e = &mut self.engine;
        e.run(&self.grouped, input.dt_s, &[], true, opts)?;
        e.single_input(self.groups.widths(), self.groups.weights(), self.groups.d())?;
        e.model.finish_gain()?;
        e.model.pulses = self.ensemble.kept();
        e.model.skipped = self.ensemble.skipped();
        e.model.noise_rms = rms;
        Ok(&self.engine.model)
    }

    /// The jackknife uncertainty of an order-2 model on the truncated SVD path, without the
    /// model itself: the same pulses, Hankel size and leave-one-out re-identifications as
    /// [`identify`](Self::identify), so that a second workspace (another thread) can compute
    /// it while this one's twin runs [`identify_model`](Self::identify_model) on the same
    /// input; [`set_uncertainty`](Self::set_uncertainty) then completes the model, identical to
    /// what `identify` gives. For order 2 the leave-one-out pole pair needs no reference pair
    /// (both orderings give the same fn and ζ). Returns `Ok(false)` (nothing computed) when
    /// this does not apply: jackknife off, order not fixed at 2, or the dense path (whose
    /// jackknife starts from the model's singular vectors). The uncertainty is then read with
    /// [`Model::uncertainty`] on [`model`](Self::model). No heap allocation.
    pub fn jackknife_only(
        &mut self,
        input: &PulseInput<'_>,
        opts: &IdentOptions,
    ) -> Result<bool, IdentError> {
        if !opts.jackknife || opts.order != Some(2) {
            return Ok(false);
        }
        self.prepare_pulses(input, opts)?;
        let (dims, path) = self.engine.plan(&self.grouped, &[], true, opts)?;
        if path != SvdPath::Truncated {
            return Ok(false);
        }
        let m = &mut self.engine.model;
        m.n = 2;
        m.q = input.y.len();
        m.p = self.grouped.inputs();
        m.dt_s = input.dt_s;
        m.dims = dims;
        m.path = path;
        m.std_fn = f64::NAN;
        m.std_zeta = f64::NAN;
        m.std_dc.fill(f64::NAN);
        let zero = C64::new(0.0, 0.0);
        self.jackknife(input, Some((zero, zero)))?;
        Ok(true)
    }

    /// Sets the jackknife uncertainty of the last model (from [`jackknife_only`] of a twin
    /// workspace): std of fn, ζ and of the DC gain of each output.
    ///
    /// [`jackknife_only`]: Self::jackknife_only
    pub fn set_uncertainty(&mut self, std_fn: f64, std_zeta: f64, std_dc: &[f64]) {
        let m = &mut self.engine.model;
        m.std_fn = std_fn;
        m.std_zeta = std_zeta;
        let q = std_dc.len().min(m.std_dc.len());
        m.std_dc[..q].copy_from_slice(&std_dc[..q]);
    }

    /// Ensemble, per-width responses and the Markov-parameter noise of a pulse experiment.
    fn prepare_pulses(
        &mut self,
        input: &PulseInput<'_>,
        opts: &IdentOptions,
    ) -> Result<(), IdentError> {
        self.ensemble
            .build(input, opts.max_pulse_width, &mut self.markov)?;
        self.groups
            .build(&self.ensemble, input, &mut self.grouped)?;
        let q = input.y.len();
        let e = &mut self.engine;
        let wmin = self
            .groups
            .weights()
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let out_noise = self.ensemble.output_noise();
        for c in 0..q {
            e.noise[c] = out_noise[c] / wmin.sqrt();
        }
        if e.noise[..q].iter().any(|v| !v.is_finite()) {
            sizing::tail_noise(&self.grouped, &mut e.noise[..q]);
        }
        Ok(())
    }

    /// Leave-one-pulse-out re-identifications of the last model (its order, Hankel size and
    /// SVD path; `base` the pole pair to match), then the jackknife std. Needs at least two
    /// kept pulses (else the uncertainty stays NaN).
    fn jackknife(
        &mut self,
        input: &PulseInput<'_>,
        base: Option<(C64, C64)>,
    ) -> Result<(), IdentError> {
        if self.ensemble.kept() < 2 {
            return Ok(());
        }
        let e = &mut self.engine;
        let mut count = 0;
        for i in 0..self.ensemble.pulses().len() {
            if !self.ensemble.pulses()[i].kept {
                continue;
            }
            self.groups.leave_one_out(
                &self.ensemble,
                input,
                i,
                &mut self.jk_markov,
                &mut self.jk_weights,
            )?;
            let w = &self.jk_weights[..self.groups.groups()];
            e.jackknife_one(
                &self.jk_markov,
                count,
                self.groups.widths(),
                w,
                self.groups.d(),
                base,
            )?;
            count += 1;
        }
        e.finish_jackknife(count);
        Ok(())
    }

    /// Identifies from given Markov parameters (`Y_0 = D`, `Y_k = C A^(k-1) B`), e.g. from
    /// OKID. The noise floor is the RMS of the sequence's last quarter. No heap allocation.
    pub fn identify_markov(
        &mut self,
        markov: &MarkovSeq,
        dt_s: f64,
        opts: &IdentOptions,
    ) -> Result<&Model, IdentError> {
        let l = &self.limits;
        let (q, p, len) = (markov.outputs(), markov.inputs(), markov.len());
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(IdentError::InvalidInput("dt_s must be finite and > 0"));
        }
        for (what, value, limit) in [
            ("outputs", q, l.max_outputs),
            ("inputs", p, l.max_inputs),
            ("Markov blocks", len, l.max_samples),
        ] {
            if value > limit {
                return Err(IdentError::LimitsExceeded { what, value, limit });
            }
        }
        if let Some(pos) = markov.as_slice().iter().position(|v| !v.is_finite()) {
            let blk = pos / (q * p);
            return Err(IdentError::NonFinite {
                signal: "markov",
                channel: pos % (q * p),
                sample: blk,
            });
        }
        if markov.as_slice().iter().skip(q * p).all(|v| *v == 0.0) {
            return Err(IdentError::ConstantOutput { channel: 0 });
        }
        let e = &mut self.engine;
        sizing::tail_noise(markov, &mut e.noise[..q]);
        let rms = (e.noise[..q].iter().map(|s| s * s).sum::<f64>() / q as f64).sqrt();
        e.run(markov, dt_s, &[], false, opts)?;
        e.model.finish_gain()?;
        e.model.pulses = 0;
        e.model.skipped = 0;
        e.model.noise_rms = rms;
        Ok(&self.engine.model)
    }
}

impl Engine {
    fn new(l: &Limits) -> Self {
        let pmax = max_p(l);
        let rows = l.max_block_rows * l.max_outputs;
        let cols = l.max_block_cols * pmax;
        let wide = rows.min(cols);
        let (dense_rows, dense_cols) = (rows.min(svd::DENSE_MAX_DIM), cols.min(svd::DENSE_MAX_DIM));
        let kmax = (l.max_order + EXTRA_TRIPLETS).min(wide).max(1);
        let n = l.max_order;
        Self {
            limits: *l,
            kmax,
            dense_rows,
            dense_cols,
            hbuf: vec![0.0; dense_rows * dense_cols],
            dense: DenseSvd::new(dense_rows, dense_cols),
            trunc: TruncatedSvd::new(
                l.max_block_rows,
                l.max_block_cols,
                l.max_outputs,
                pmax,
                kmax,
            ),
            sub: SubspaceSvd::new(rows, cols, kmax),
            u: vec![0.0; rows * kmax],
            v: vec![0.0; cols * kmax],
            jk_sigma: vec![0.0; kmax],
            jk_u: vec![0.0; rows * kmax],
            jk_v: vec![0.0; cols * kmax],
            era_scratch: vec![0.0; rows * n],
            noise: vec![0.0; l.max_outputs],
            lite: Lite {
                a: vec![0.0; n * n],
                b: vec![0.0; n * pmax],
                c: vec![0.0; l.max_outputs * n],
                d: vec![0.0; l.max_outputs * pmax],
                m: vec![0.0; n * n],
                s: vec![0.0; n * n],
                nrm: vec![0.0; n * n],
                b1: vec![0.0; n],
                x: vec![0.0; n * pmax],
                poles: vec![C64::new(0.0, 0.0); n],
                dc: vec![0.0; l.max_outputs * pmax],
            },
            theta_fn: vec![0.0; l.max_pulses],
            theta_zeta: vec![0.0; l.max_pulses],
            theta_dc: vec![0.0; l.max_pulses * l.max_outputs],
            model: Model::new(n, l.max_outputs, pmax, wide),
        }
    }

    /// Order checks, Hankel size and SVD path of `markov` (the first part of `run`); `pulse`
    /// stretches the automatic Hankel span past the noise crossing ([`sizing::pulse_span`]).
    fn plan(
        &self,
        markov: &MarkovSeq,
        growth: &[f64],
        pulse: bool,
        opts: &IdentOptions,
    ) -> Result<(HankelDims, SvdPath), IdentError> {
        let l = self.limits;
        let (q, p, len) = (markov.outputs(), markov.inputs(), markov.len());
        if let Some(n) = opts.order {
            if n == 0 {
                return Err(IdentError::InvalidInput("order must be >= 1"));
            }
            if n > l.max_order {
                return Err(IdentError::LimitsExceeded {
                    what: "order",
                    value: n,
                    limit: l.max_order,
                });
            }
        }
        let avail = len.saturating_sub(1);
        let dims = match opts.hankel_blocks {
            Some((r, c)) => {
                sizing::explicit_dims(q, p, r, c, avail, l.max_block_rows, l.max_block_cols)?
            }
            None => {
                let mut signal = sizing::signal_length(markov, &self.noise[..q], growth);
                if pulse {
                    signal = sizing::pulse_span(signal, len);
                }
                if signal == 0 {
                    return Err(IdentError::RankDeficient {
                        rank: 0,
                        order: opts.order.unwrap_or(0),
                    });
                }
                let min_size = opts.order.map_or(3, |n| n + 1);
                sizing::hankel_dims(
                    q,
                    p,
                    avail,
                    signal,
                    min_size,
                    l.max_block_rows,
                    l.max_block_cols,
                )?
            }
        };
        let (rows, cols) = (dims.rows(), dims.cols());
        let wide = rows.min(cols);
        if let Some(n) = opts.order {
            if n > wide {
                return Err(IdentError::OrderTooHigh {
                    order: n,
                    max: wide,
                });
            }
        }
        let path = svd::resolve(opts.svd, rows, cols, self.dense_rows, self.dense_cols)?;
        Ok((dims, path))
    }

    /// Sizing ([`plan`](Self::plan)), SVD, order, realisation and modal analysis of `markov`.
    fn run(
        &mut self,
        markov: &MarkovSeq,
        dt_s: f64,
        growth: &[f64],
        pulse: bool,
        opts: &IdentOptions,
    ) -> Result<(), IdentError> {
        let l = self.limits;
        let (q, p) = (markov.outputs(), markov.inputs());
        let (dims, path) = self.plan(markov, growth, pulse, opts)?;
        let (rows, cols) = (dims.rows(), dims.cols());
        let wide = rows.min(cols);
        let k = self.kmax.min(wide);
        let mut converged = k;
        match path {
            SvdPath::Dense => {
                let m = &mut self.model;
                dims.fill(markov.as_slice(), 0, &mut self.hbuf);
                self.dense.compute(
                    &self.hbuf,
                    rows,
                    cols,
                    k,
                    &mut m.sigma,
                    &mut self.u,
                    &mut self.v,
                )?;
                m.n_sigma = wide;
            }
            SvdPath::Truncated => {
                converged = self.truncated_svd(markov, dims, k, opts.order.unwrap_or(1))?;
            }
        }
        let pooled = (self.noise[..q]
            .iter()
            .map(|s| if s.is_finite() { s * s } else { 0.0 })
            .sum::<f64>()
            / q as f64)
            .sqrt();
        let noise_sv = sizing::noise_singular_value(pooled, &dims, growth);
        let sig = &self.model.sigma[..self.model.n_sigma];
        let n = match opts.order {
            Some(n) => {
                let rank = sizing::auto_order(sig, 0.0, wide);
                if rank < n {
                    return Err(IdentError::RankDeficient { rank, order: n });
                }
                n
            }
            None => sizing::auto_order(sig, noise_sv, l.max_order.min(k)),
        };
        if n == 0 {
            return Err(IdentError::RankDeficient { rank: 0, order: 0 });
        }
        if n > converged {
            // The automatic order reached past the triplets that had converged: ask for them.
            self.truncated_svd(markov, dims, k, n)?;
        }
        self.h1v(markov, dims, n, path, false)?;
        let m = &mut self.model;
        m.n = n;
        m.q = q;
        m.p = p;
        m.dt_s = dt_s;
        m.dims = dims;
        m.path = path;
        m.std_fn = f64::NAN;
        m.std_zeta = f64::NAN;
        m.std_dc.fill(f64::NAN);
        realize(
            markov.as_slice(),
            &dims,
            n,
            &m.sigma,
            &self.u,
            &self.v,
            &self.era_scratch,
            &mut m.a,
            &mut m.b,
            &mut m.c,
            &mut m.d,
        );
        m.analyse_modes(&self.u, &self.v)
    }

    /// Leading `k` triplets by the truncated (FFT + Lanczos) SVD, at least `need` converged;
    /// the rest are Ritz estimates for the order choice. Returns how many converged.
    fn truncated_svd(
        &mut self,
        markov: &MarkovSeq,
        dims: HankelDims,
        k: usize,
        need: usize,
    ) -> Result<usize, IdentError> {
        let m = &mut self.model;
        let (q, p) = (dims.q, dims.p);
        let got = self
            .trunc
            .compute_at_least(
                markov.as_slice(),
                q,
                p,
                dims.r,
                dims.c,
                0,
                k,
                need.min(k),
                &mut m.sigma[..k],
                &mut self.u,
                &mut self.v,
            )
            .map_err(svd::SvdError::from)?;
        m.n_sigma = k;
        Ok(got)
    }

    /// `era_scratch = H(1) V_n` (of the jackknife's `V` when `jk`), by FFT products on the
    /// truncated path and direct products on the dense one.
    fn h1v(
        &mut self,
        markov: &MarkovSeq,
        dims: HankelDims,
        n: usize,
        path: SvdPath,
        jk: bool,
    ) -> Result<(), IdentError> {
        let (rows, cols) = (dims.rows(), dims.cols());
        let v = if jk { &self.jk_v } else { &self.v };
        match path {
            SvdPath::Dense => h1_times_v(markov.as_slice(), &dims, n, v, &mut self.era_scratch),
            SvdPath::Truncated => {
                for l in 0..n {
                    self.trunc
                        .apply(
                            markov.as_slice(),
                            dims.q,
                            dims.p,
                            dims.r,
                            dims.c,
                            1,
                            &v[l * cols..(l + 1) * cols],
                            &mut self.era_scratch[l * rows..(l + 1) * rows],
                        )
                        .map_err(svd::SvdError::from)?;
                }
            }
        }
        Ok(())
    }

    /// Converts the realised per-width input matrices `B̃_g` into the single input `B` and
    /// sets `D` ([`crate::grouped`]).
    fn single_input(
        &mut self,
        widths: &[usize],
        weights: &[f64],
        d: &[f64],
    ) -> Result<(), IdentError> {
        let m = &mut self.model;
        let n = m.n;
        let lt = &mut self.lite;
        if !input_matrix(
            &m.a,
            n,
            &m.b,
            widths,
            weights,
            &mut lt.m,
            &mut lt.s,
            &mut lt.nrm,
            &mut lt.b1,
        ) {
            return Err(IdentError::InvalidInput(
                "the pulse widths cannot excite a pole of the model: B is not identifiable",
            ));
        }
        m.set_single_input(&lt.b1, d);
        Ok(())
    }

    /// Re-identifies the leave-one-out sequence at the model's order and Hankel size and
    /// stores fn, ζ and the DC gains as estimate number `slot`. On the truncated path only the
    /// `n` triplets the realisation uses are computed, converged to the SVD's tolerance (no
    /// extra Ritz values: the order is fixed), with the sign-free final small SVD.
    fn jackknife_one(
        &mut self,
        markov: &MarkovSeq,
        slot: usize,
        widths: &[usize],
        weights: &[f64],
        d: &[f64],
        base: Option<(C64, C64)>,
    ) -> Result<(), IdentError> {
        let m = &self.model;
        let (n, q, dims) = (m.n, m.q, m.dims);
        let b = (n + EXTRA_TRIPLETS)
            .min(self.kmax)
            .min(dims.rows().min(dims.cols()));
        let path = m.path;
        match path {
            SvdPath::Dense => self.sub.compute(
                markov.as_slice(),
                dims,
                b,
                JACKKNIFE_ITERS,
                &self.v,
                &mut self.jk_sigma,
                &mut self.jk_u,
                &mut self.jk_v,
            )?,
            SvdPath::Truncated => {
                // fn, ζ and the DC gain do not depend on the signs of the singular vectors.
                self.trunc.set_sign_free(true);
                let r = self.trunc.compute_at_least(
                    markov.as_slice(),
                    dims.q,
                    dims.p,
                    dims.r,
                    dims.c,
                    0,
                    n,
                    n,
                    &mut self.jk_sigma[..n],
                    &mut self.jk_u,
                    &mut self.jk_v,
                );
                self.trunc.set_sign_free(false);
                r.map_err(svd::SvdError::from)?;
            }
        }
        self.h1v(markov, dims, n, path, true)?;
        let lt = &mut self.lite;
        realize(
            markov.as_slice(),
            &dims,
            n,
            &self.jk_sigma,
            &self.jk_u,
            &self.jk_v,
            &self.era_scratch,
            &mut lt.a,
            &mut lt.b,
            &mut lt.c,
            &mut lt.d,
        );
        let m = &self.model;
        lt.m[..n * n].copy_from_slice(&lt.a[..n * n]);
        eigenvalues(&mut lt.m, n, &mut lt.poles)?;
        let (f, z) = match base {
            Some(base) => {
                let (s1, s2) = closest_pair(&lt.poles[..n], base, m.dt_s);
                fn_zeta(s1, s2)
            }
            None => (f64::NAN, f64::NAN),
        };
        self.theta_fn[slot] = f;
        self.theta_zeta[slot] = z;
        let ok = input_matrix(
            &lt.a,
            n,
            &lt.b,
            widths,
            weights,
            &mut lt.m,
            &mut lt.s,
            &mut lt.nrm,
            &mut lt.b1,
        );
        if ok {
            dc_gain(
                &lt.a, &lt.b1, &lt.c, d, n, q, 1, &mut lt.m, &mut lt.x, &mut lt.dc,
            );
        } else {
            lt.dc[..q].fill(f64::NAN);
        }
        for i in 0..q {
            self.theta_dc[slot * self.limits.max_outputs + i] = lt.dc[i];
        }
        Ok(())
    }

    fn finish_jackknife(&mut self, count: usize) {
        let m = &mut self.model;
        m.std_fn = jackknife_std(&self.theta_fn[..count]);
        m.std_zeta = jackknife_std(&self.theta_zeta[..count]);
        let mq = self.limits.max_outputs;
        for i in 0..m.q {
            let vals = (0..count).map(|s| self.theta_dc[s * mq + i]);
            m.std_dc[i] = strided_jackknife(vals, count);
        }
    }
}

/// Most input columns the engine handles: the inputs of given Markov parameters, or one
/// column per pulse width on the pulse path.
fn max_p(l: &Limits) -> usize {
    l.max_inputs.max(MAX_GROUPS)
}

/// [`jackknife_std`] over an iterator (no allocation).
fn strided_jackknife(vals: impl Iterator<Item = f64> + Clone, n: usize) -> f64 {
    if n < 2 || vals.clone().any(|v| !v.is_finite()) {
        return f64::NAN;
    }
    let mean = vals.clone().sum::<f64>() / n as f64;
    let ss: f64 = vals.map(|v| (v - mean) * (v - mean)).sum();
    ((n - 1) as f64 / n as f64 * ss).sqrt()
}

/// The pole pair (as continuous poles) closest to `base`.
fn closest_pair(poles: &[C64], base: (C64, C64), dt: f64) -> (C64, C64) {
    let n = poles.len();
    let mut best = (C64::new(f64::NAN, 0.0), C64::new(f64::NAN, 0.0));
    let mut err = f64::INFINITY;
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            let (s1, s2) = (continuous(poles[i], dt), continuous(poles[j], dt));
            let e = (s1 - base.0).norm() + (s2 - base.1).norm();
            if e < err {
                err = e;
                best = (s1, s2);
            }
        }
    }
    best
}
