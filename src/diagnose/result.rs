//! What `diagnose` publishes (the JSON of `propid diagnose --json`, issue 5) and how a fitted
//! model is summarised with the field names of `propid identify --json`.

use serde::Serialize;
use serde_json::{json, Map, Value};

use super::fit::Fit;
use super::model::{ix, Spec};
use propid_numerics::modal::mass_spring_damper;
use propid_numerics::report::{
    Gain as ReportGain, MassSpringDamper, ModeIndicators, ModelReport, Uncertainty,
};
use propid_numerics::discretise::discretise_second_order;

/// A fitted model, published with every field of `propid identify --json`'s `"model"`
/// ([`ModelReport`], flattened: same names, same types) plus the terms of the extension
/// (`terms`).
///
/// Where the fields come from:
/// - `order`, `dt_s`, `fn_hz`, `zeta`, `dc_gain`, `time_constants_s`, `poles_s`, `poles_z`,
///   `a`, `b`, `c`, `d`, `mass_spring_damper`: the fitted output-error model itself
///   (`fn_hz`, `zeta` of the 2nd-order core; `mass_spring_damper` = `k = 1/K`, `m = k/ωn²`,
///   `d = 2ζωn m` of that core, [`propid_numerics::modal::mass_spring_damper`]).
/// - `noise_rms`: the RMS of the model's simulation residual on the estimation samples,
///   `√(SSE/n)`.
/// - `singular_values`, `pulses`, `pulses_skipped`, `hankel_block_rows`,
///   `hankel_block_cols`, `svd`: the identification core's run on the estimation part (the ERA /
///   OKID model the baseline started from, `baseline.core_model`). They describe that data's
///   Hankel matrix, not the output-error fit; without a core model: empty, 0 and `"none"`.
/// - `indicators` (ERA's per-mode accuracy indicators) and `uncertainty` (the jackknife over
///   pulses) have no meaning for an output-error model: one entry of nulls per pole, and nulls.
#[derive(Debug, Clone, Serialize)]
pub struct ModelSummary {
    /// The fields of `propid identify --json`'s model.
    #[serde(flatten)]
    pub report: ModelReport,
    /// Output offset and the extension's terms (`delay_samples`, `exponent`, `mode_fn_hz`, ...).
    pub terms: Map<String, Value>,
}

/// Poles of `s² + 2ζωn s + ωn²`.
fn poles(fn_hz: f64, zeta: f64) -> [[f64; 2]; 2] {
    let wn = 2.0 * std::f64::consts::PI * fn_hz;
    if zeta < 1.0 {
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        [[-zeta * wn, wd], [-zeta * wn, -wd]]
    } else {
        let r = wn * (zeta * zeta - 1.0).sqrt();
        [[-zeta * wn + r, 0.0], [-zeta * wn - r, 0.0]]
    }
}

