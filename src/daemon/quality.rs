//! Whether an identified model may be published as a model.
//!
//! ERA always returns *a* realisation; when the pulse responses are not resolved above the
//! noise (one-sample pulses at 10 kHz carry a tenth of the energy they carry at 1 kHz), that
//! realisation is noise fitted by a 2nd-order model: poles on the wrong side of the imaginary
//! axis, DC gains of either sign. A flight controller must never receive such a model as a
//! model, so the worker checks each one against facts that hold for any motor–propeller and
//! publishes a failing one as a `model_unreliable` warning instead (with its numbers and the
//! reasons), outside the gain schedule:
//!
//! - `unstable_pole`: a continuous pole with `Re(s) ≥ 0`. A motor–propeller's thrust, torque
//!   and speed responses to throttle settle; a pole that does not is not the plant's.
//! - `dc_gain_uncertain`: the jackknife standard deviation of the DC gain (leave one pulse out,
//!   [`propid_numerics::uncertainty`]) is larger than the DC gain itself — the pulses disagree on
//!   even its sign. (Only with `identify.jackknife = true`.) The scatter of `fn_hz` is not
//!   judged: near critical damping a leave-one-out model can flip between a complex and a real
//!   pole pair, which inflates the scatter of a good estimate (measured: fn 12.8 Hz ± 14 Hz on
//!   a 12 Hz plant); the published `uncertainty` reports it instead.
//!
//! The checks are deliberately coarse: a model that passes may still be imprecise, and its
//! `uncertainty` says by how much; a model that fails is certainly not the plant.

use propid_numerics::report::Gain;
use propid_numerics::ModelReport;
use serde::Serialize;

/// Relative jackknife standard deviation above which a value is unknown.
pub const MAX_RELATIVE_SD: f64 = 1.0;

/// Hint published with an unreliable model.
pub const HINT: &str = "the pulse responses are not resolved above the noise: use wider pulses \
    ([experiment] pulse_width_samples, e.g. 1 ms worth of samples), larger pulse_amplitudes, \
    or more pulses per model ([identify] pulses_per_model)";

/// Why a model is not the plant's (published in the warning's `reasons`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Flaw {
    /// A continuous pole with `Re(s) >= 0`, or one that is not a finite number.
    UnstablePole,
    /// The jackknife standard deviation of the DC gain exceeds the DC gain.
    DcGainUncertain,
}

/// The flaws of a model (empty: publish it as a model).
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
    use crate::daemon::fixtures::report;
    use serde_json::json;

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
        let v = serde_json::to_value([Flaw::UnstablePole, Flaw::DcGainUncertain]).unwrap();
        assert_eq!(v, json!(["unstable_pole", "dc_gain_uncertain"]));
    }
}
