//! What `diagnose` publishes (the JSON of `propid diagnose --json`, issue 5). The models are
//! summarised in [`super::summary`].

use propid_numerics::EffectName;
use serde::Serialize;

use super::finding::Finding;
use super::summary::ModelSummary;

/// A model with its validation fit.
#[derive(Debug, Clone, Serialize)]
pub struct Stage {
    /// Which baseline the record got and why (`kind`: `stand` or `generic`, `why`).
    #[serde(flatten)]
    pub choice: super::stand::BaselineChoice,
    /// The model.
    pub model: ModelSummary,
    /// The held-out figure: the mean over the validation folds of
    /// `100 (1 − ‖y − ŷ‖ / ‖y − mean y‖)` on each fold ([`Validation`]).
    pub fit_percent: f64,
    /// The identification core's own model of the estimation part (ERA / OKID, what
    /// `propid identify` publishes) and its fit on the validation samples (in-sample under
    /// blocked cross-validation: the core is not refitted per fold); absent when the core
    /// refused.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub core_model: Option<super::era_start::EraBaseline>,
}

/// The extended model.
#[derive(Debug, Clone, Serialize)]
pub struct Extended {
    /// Names of the effects it includes, in the order found.
    pub effects: Vec<EffectName>,
    /// The model.
    pub model: ModelSummary,
    /// The held-out figure (as the baseline's), percent.
    pub fit_percent: f64,
}

/// What the extension gained on the validation samples.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Gain {
    /// `fit_extended − fit_baseline` (held-out figures), percentage points.
    pub fit_percent_points: f64,
    /// `RMS(residual extended) / RMS(residual baseline)`, both held-out residuals over the
    /// same samples (each fold's prediction by the model refitted without it; missing outputs
    /// skipped).
    pub rms_ratio: f64,
}

/// Which samples were used for what (half-open ranges of sample indices).
#[derive(Debug, Clone, Serialize)]
pub struct Split {
    /// Samples the published models were fitted on, `[first, end)` (every sample under
    /// blocked cross-validation).
    pub estimation: [usize; 2],
    /// Samples held out, `[first, end)`: the tail under `holdout`; every sample (each in one
    /// fold) under `blocked_cv`.
    pub validation: [usize; 2],
}

/// How the held-out figures were measured ([`super::folds`]).
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    /// `blocked_cv` (folds of whole command levels) or `holdout` (one tail: no steps).
    pub method: super::folds::Method,
    /// Each fold, in order.
    pub folds: Vec<FoldFit>,
    /// Mean of the folds' baseline fits: the baseline's `fit_percent`.
    pub baseline_mean_fit_percent: f64,
    /// Mean of the folds' fits of the final model (the extended one, else the baseline).
    pub mean_fit_percent: f64,
}

impl Validation {
    /// One line for the human summary and the report: how the figure was measured, given
    /// the estimation samples `split`.
    pub fn describe(&self, split: &Split) -> String {
        match self.method {
            super::folds::Method::Holdout => format!(
                "estimation samples {}..{}, validation samples {}..{}",
                split.estimation[0], split.estimation[1], split.validation[0], split.validation[1]
            ),
            super::folds::Method::BlockedCv => {
                let folds: Vec<String> = self
                    .folds
                    .iter()
                    .map(|f| {
                        format!(
                            "{}..{}: {:.1} → {:.1} %",
                            f.samples[0], f.samples[1], f.baseline_fit_percent, f.fit_percent
                        )
                    })
                    .collect();
                format!(
                    "blocked cross-validation over {} folds cut at the command's steps (each refitted without \
                     it and scored on it; baseline → final model): {}",
                    self.folds.len(),
                    folds.join(", ")
                )
            }
        }
    }
}

/// One fold of the validation.
#[derive(Debug, Clone, Serialize)]
pub struct FoldFit {
    /// Its held-out samples, `[first, end)`.
    pub samples: [usize; 2],
    /// Fit of the baseline refitted without the fold, scored on it, percent.
    pub baseline_fit_percent: f64,
    /// Fit of the final model refitted without the fold, scored on it, percent.
    pub fit_percent: f64,
}