impl ModelSummary {
    /// Summarises a fit on data sampled every `dt_s`; `core` is the identification core's model
    /// of the estimation part (the source of the Hankel fields, see the type's doc).
    pub fn from_fit(fit: &Fit, dt_s: f64, core: Option<&ModelReport>) -> ModelSummary {
        let v = &fit.params.v;
        let spec = &fit.spec;
        let slope = if spec.static_map {
            v[ix::EXPONENT]
        } else {
            1.0
        };
        let k = v[ix::GAIN] * slope;
        let (a2, b2) = discretise_second_order(v[ix::FN], v[ix::ZETA], 1.0, dt_s);
        let mut ps: Vec<[f64; 2]> = poles(v[ix::FN], v[ix::ZETA]).to_vec();
        let (a, b, c) = if spec.extra_mode {
            ps.extend(poles(v[ix::MODE_FN], v[ix::MODE_ZETA]));
            let (am, bm) = discretise_second_order(v[ix::MODE_FN], v[ix::MODE_ZETA], 1.0, dt_s);
            let g = v[ix::MODE_GAIN];
            let a = vec![
                vec![a2[(0, 0)], a2[(0, 1)], 0.0, 0.0],
                vec![a2[(1, 0)], a2[(1, 1)], 0.0, 0.0],
                vec![bm[0], 0.0, am[(0, 0)], am[(0, 1)]],
                vec![bm[1], 0.0, am[(1, 0)], am[(1, 1)]],
            ];
            let b = vec![vec![b2[0] * k], vec![b2[1] * k], vec![0.0], vec![0.0]];
            (a, b, vec![vec![1.0 - g, 0.0, g, 0.0]])
        } else {
            let a = vec![vec![a2[(0, 0)], a2[(0, 1)]], vec![a2[(1, 0)], a2[(1, 1)]]];
            (
                a,
                vec![vec![b2[0] * k], vec![b2[1] * k]],
                vec![vec![1.0, 0.0]],
            )
        };
        let poles_z = ps
            .iter()
            .map(|s| {
                let m = (s[0] * dt_s).exp();
                [m * (s[1] * dt_s).cos(), m * (s[1] * dt_s).sin()]
            })
            .collect();
        let mut tcs: Vec<f64> = ps
            .iter()
            .filter(|s| s[1] == 0.0 && s[0] < 0.0)
            .map(|s| -1.0 / s[0])
            .collect();
        tcs.sort_by(|a, b| b.total_cmp(a));
        let (m, d, kk) = mass_spring_damper(v[ix::FN], v[ix::ZETA], k);
        let null_mode = ModeIndicators {
            msv: f64::NAN,
            mac: f64::NAN,
            emac: f64::NAN,
            mpc: f64::NAN,
            cmi: f64::NAN,
        };
        let report = ModelReport {
            order: spec.order(),
            dt_s,
            fn_hz: v[ix::FN],
            zeta: v[ix::ZETA],
            dc_gain: ReportGain::Scalar(k),
            time_constants_s: tcs,
            indicators: vec![null_mode; ps.len()],
            poles_s: ps,
            poles_z,
            a,
            b,
            c,
            d: vec![vec![0.0]],
            singular_values: core.map_or(Vec::new(), |r| r.singular_values.clone()),
            uncertainty: Uncertainty {
                fn_hz: f64::NAN,
                zeta: f64::NAN,
                dc_gain: ReportGain::Scalar(f64::NAN),
            },
            pulses: core.map_or(0, |r| r.pulses),
            pulses_skipped: core.map_or(0, |r| r.pulses_skipped),
            noise_rms: if fit.n > 0 {
                (fit.sse / fit.n as f64).sqrt()
            } else {
                f64::NAN
            },
            mass_spring_damper: MassSpringDamper { m, d, k: kk },
            hankel_block_rows: core.map_or(0, |r| r.hankel_block_rows),
            hankel_block_cols: core.map_or(0, |r| r.hankel_block_cols),
            svd: core.map_or("none".to_string(), |r| r.svd.clone()),
        };
        ModelSummary {
            report,
            terms: terms(spec, fit, dt_s),
        }
    }
}

fn terms(spec: &Spec, fit: &Fit, dt_s: f64) -> Map<String, Value> {
    let v = &fit.params.v;
    let mut m = Map::new();
    m.insert("offset".into(), json!(v[ix::OFFSET]));
    m.insert("gain".into(), json!(v[ix::GAIN]));
    if spec.delay > 0 {
        m.insert("delay_samples".into(), json!(spec.delay));
        m.insert("delay_s".into(), json!(spec.delay as f64 * dt_s));
    }
    if spec.static_map {
        m.insert("exponent".into(), json!(v[ix::EXPONENT]));
    }
    if spec.extra_mode {
        m.insert("mode_fn_hz".into(), json!(v[ix::MODE_FN]));
        m.insert("mode_zeta".into(), json!(v[ix::MODE_ZETA]));
        m.insert("mode_gain".into(), json!(v[ix::MODE_GAIN]));
    }
    if spec.drift {
        m.insert("drift_per_s".into(), json!(v[ix::DRIFT]));
    }
    if spec.periodic {
        m.insert("periodic_freq_hz".into(), json!(v[ix::SIN_FREQ]));
        m.insert(
            "periodic_amplitude".into(),
            json!(v[ix::SIN_A].hypot(v[ix::SIN_B])),
        );
    }
    if spec.supply {
        m.insert("gain_per_volt".into(), json!(v[ix::GAIN_PER_VOLT]));
    }
    if spec.clip_throttle {
        m.insert("throttle_clip".into(), json!(v[ix::CLIP]));
    }
    if let Some(l) = spec.clip_sensor {
        m.insert("sensor_clip".into(), json!(l));
    }
    m
}

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
    /// Effect name (one of [`super::catalogue::EFFECTS`]).
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
}
