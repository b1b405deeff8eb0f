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
//! - [`Flaw::DcGainContradictsLevels`] ([`judge_gain`], when the record has steady levels: a
//!   staircase, steps, a slow ramp): the DC gain `G` against the least-squares slope `g` of the
//!   record's own steady levels ([`crate::static_map::level_slope`], `sd` its standard error).
//!   A linear model fitted across those levels settles on them, so its gain has the sign of
//!   `g` and lies within a factor [`LEVEL_GAIN_FACTOR`] of it: a curved static map puts its local
//!   slopes on either side of `g` (`T = k·u³` over 0..1: local slopes 0..3k, `g ≈ 0.9k`). The
//!   check runs only when `g` is resolved, `|g| > `[`LEVEL_SLOPE_SIGMAS`]` · sd`; a flat or
//!   scattered map says nothing about the sign. `G/g ≤ 0` (a thrust that falls as the command
//!   rises on a stand whose levels rise) or `G/g` outside `[1/4, 4]` is a number the data do
//!   not support: refused, with both numbers named.
//!
//! - [`Flaw::ImplausibleDcGain`]: a DC gain (any output's) that is not a finite number or
//!   exceeds [`MAX_ABS_DC_GAIN`] in magnitude — the physical plausibility bound. Thrust in N,
//!   torque in N·m, speed in rev/min per unit throttle: the largest stands measure hundreds of
//!   N and tens of thousands of rev/min at full throttle, so a gain above 10⁶ is no motor's (a
//!   stand that sends ±3e38 among its samples gave −1.9e39).
//!
//! The checks are deliberately coarse: a model that passes may still be imprecise, and its
//! `uncertainty` says by how much; a model that fails is certainly not the plant. The daemon
//! publishes a failing model as a `model_unreliable` warning; `propid identify` prints it with
//! `"quality": {"accepted": false, ...}` and exits 4.

use serde::Serialize;

use crate::report::Gain;
use crate::static_map::LevelSlope;
use crate::ModelReport;

/// Relative jackknife standard deviation above which a value is unknown.
pub const MAX_RELATIVE_SD: f64 = 1.0;
/// Largest |DC gain| of a plausible model (output units per unit throttle: N, N·m, rev/min);
/// see [`Flaw::ImplausibleDcGain`].
pub const MAX_ABS_DC_GAIN: f64 = 1e6;
/// A DC gain `G` agrees with the levels' slope `g` when `1/F ≤ G/g ≤ F`.
pub const LEVEL_GAIN_FACTOR: f64 = 4.0;
/// The levels' slope is resolved when it exceeds this many standard errors.
pub const LEVEL_SLOPE_SIGMAS: f64 = 2.0;

/// Why a model is not the plant's (published by these names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Flaw {
    /// A continuous pole with `Re(s) >= 0`, or one that is not a finite number.
    UnstablePole,
    /// The jackknife standard deviation of the DC gain exceeds the DC gain.
    DcGainUncertain,
    /// The DC gain has the other sign than the record's steady levels, or is more than
    /// [`LEVEL_GAIN_FACTOR`] times off their slope ([`judge_gain`]).
    DcGainContradictsLevels,
    /// A stand's command sampled more slowly than a motor–propeller settles
    /// ([`judge_sample_period`]): every sample is a steady state, the record holds no dynamics.
    SamplePeriodTooLong,
    /// A DC gain beyond the physical plausibility bound [`MAX_ABS_DC_GAIN`] (or not finite).
    ImplausibleDcGain,
}

impl Flaw {
    /// The published name.
    pub fn name(self) -> &'static str {
        match self {
            Flaw::UnstablePole => "unstable_pole",
            Flaw::DcGainUncertain => "dc_gain_uncertain",
            Flaw::DcGainContradictsLevels => "dc_gain_contradicts_levels",
            Flaw::SamplePeriodTooLong => "sample_period_too_long",
            Flaw::ImplausibleDcGain => "implausible_dc_gain",
        }
    }
}