/// What the record held (`"source"`; the same names and meaning as `propid identify`'s).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Source {
    /// Samples diagnosed.
    pub samples: usize,
    /// Samples of the output missing in the record (lost, empty cells).
    pub missing: usize,
    /// Isolated outlier samples of the output ([`propid_numerics::outliers`], the command's
    /// changes guarded), left out of every fit, fold and noise floor like missing samples
    /// (never replaced; not counted in `missing`).
    pub outliers: usize,
    /// Samples at the record's start left out as a start-up transient
    /// ([`propid_numerics::startup`]; marked missing, not counted in `missing`); 0 when none.
    pub start_up_transient: usize,
}

/// The whole diagnosis (`propid diagnose --json`).
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosis {
    /// What the record held, its outliers counted.
    pub source: Source,
    /// When the output answers a command within the command's own sample, the lead every
    /// model gives the input ([`super::lead`]); absent for the plain hold.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input_lead: Option<InputLead>,
    /// The 2nd-order model and its validation fit.
    pub baseline: Stage,
    /// The effects found (empty when none).
    pub findings: Vec<Finding>,
    /// The model extended by the findings (null when none).
    pub extended: Option<Extended>,
    /// The gain of the extension (null when none).
    pub gain: Option<Gain>,
    /// Estimation and validation samples.
    pub split: Split,
    /// The held-out figures fold by fold.
    pub validation: Validation,
    /// The noise floor measured from the data (null when none could be measured).
    pub noise_floor: Option<super::noise::NoiseFloor>,
    /// Residual RMS of the models on the validation samples.
    pub residual: super::verdict::Residual,
    /// Is the final residual at the noise floor ([`super::verdict`]).
    pub verdict: super::verdict::Verdict,
    /// Implausible results of the published models.
    pub warnings: Vec<super::verdict::Warning>,
    /// The candidates that fitted in-sample and were not taken, each with its score, held-out
    /// change and reason ([`super::rejected`]); empty when none.
    pub rejected: Vec<super::rejected::Rejected>,
    /// On a stand baseline: every channel's held-out figures and departures and the stand's
    /// figures ([`super::stand`]); absent on the generic baseline.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stand: Option<super::stand::StandDiagnosis>,
    /// On a stand baseline, the calibrated stand ([`Diagnosis::stand_baseline`]).
    #[serde(skip)]
    pub stand_model: Option<super::stand::StandBaseline>,
    /// Fitted models and predictions, for reports (not serialised).
    #[serde(skip)]
    pub traces: Traces,
}

impl Diagnosis {
    /// The calibrated stand (the stand baseline fitted on the estimation part and the model
    /// with every effect found, with the parts of the stand it frees); `None` on the generic
    /// baseline. For a simulated stand's configuration.
    pub fn stand_baseline(&self) -> Option<&super::stand::StandBaseline> {
        self.stand_model.as_ref()
    }
}

/// The input's lead ([`super::lead`]): each input sample acts this long before its row.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct InputLead {
    /// Share of a sample (0..1).
    pub samples: f64,
    /// Seconds.
    pub seconds: f64,
}

/// Measured and simulated outputs over the whole record, for plots.
#[derive(Debug, Clone, Default)]
pub struct Traces {
    /// Sample period, seconds.
    pub dt_s: f64,
    /// The segmentation's rules the diagnosis used ([`crate::ctx::Ctx::rules`]).
    pub rules: propid_numerics::segment::SegmentRules,
    /// Input.
    pub u: Vec<f64>,
    /// Measured output.
    pub y: Vec<f64>,
    /// Baseline simulation.
    pub baseline: Vec<f64>,
    /// Extended simulation (equal to the baseline when nothing was found).
    pub extended: Vec<f64>,
    /// Stabilization diagram of the identification core's ERA start (when it gave one) and
    /// that model's fn and ζ.
    pub stabilization: Option<(propid_numerics::stabilization::Stabilization, f64, f64)>,
    /// The final model (the extended one, else the baseline) as fitted, for a model file.
    pub model: super::model::Model,
    /// The reference throttle and voltage its terms were fitted about
    /// ([`super::signals::Signals::u_ref`], [`super::signals::Signals::v_ref`]).
    pub refs: [f64; 2],
}
