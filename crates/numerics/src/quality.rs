//! Whether an identified model may be used as the plant's model: the one rule of the daemon's
//! windows and of `propid identify`.
//!
//! ERA always returns *a* realisation; when the pulse responses are not resolved above the
//! noise (one-sample pulses at 10 kHz carry a tenth of the energy they carry at 1 kHz), or the
//! record is not what the model assumes (a start-up transient under the first pulses), that
//! realisation is noise or drift fitted by a low-order model: poles on the wrong side of the
//! imaginary axis, DC gains of either sign. A flight controller must never receive such a model
//! as a model, so each one is checked against facts that hold for any motor–propeller:
//!
//! - [`Flaw::UnstablePole`]: a continuous pole with `Re(s) ≥ 0` (or not a finite number). A
//!   motor–propeller's thrust, torque and speed responses to throttle settle; a pole that does
//!   not is not the plant's.
//! - [`Flaw::DcGainUncertain`]: the jackknife standard deviation of the DC gain (leave one
//!   pulse out, [`crate::uncertainty`]) is larger than [`MAX_RELATIVE_SD`] times the DC gain
//!   itself — the pulses disagree on even its sign. (Only when the jackknife ran.) The scatter
//!   of `fn_hz` is not judged: near critical damping a leave-one-out model can flip between a
//!   complex and a real pole pair, which inflates the scatter of a good estimate (measured:
//!   fn 12.8 Hz ± 14 Hz on a 12 Hz plant); the published `uncertainty` reports it instead.
//!
//! The checks are deliberately coarse: a model that passes may still be imprecise, and its
//! `uncertainty` says by how much; a model that fails is certainly not the plant. The daemon
//! publishes a failing model as a `model_unreliable` warning; `propid identify` prints it with
//! `"quality": {"accepted": false, ...}` and exits 4.

use serde::Serialize;

use crate::report::Gain;
use crate::ModelReport;

/// Relative jackknife standard deviation above which a value is unknown.
pub const MAX_RELATIVE_SD: f64 = 1.0;

/// Why a model is not the plant's (published by these names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Flaw {
    /// A continuous pole with `Re(s) >= 0`, or one that is not a finite number.
    UnstablePole,
    /// The jackknife standard deviation of the DC gain exceeds the DC gain.
    DcGainUncertain,
}

impl Flaw {
    /// The published name.
    pub fn name(self) -> &'static str {
        match self {
            Flaw::UnstablePole => "unstable_pole",
            Flaw::DcGainUncertain => "dc_gain_uncertain",
        }
    }
}