/// The DC gain of output 0 per unit of input 0 when it is finite and `≤ 0`: more command,
/// less output — implausible for a thrust (or a speed, a current) under a throttle command: a
/// load cell mounted reversed, a sign convention of the export, or a wrong model. A warning
/// (`nonpositive_gain`, in `identify` and `diagnose`), not a flaw: the model may be right for
/// a reversed sensor, and the user must be told either way.
pub fn nonpositive_gain(model: &ModelReport) -> Option<f64> {
    let gain = model.dc_gain.get(0);
    (gain.is_finite() && gain <= 0.0).then_some(gain)
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
    let gains: Vec<f64> = match &model.dc_gain {
        Gain::Scalar(g) => vec![*g],
        Gain::List(v) => v.clone(),
        Gain::Matrix(m) => m.iter().flatten().copied().collect(),
    };
    if gains
        .iter()
        .any(|g| !(g.is_finite() && g.abs() <= MAX_ABS_DC_GAIN))
    {
        flaws.push(Flaw::ImplausibleDcGain);
    }
    // judged for one output (a scalar gain) with both numbers finite
    if let (Gain::Scalar(v), Gain::Scalar(sd)) = (&model.dc_gain, &model.uncertainty.dc_gain) {
        if v.is_finite() && sd.is_finite() && *sd > MAX_RELATIVE_SD * v.abs() {
            flaws.push(Flaw::DcGainUncertain);
        }
    }
    flaws
}

/// Whether a record of a stand's command sampled every `dt_s` can show a motor–propeller's
/// dynamics: not when a sample lasts longer than the response takes to settle
/// ([`crate::segment::MAX_PULSE_S`], a third of a second; [`Flaw::SamplePeriodTooLong`]).
/// Such a log (a stand's table of steady averages, a slow ramp logged at 2 Hz) holds a static
/// map and nothing else: a model fitted to it has time constants of the sampling, not of the
/// plant (measured: τ = 33.9 s from a table with a row every 5 s; τ = 10.1 s from a ramp
/// logged at 2.1 Hz). Asked only of a command's record: a signal in its own units (a tank's
/// pump voltage) may drive a plant as slow as its samples.
pub fn judge_sample_period(dt_s: f64) -> Option<Flaw> {
    (dt_s > crate::segment::MAX_PULSE_S).then_some(Flaw::SamplePeriodTooLong)
}

/// A DC gain the steady levels do not support ([`Flaw::DcGainContradictsLevels`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainContradiction {
    /// The model's DC gain (input 0 to output 0).
    pub dc_gain: f64,
    /// The levels' least-squares slope.
    pub slope: LevelSlope,
}

impl std::fmt::Display for GainContradiction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.slope;
        write!(
            f,
            "the model's DC gain {:.4} is not the gain of the record's {} steady levels \
             (their least-squares slope {:.4}{}; a linear model across them has its sign and \
             lies within a factor {LEVEL_GAIN_FACTOR} of it): the record holds what a linear \
             model cannot (a jump the logged command does not explain, an unlogged hold, a \
             response slower than the record resolves)",
            self.dc_gain,
            s.levels,
            s.slope,
            s.sd.map_or(String::new(), |sd| format!(" ± {sd:.4}")),
        )
    }
}

