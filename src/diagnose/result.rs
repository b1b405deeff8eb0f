//! What `diagnose` publishes (the JSON of `propid diagnose --json`, issue 5). The models are
//! summarised in [`super::summary`].

use serde::Serialize;
use serde_json::{Map, Value};

use super::summary::ModelSummary;

/// A model with its validation fit.
#[derive(Debug, Clone, Serialize)]
pub struct Stage {
    /// The model.
    pub model: ModelSummary,
    /// `100 (1 − ‖y − ŷ‖ / ‖y − mean y‖)` on the validation samples.
    pub fit_percent: f64,
    /// The identification core's own model of the estimation part (ERA / OKID, what
    /// `propid identify` publishes) and its validation fit; absent when the core refused.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub core_model: Option<super::era_start::EraBaseline>,
}

/// The extended model.
#[derive(Debug, Clone, Serialize)]
pub struct Extended {
    /// Names of the effects it includes, in the order found.
    pub effects: Vec<String>,
    /// The model.
    pub model: ModelSummary,
    /// Validation fit, percent.
    pub fit_percent: f64,
}

/// One named effect.
#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    /// Effect name (one of [`super::effects::REGISTRY`]).
    pub effect: String,
    /// Test statistic `n ln(SSE_before / SSE_after)` (larger is stronger evidence).
    pub score: f64,
    /// The evidence in words.
    pub evidence: String,
    /// The effect's parameter estimates (`delay_s`, `exponent`, `fn_hz`, ...).
    #[serde(flatten)]
    pub params: Map<String, Value>,
}

/// What the extension gained on the validation samples.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Gain {
    /// `fit_extended − fit_baseline`, percentage points.
    pub fit_percent_points: f64,
    /// `RMS(residual extended) / RMS(residual baseline)`, both residuals of the simulation
    /// over the same held-out validation samples (missing outputs skipped).
    pub rms_ratio: f64,
}

/// Which samples were used for what (half-open ranges of sample indices).
#[derive(Debug, Clone, Serialize)]
pub struct Split {
    /// Samples the models were fitted on, `[first, end)`.
    pub estimation: [usize; 2],
    /// Held-out samples the fits are measured on, `[first, end)`.
    pub validation: [usize; 2],
}

/// The whole diagnosis (`propid diagnose --json`).
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosis {
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
    /// The noise floor measured from the data (null when none could be measured).
    pub noise_floor: Option<super::noise::NoiseFloor>,
    /// Residual RMS of the models on the validation samples.
    pub residual: super::verdict::Residual,
    /// Is the final residual at the noise floor ([`super::verdict`]).
    pub verdict: super::verdict::Verdict,
    /// Implausible results of the published models.
    pub warnings: Vec<super::verdict::Warning>,
    /// Fitted models and predictions, for reports (not serialised).
    #[serde(skip)]
    pub traces: Traces,
}

/// Measured and simulated outputs over the whole record, for plots.
#[derive(Debug, Clone, Default)]
pub struct Traces {
    /// Sample period, seconds.
    pub dt_s: f64,
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
}