/// The flaws of a model (empty: it may be used as a model).
pub fn judge(model: &ModelReport) -> Vec<Flaw> {
    let mut flaws = Vec::new();
    // a non-finite real part (published as null) is not a settled pole either
    if model
        .poles_s
        .iter()
        .any(|&[re, _]| !(re.is_finite() && re < 0.0))
    {
        flaws.push(Flaw::UnstablePole);
    }
    // judged for one output (a scalar gain) with both numbers finite
    if let (Gain::Scalar(v), Gain::Scalar(sd)) = (&model.dc_gain, &model.uncertainty.dc_gain) {
        if v.is_finite() && sd.is_finite() && *sd > MAX_RELATIVE_SD * v.abs() {
            flaws.push(Flaw::DcGainUncertain);
        }
    }
    flaws
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};

    /// A complete, stable 2nd-order model report with the fields of `overrides` replaced.
    fn report(overrides: Value) -> ModelReport {
        let mut base = json!({
            "order": 2, "dt_s": 0.001, "fn_hz": 12.5, "zeta": 0.5, "dc_gain": 2.0,
            "time_constants_s": [], "poles_s": [[-39.25, 68.0], [-39.25, -68.0]],
            "poles_z": [[0.96, 0.065], [0.96, -0.065]],
            "a": [[0.5, 0.25], [-0.25, 0.5]], "b": [[1.0], [0.0]], "c": [[1.0, 0.0]],
            "d": [[0.0]], "singular_values": [3.0, 1.0], "indicators": [],
            "uncertainty": {"fn_hz": 0.25, "zeta": null, "dc_gain": 0.5},
            "pulses": 1, "pulses_skipped": 0, "noise_rms": 0.01,
            "mass_spring_damper": {"m": 0.25, "d": 0.125, "k": 0.5},
            "hankel_block_rows": 10, "hankel_block_cols": 10, "svd": "truncated"
        });
        if let (Some(b), Value::Object(o)) = (base.as_object_mut(), overrides) {
            b.extend(o);
        }
        serde_json::from_value(base).expect("a complete model report")
    }

    #[test]
    fn a_good_estimate_with_a_wide_fn_scatter_passes() {
        // measured at 1 kHz: one leave-one-out model flipped to real poles
        let m = report(json!({
            "fn_hz": 12.78, "zeta": 0.80, "dc_gain": 11.89,
            "poles_s": [[-64.0, 48.5], [-64.0, -48.5]],
            "uncertainty": {"fn_hz": 14.4, "zeta": 1.54, "dc_gain": 2.89}
        }));
        assert!(judge(&m).is_empty());
    }

    #[test]
    fn a_resolved_model_passes() {
        // 1 kHz, one-sample pulses, 0.01 N noise: a typical daemon model
        let m = report(json!({
            "fn_hz": 12.4, "zeta": 0.78, "dc_gain": 12.2,
            "poles_s": [[-61.0, 48.5], [-61.0, -48.5]],
            "uncertainty": {"fn_hz": 0.56, "zeta": 0.26, "dc_gain": 2.6}
        }));
        assert!(judge(&m).is_empty());
        // without jackknife only the poles are judged
        let m = report(
            json!({"fn_hz": 12.4, "dc_gain": 12.2, "poles_s": [[-30.0, 0.0], [-900.0, 0.0]],
            "uncertainty": {"fn_hz": null, "zeta": null, "dc_gain": null}}),
        );
        assert!(judge(&m).is_empty());
    }

    #[test]
    fn noise_fitted_models_fail_with_their_reasons() {
        // measured: 10 kHz, one-sample pulses, 0.01 N noise (the default sim plant)
        let m = report(json!({
            "fn_hz": null, "zeta": null, "dc_gain": -565.8,
            "poles_s": [[0.632, 0.0], [-2709.3, 31415.9]],
            "uncertainty": {"dc_gain": 211.5, "fn_hz": null, "zeta": null}
        }));
        assert_eq!(judge(&m), vec![Flaw::UnstablePole]);
        let m = report(json!({
            "fn_hz": 61.4, "zeta": 22.2, "dc_gain": 45.3,
            "poles_s": [[-8.69, 0.0], [-17110.8, 0.0]],
            "uncertainty": {"dc_gain": 472.1, "fn_hz": null, "zeta": null}
        }));
        assert_eq!(judge(&m), vec![Flaw::DcGainUncertain]);
        let m = report(json!({
            "fn_hz": 3.0, "dc_gain": 1.0, "poles_s": [[null, 0.0], [-0.0, 0.0]],
            "uncertainty": {"fn_hz": 3.5, "zeta": null, "dc_gain": 1.5}
        }));
        assert_eq!(judge(&m), vec![Flaw::UnstablePole, Flaw::DcGainUncertain]);
        // a pole at the origin is not settled
        let m = report(json!({"poles_s": [[-0.0, 0.0], [-5.0, 0.0]]}));
        assert_eq!(judge(&m), vec![Flaw::UnstablePole]);
    }

    #[test]
    fn flaws_are_published_by_their_names() {
        let all = [Flaw::UnstablePole, Flaw::DcGainUncertain];
        let v = serde_json::to_value(all).unwrap();
        assert_eq!(v, json!(["unstable_pole", "dc_gain_uncertain"]));
        for f in all {
            assert_eq!(serde_json::to_value(f).unwrap(), json!(f.name()));
        }
    }
}
