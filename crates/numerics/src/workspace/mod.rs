//! The allocation-free identification entry point: a [`Workspace`] built once from [`Limits`]
//! holds every buffer; [`Workspace::identify`] (pulse experiments) and
//! [`Workspace::identify_markov`] (given Markov parameters, e.g. from OKID) fill its
//! [`Model`] without touching the heap (proven by `tests/alloc/`).
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
//!
//! The workspace holds the buffers and runs the steps in order; each step is its own module:
//! pulses and per-width responses ([`crate::pulses`], [`crate::grouped`]), noise floor, Hankel
//! size and order ([`crate::order`]), SVD and realisation ([`crate::era`]), modal analysis
//! ([`Model`]), jackknife ([`crate::uncertainty`]). `engine` sequences ERA, `jackknife` the
//! leave-one-out re-identifications.

mod engine;
mod jackknife;
pub mod limits;

pub use limits::Limits;

use engine::{max_p, Engine};

use super::grouped::{WidthGroups, MAX_GROUPS};
use super::model::Model;
use super::order::noise_floor;
use super::pulses::{PulseEnsemble, PulseInput};
use super::stabilization::{self, StabOptions, Stabilization};
use super::svd::{SvdChoice, SvdPath};
use super::{IdentError, MarkovSeq};

type C64 = nalgebra::Complex<f64>;

/// Most Hankel block rows (and columns) a workspace sized from its data is given for an
/// automatically sized Hankel (`propid identify` from the record, the daemon from its window):
/// the automatic span covers the pulse response above the noise ([`crate::order`]), which at
/// 20 kHz is ~2 000 lags for a 12 Hz plant, far past the default 128 blocks (a Hankel over the
/// first 12.8 ms of a 100 ms response gave fn 8 Hz ± 7 Hz for 12 Hz). The cap bounds the
/// singular-vector buffers (`blocks × (order + 4)` doubles each: 1 MB at 8192 blocks).
pub const AUTO_MAX_BLOCKS: usize = 8192;

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
    /// `order` is an automatic rule's count of singular values above the noise (OKID's: its
    /// noise floor is known only after the regression), not the caller's: a ceiling that
    /// steps down like an automatic order ([`crate::order::model_order::settled_order`]).
    pub order_is_a_ceiling: bool,
}

impl Default for IdentOptions {
    fn default() -> Self {
        Self {
            order: None,
            svd: SvdChoice::Auto,
            hankel_blocks: None,
            max_pulse_width: crate::segment::SegmentRules::DEFAULT.max_pulse_samples,
            jackknife: true,
            order_is_a_ceiling: false,
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
    /// What the SVD in the engine decomposed: the model's, from pulses or given Markov
    /// parameters (`None`: no model, or the SVD no longer the model's).
    era_of: Option<EraOf>,
}

/// Which Markov sequence the last model's ERA ran on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum EraOf {
    /// The per-width pulse responses of [`Workspace::identify_model`].
    Pulses,
    /// The sequence given to [`Workspace::identify_markov`].
    Given,
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
            era_of: None,
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

    /// The pulses, baselines and average of the last pulse identification (the pulses each
    /// response window starts at; for plots of the measured responses around the model).
    pub fn ensemble(&self) -> &crate::pulses::PulseEnsemble {
        &self.ensemble
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
        self.era_of = None;
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
        e.run(&self.grouped, input.dt_s, self.groups.growth(), true, opts)?;
        e.single_input(self.groups.widths(), self.groups.weights(), self.groups.d())?;
        e.model.finish_gain()?;
        e.model.pulses = self.ensemble.kept();
        e.model.skipped = self.ensemble.skipped();
        e.model.missing_samples = count_missing(input.missing);
        e.model.noise_rms = rms;
        self.era_of = Some(EraOf::Pulses);
        Ok(&self.engine.model)
    }

    /// The stabilization diagram ([`crate::stabilization`]) of the last pulse identification
    /// ([`identify`](Self::identify), [`identify_model`](Self::identify_model)), realised from
    /// that model's own Hankel SVD at every order. Allocates; not for the hot path.
    pub fn stabilization(&mut self, opts: &StabOptions) -> Result<Stabilization, IdentError> {
        if self.era_of != Some(EraOf::Pulses) {
            return Err(IdentError::InvalidInput(
                "stabilization: no pulse model in this workspace",
            ));
        }
        self.engine.stabilization(&self.grouped, opts)
    }

    /// [`stabilization`](Self::stabilization) of the last
    /// [`identify_markov`](Self::identify_markov); `markov` must be the sequence it was given.
    pub fn stabilization_markov(
        &mut self,
        markov: &MarkovSeq,
        opts: &StabOptions,
    ) -> Result<Stabilization, IdentError> {
        if self.era_of != Some(EraOf::Given) {
            return Err(IdentError::InvalidInput(
                "stabilization: no model from given Markov parameters in this workspace",
            ));
        }
        self.engine.stabilization(markov, opts)
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
        self.era_of = None;
        self.prepare_pulses(input, opts)?;
        let (dims, path) = self
            .engine
            .plan(&self.grouped, self.groups.growth(), true, opts)?;
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
        noise_floor::pulse_noise(
            self.ensemble.output_noise(),
            self.groups.weights(),
            &self.grouped,
            &mut self.engine.noise[..q],
        );
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
        self.era_of = None;
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
        noise_floor::tail_noise(markov, &mut e.noise[..q]);
        let rms = (e.noise[..q].iter().map(|s| s * s).sum::<f64>() / q as f64).sqrt();
        e.run(markov, dt_s, &[], false, opts)?;
        e.model.finish_gain()?;
        e.model.pulses = 0;
        e.model.skipped = 0;
        e.model.missing_samples = 0;
        e.model.noise_rms = rms;
        self.era_of = Some(EraOf::Given);
        Ok(&self.engine.model)
    }
}

impl Engine {
    /// The stabilization diagram of the model from the SVD of `markov` still in [`Era`]
    /// ([`stabilization::from_era`]).
    ///
    /// [`Era`]: crate::era::Era
    fn stabilization(
        &mut self,
        markov: &MarkovSeq,
        opts: &StabOptions,
    ) -> Result<Stabilization, IdentError> {
        let m = &self.model;
        let sigma = &m.sigma[..m.n_sigma];
        let plan = (m.dims, m.path);
        stabilization::from_era(&mut self.era, markov, plan, sigma, m.dt_s, m.n, opts)
    }
}

/// Samples marked missing in a mask (an empty mask marks none).
pub fn count_missing(missing: &[bool]) -> usize {
    missing.iter().filter(|m| **m).count()
}
