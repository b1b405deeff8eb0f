//! What the model, the fit and the published JSON need from an effect's fitted parameters: the
//! [`Term`] trait, where a term acts on the signal path ([`Place`]) and how the fit moves its
//! free parameters ([`Scale`]). Each effect's parameter struct (in its file under
//! [`crate::effects`]) implements it: its values (names and units in the struct's doc), where
//! and how they act, which of them the fit adjusts, when they are plausible, what is published
//! (the model's `terms`, the finding's parameters) and the evidence in words.

use propid_numerics::nonlinear_core::CoreLaw;
use propid_numerics::EffectName;
use serde::Serialize;
use serde_json::{Map, Value};

use crate::ctx::Ctx;
use crate::linear_part::LinearPart;
use crate::signals::{Core, Signals};

/// Where along the signal path a term acts. The model applies the places in this order, and
/// terms at the same place in registry order:
///
/// ```text
///   u → InputShift → InputLimit → InputMap → InputScale → × K → core (with the Core
///     terms' law) → Series → × output scales → + offset → OutputAdd → OutputLimit → ŷ
/// ```
///
/// The output scales are every term's [`Term::scale_output`] (a term that scales the core's
/// output by a measured signal, whatever its place: the supply sag's share on the output).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Place {
    /// Shifts the input in time (first: every other input term sees the shifted input).
    InputShift,
    /// Limits the input.
    InputLimit,
    /// A static map of the input.
    InputMap,
    /// Scales the input by another measured signal.
    InputScale,
    /// Changes the core's own law (a cubic restoring term, a time scale per direction):
    /// [`Term::core_law`].
    Core,
    /// A linear element in series after the core (adds states to the linear part).
    Series,
    /// A term added to the output, independent of it (of the core's gain and offset too).
    OutputAdd,
    /// Limits the output (the last step; left out of the linear least squares).
    OutputLimit,
}

impl Place {
    /// Every place, in signal-path order.
    pub const ALL: [Place; 8] = [
        Place::InputShift,
        Place::InputLimit,
        Place::InputMap,
        Place::InputScale,
        Place::Core,
        Place::Series,
        Place::OutputAdd,
        Place::OutputLimit,
    ];

    /// True for the places before the core's gain.
    pub fn is_input(self) -> bool {
        self < Place::Core
    }
}

/// How the fit moves a free parameter: frequencies and damping ratios in logarithm (they stay
/// positive), everything else as is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Adjusted as is.
    Linear,
    /// Adjusted in logarithm.
    Log,
}

/// A term as [`std::any::Any`], so that a reader outside the crate (the model file,
/// `propid-model`) can tell each effect's parameter struct from the others.
pub trait AsAny {
    /// `self` as `Any`.
    fn as_any(&self) -> &dyn std::any::Any;
}

impl<T: std::any::Any> AsAny for T {
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

/// The fitted parameters of one effect inside a model .
pub trait Term: AsAny + std::fmt::Debug + Send + Sync {
    /// The effect's published name (the same as its [`Effect::name`]).
    fn name(&self) -> EffectName;

    /// Where it acts on the signal path.
    fn place(&self) -> Place;

    /// A boxed copy (models are copied for every start of a fit).
    fn clone_box(&self) -> Box<dyn Term>;

    /// Whether these fitted values, in a fitted model with core `core` (`has_nan`: a free
    /// parameter of that model is NaN), are physically plausible (fits that leave the
    /// plausible ranges are numerical artefacts, not findings). Default: no free parameter of
    /// the model is NaN.
    fn plausible(&self, _ctx: &Ctx, _core: &Core, has_nan: bool) -> bool {
        !has_nan
    }

    /// Samples by which the measured supply voltage reaches the input terms late: the part of
    /// a dead time that lies on the output's side (a load cell's filter, a logger's buffer) and
    /// so delays what the voltage acts on as much as the throttle ([`crate::model::simulate`]
    /// shifts the voltage by the largest of these). Default 0.
    fn voltage_delay(&self) -> usize {
        0
    }

    /// Samples by which the term delays the throttle (a dead time's); default 0.
    fn input_delay(&self) -> usize {
        0
    }

    /// A copy with `samples` of its delay (at most all of it) on the output's side
    /// ([`Term::voltage_delay`]); `None` (the default) for a term without a delay.
    fn with_voltage_delay(&self, _samples: usize) -> Option<Box<dyn Term>> {
        None
    }

