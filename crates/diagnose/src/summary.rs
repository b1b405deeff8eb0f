//! How a fitted model is published: every field of `propid identify --json`'s model plus the
//! terms of the extension.

use serde::Serialize;
use serde_json::{json, Map, Value};

use super::fit::Fit;
use super::linear_part::LinearPart;
use propid_numerics::modal::mass_spring_damper;
use propid_numerics::report::{
    Gain as ReportGain, MassSpringDamper, ModeIndicators, ModelReport, Uncertainty,
};

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

impl ModelSummary {
    /// Summarises a fit on data sampled every `dt_s`; `core` is the identification core's model
    /// of the estimation part (the source of the Hankel fields, see the type's doc).
    pub fn from_fit(fit: &Fit, dt_s: f64, core: Option<&ModelReport>) -> ModelSummary {
        let m = &fit.model;
        let slope = m.terms().fold(1.0, |s, t| s * t.dc_slope());
        let k = m.core.gain * slope;
        let mut lin = LinearPart::core(m.core.fn_hz, m.core.zeta, k, dt_s);
        for t in m.terms() {
            t.extend_linear(&mut lin, dt_s);
        }
        let LinearPart { a, b, c, poles_s } = lin;
        let poles_z = poles_s
            .iter()
            .map(|s| {
                let m = (s[0] * dt_s).exp();
                [m * (s[1] * dt_s).cos(), m * (s[1] * dt_s).sin()]
            })
            .collect();
        let mut tcs: Vec<f64> = poles_s
            .iter()
            .filter(|s| s[1] == 0.0 && s[0] < 0.0)
            .map(|s| -1.0 / s[0])
            .collect();
        tcs.sort_by(|a, b| b.total_cmp(a));
        let (mass, damping, stiffness) = mass_spring_damper(m.core.fn_hz, m.core.zeta, k);
        let null_mode = ModeIndicators {
            msv: f64::NAN,
            mac: f64::NAN,
            emac: f64::NAN,
            mpc: f64::NAN,
            cmi: f64::NAN,
        };
        let report = ModelReport {
            order: a.len(),
            dt_s,
            fn_hz: m.core.fn_hz,
            zeta: m.core.zeta,
            dc_gain: ReportGain::Scalar(k),
            time_constants_s: tcs,
            indicators: vec![null_mode; poles_s.len()],
            poles_s,
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
            missing_samples: core.map_or(0, |r| r.missing_samples),
            noise_rms: if fit.n > 0 {
                (fit.sse / fit.n as f64).sqrt()
            } else {
                f64::NAN
            },
            mass_spring_damper: MassSpringDamper {
                m: mass,
                d: damping,
                k: stiffness,
            },
            hankel_block_rows: core.map_or(0, |r| r.hankel_block_rows),
            hankel_block_cols: core.map_or(0, |r| r.hankel_block_cols),
            svd: core.map_or("none".to_string(), |r| r.svd.clone()),
            order_stepped_down_from: None,
        };
        ModelSummary {
            report,
            terms: terms(fit, dt_s),
        }
    }
}

/// The model's `terms`: the core's gain and offset, then each effect's entries.
fn terms(fit: &Fit, dt_s: f64) -> Map<String, Value> {
    let m = &fit.model;
    let mut out = Map::new();
    out.insert("offset".into(), json!(m.core.offset));
    out.insert("gain".into(), json!(m.core.gain));
    for t in m.terms() {
        t.terms(dt_s, &mut out);
    }
    out
}