/// The check of the DC gain against the record's steady levels (see the module doc): `Some`
/// when `model`'s gain from input 0 to output 0 contradicts `slope`, `None` when it agrees or
/// the slope is not resolved.
pub fn judge_gain(model: &ModelReport, slope: &LevelSlope) -> Option<GainContradiction> {
    let g = slope.slope;
    let resolved = g.is_finite()
        && g != 0.0
        && match slope.sd {
            None => true,
            Some(sd) => sd.is_finite() && g.abs() > LEVEL_SLOPE_SIGMAS * sd,
        };
    if !resolved {
        return None;
    }
    let dc_gain = model.dc_gain.get(0);
    let ratio = dc_gain / g;
    let agrees =
        ratio.is_finite() && (1.0 / LEVEL_GAIN_FACTOR..=LEVEL_GAIN_FACTOR).contains(&ratio);
    (!agrees).then_some(GainContradiction {
        dc_gain,
        slope: *slope,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};

    #[test]
    fn a_command_sampled_more_slowly_than_a_motor_settles_holds_no_dynamics() {
        assert_eq!(judge_sample_period(0.001), None);
        assert_eq!(judge_sample_period(0.1), None);
        assert_eq!(judge_sample_period(0.3), None);
        assert_eq!(judge_sample_period(0.5), Some(Flaw::SamplePeriodTooLong));
        assert_eq!(judge_sample_period(5.0), Some(Flaw::SamplePeriodTooLong));
        assert_eq!(Flaw::SamplePeriodTooLong.name(), "sample_period_too_long");
    }

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
    fn a_gain_against_the_levels_passes_only_with_their_sign_and_size() {
        let slope = |g: f64, sd: Option<f64>| LevelSlope {
            slope: g,
            sd,
            levels: 25,
        };
        // measured on noahcurtiss robbe (force counts per unit command): levels' slope 669,
        // the realised model's gain -5978
        let s = slope(669.0, Some(40.0));
        let c = judge_gain(&report(json!({"dc_gain": -5978.3})), &s).unwrap();
        assert_eq!(c.dc_gain, -5978.3);
        assert!(c.to_string().contains("-5978.3"), "{c}");
        assert!(c.to_string().contains("669.0"), "{c}");
        for ok in [585.0, 669.0 / 3.9, 669.0 * 3.9] {
            assert!(
                judge_gain(&report(json!({ "dc_gain": ok })), &s).is_none(),
                "{ok}"
            );
        }
        for bad in [0.0, 669.0 / 4.1, 669.0 * 4.1] {
            assert!(
                judge_gain(&report(json!({ "dc_gain": bad })), &s).is_some(),
                "{bad}"
            );
        }
        // a non-finite gain is not supported either
        assert!(judge_gain(&report(json!({ "dc_gain": null })), &s).is_some());
        // falling levels: a falling gain agrees
        let s = slope(-2.0, None);
        assert!(judge_gain(&report(json!({"dc_gain": -1.5})), &s).is_none());
        assert!(judge_gain(&report(json!({"dc_gain": 1.5})), &s).is_some());
        // a slope within two standard errors of 0 says nothing
        let s = slope(1.0, Some(0.6));
        assert!(judge_gain(&report(json!({"dc_gain": -100.0})), &s).is_none());
    }

    #[test]
    fn a_gain_no_motor_has_is_implausible() {
        let m = report(json!({"dc_gain": -1.9e39}));
        assert_eq!(judge(&m), vec![Flaw::ImplausibleDcGain]);
        let m = report(json!({"dc_gain": 2.0e6}));
        assert_eq!(judge(&m), vec![Flaw::ImplausibleDcGain]);
        let m = report(json!({"dc_gain": null}));
        assert_eq!(judge(&m), vec![Flaw::ImplausibleDcGain]);
        // a big stand: 300 N at full throttle
        let m = report(json!({"dc_gain": 300.0}));
        assert!(judge(&m).is_empty());
        assert_eq!(Flaw::ImplausibleDcGain.name(), "implausible_dc_gain");
    }

    #[test]
    fn flaws_are_published_by_their_names() {
        let all = [
            Flaw::UnstablePole,
            Flaw::DcGainUncertain,
            Flaw::DcGainContradictsLevels,
        ];
        let v = serde_json::to_value(all).unwrap();
        assert_eq!(
            v,
            json!([
                "unstable_pole",
                "dc_gain_uncertain",
                "dc_gain_contradicts_levels"
            ])
        );
        for f in all {
            assert_eq!(serde_json::to_value(f).unwrap(), json!(f.name()));
        }
    }
}