    /// The shares of its delay tried on the output's side, samples, ascending from none to all
    /// of it ([`Term::with_voltage_delay`]); empty (the default) for a term without a delay.
    fn voltage_delay_shares(&self) -> Vec<usize> {
        Vec::new()
    }

    /// A copy whose delay is one sample shorter on both sides (a whole sample of the core's
    /// input lead taken into it: [`crate::lead::canonical`]); `None` (the default) for a term
    /// without a delay.
    fn one_sample_shorter(&self) -> Option<Box<dyn Term>> {
        None
    }

    /// Whether the term reads the measured supply voltage (then the share of a dead time on the
    /// output's side, [`Term::voltage_delay`], changes the model). Default: no.
    fn reads_voltage(&self) -> bool {
        false
    }

    /// Input places: transforms the input path `v` (one value per sample, the throttle before
    /// the core's gain) in place.
    fn shape_input(&self, _v: &mut [f64], _sig: &Signals) {}

    /// [`Place::Core`]: sets this term's part of the core's law (its cubic stiffness or its
    /// time scale per direction; [`propid_numerics::nonlinear_core`]).
    fn core_law(&self, _law: &mut CoreLaw) {}

    /// [`Place::Series`]: filters the core's output `s` in place.
    fn filter(&self, _s: &mut [f64], _dt_s: f64) {}

    /// Output places: transforms the output `y` (one value per sample) in place.
    fn shape_output(&self, _y: &mut [f64], _sig: &Signals) {}

    /// Any place: scales the core's output `y` (after the series terms, before the offset, so
    /// that the output stays affine in the core's gain and offset) in place; `sig` carries the
    /// voltage as late as the input terms see it ([`Term::voltage_delay`]). Default: nothing.
    fn scale_output(&self, _y: &mut [f64], _sig: &Signals) {}

    /// The frequency band `[lo, hi]`, Hz, an additive narrowband output term lives in (a drift
    /// near 0 Hz, a sinusoid about its frequency) over `n` estimation samples, for the search's
    /// local test ([`crate::revise::passes`]). `None` (the default): the term is tested
    /// against the whole residual only.
    fn band_hz(&self, _n: usize, _dt_s: f64) -> Option<[f64; 2]> {
        None
    }

    /// The parameters the fit adjusts, in a fixed order, with how it moves each (delays and
    /// clip levels are searched on grids by the effect itself and are not listed).
    fn free(&self) -> Vec<(f64, Scale)> {
        Vec::new()
    }

    /// Sets the free parameters, in the order of [`Term::free`].
    fn set_free(&mut self, _values: &[f64]) {}

    /// How many output terms enter linearly (`ŷ += Σ θ_j φ_j(t)`), solved by least squares with
    /// the core's gain and offset ([`crate::fit::linear_refit`]).
    fn linear_count(&self) -> usize {
        0
    }

    /// The regressors `φ_j(t)` at time `t` seconds, into `row` (`linear_count` values).
    fn linear_row(&self, _t_s: f64, _row: &mut [f64]) {}

    /// Sets the linear coefficients `θ_j` (`linear_count` values).
    fn set_linear(&mut self, _theta: &[f64]) {}

    /// Small-signal gain of an input term at the reference operating point (1 for none): the
    /// published DC gain is the core's gain times the product of these.
    fn dc_slope(&self) -> f64 {
        1.0
    }

    /// [`Place::Series`]: appends its states to the published linear part (`A`, `B`, `C`,
    /// continuous poles).
    fn extend_linear(&self, _lin: &mut LinearPart, _dt_s: f64) {}

    /// Writes its entries of the model's published `terms` (`delay_samples`, `exponent`, ...).
    fn terms(&self, dt_s: f64, terms: &mut Map<String, Value>);

    /// The finding's published parameters (`delay_s`, `exponent`, `fn_hz`, ...).
    fn finding_params(&self, dt_s: f64) -> Map<String, Value>;

    /// The evidence in words; `core` is the fitted model's core, `drop` the sentence on how
    /// much the estimation residual fell with the effect.
    fn evidence(&self, core: &Core, ctx: &Ctx, drop: &str) -> String;
}

impl Clone for Box<dyn Term> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// A serialisable value as a JSON object (keys sorted, as every published map); empty for
/// anything that is not an object.
pub fn to_map(v: impl Serialize) -> Map<String, Value> {
    match serde_json::to_value(v) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    }
}
