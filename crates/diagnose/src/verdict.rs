//! Honest verdicts (issue 11): is the final model's residual at the noise floor
//! ([`super::noise`]), and are the fitted models physically plausible?
//!
//! **Verdict.** The final model is the extended one when effects were found, else the
//! baseline; `r` is its simulation residual RMS on the validation samples, `σ` the noise floor.
//! - `explained`: no effect found and `r ≤ k σ`;
//! - `effects_found`: effects found and `r ≤ k σ`;
//! - `unexplained`: otherwise (or no floor could be measured).
//!
//! `k =` [`EXPLAINED_FACTOR`] `= 1.5`. A perfect model leaves `r ≈ σ`; `r ≤ 1.5 σ` allows a
//! systematic error of at most `√(1.5² − 1) σ ≈ 1.1 σ` RMS, i.e. a model error that is lost
//! in the noise sample by sample. The margin also absorbs the floor's own uncertainty: the
//! median-of-second-differences estimate scatters by about `±10 %` over a few hundred samples and
//! reads the white part of the noise only, and the output-error residual carries the estimation
//! error of the model's parameters. Anything further above the noise is not called explained.
//!
//! `unexplained_share = max(0, 1 − σ² / r²)`: the share of the final residual's power above the
//! noise, i.e. that no effect in the catalogue accounts for.
//!
//! **Warnings** (each published model, baseline and extended):
//! - `nonpositive_gain`: DC gain (thrust per unit command) `≤ 0`: more command, less thrust.
//! - `time_constant_below_sample`: a stable pole with `τ = −1 / Re s` shorter than one sample
//!   period: a dynamic the data cannot resolve. Beside a slower pole of `τ ≥ dt` it is an
//!   overdamped core fitting a first-order response, and the message says that instead.
//! - `mode_outside_band`: the dominant mode (the core's `fn` when underdamped, its slow real
//!   pole's `|s| / 2π` when overdamped) outside the excited band `[1/T, f_hi]`: `T` the record
//!   length, `f_hi` the frequency below which [`BAND_POWER`] `= 99 %` of the power of the
//!   input's first difference `Δu` lies (Hann periodogram, [`super::spectrum::periodogram`]).
//!   `Δu` of a staircase or pulses is a train of impulses, flat up to Nyquist: the band is the
//!   whole record's; a smooth input (slow ramp, low chirp) excites only its low band, and a mode
//!   fitted above it is not measured but extrapolated.
//! - `baseline_drift_unidentifiable` (the baseline): the time `t` is an affine function of the
//!   command to within `1 − R²` ([`super::effects::baseline_drift::confounding`], `value` =
//!   `R²`): a `baseline_drift` is then indistinguishable from a change of the static map, and
//!   finding none (or one) says nothing about it.
//! - `dead_time_unidentifiable` (the baseline): the command delayed by a couple of samples is an
//!   affine function of itself to within `1 − R²` ([`super::effects::dead_time::confounding`],
//!   `value` = `R²`): a delay is then a shift of the thrust curve or a lag, and finding none
//!   (or one) says nothing about it.
//! - `supply_sag_unidentifiable` (the final model, when no `supply_sag` was found): the supply
//!   voltage's own variation, beyond what the throttle explains, is too small for even a
//!   propeller-strong voltage dependence to reach the search's score
//!   ([`super::effects::supply_sag::detectability`], `value` = that score): finding no sag says
//!   nothing about the supply.

use serde::Serialize;

use super::effects::baseline_drift::UNIDENTIFIABLE_R2;
use super::effects::dead_time::CONFOUNDING_SHIFT;
use super::effects::supply_sag::{Detectability, EXPONENT_MAX};
use super::noise::NoiseFloor;
use super::search::SCORE_THRESHOLD;
use super::spectrum::periodogram;
use super::summary::ModelSummary;

/// `k`: explained only when the final residual RMS is at most `k` noise floors.
pub const EXPLAINED_FACTOR: f64 = 1.5;
/// Share of the power of `Δu` below the excited band's upper edge.
pub const BAND_POWER: f64 = 0.99;

/// Residual RMS of the models on the validation samples (`"residual"`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Residual {
    /// The baseline's.
    pub baseline_rms: f64,
    /// The extended model's (null when no effect was found).
    pub extended_rms: Option<f64>,
}

impl Residual {
    /// The final model's residual RMS (extended when there is one).
    pub fn final_rms(&self) -> f64 {
        self.extended_rms.unwrap_or(self.baseline_rms)
    }
}

/// The verdict's kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum VerdictKind {
    /// No effect found and the baseline's residual is at the noise floor.
    Explained,
    /// Effects found and the extended model's residual is at the noise floor.
    EffectsFound,
    /// The final residual is above the noise floor.
    Unexplained,
}

/// The verdict (`"verdict"`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// See the module doc.
    pub kind: VerdictKind,
    /// `max(0, 1 − σ²/r²)` of the final model (null without a floor).
    pub unexplained_share: f64,
    /// Why, in words.
    pub reason: String,
}

/// The verdict on the final residual given the floor and whether effects were found.
pub fn verdict(floor: Option<&NoiseFloor>, residual: &Residual, effects_found: bool) -> Verdict {
    let r = residual.final_rms();
    let which = if effects_found {
        "the extended model"
    } else {
        "the 2nd-order model"
    };
    let Some(f) = floor.filter(|f| f.rms > 0.0 && f.rms.is_finite()) else {
        return Verdict {
            kind: VerdictKind::Unexplained,
            unexplained_share: f64::NAN,
            reason: "no noise floor could be measured from the data".into(),
        };
    };
    let ratio = r / f.rms;
    let share = (1.0 - (f.rms / r).powi(2)).max(0.0);
    let at_floor = ratio <= EXPLAINED_FACTOR;
    let kind = match (at_floor, effects_found) {
        (true, false) => VerdictKind::Explained,
        (true, true) => VerdictKind::EffectsFound,
        (false, _) => VerdictKind::Unexplained,
    };
    let reason = if at_floor {
        format!(
            "{which}'s validation residual RMS {r:.4} is {ratio:.2} × the noise floor {:.4} \
             (≤ {EXPLAINED_FACTOR})",
            f.rms
        )
    } else {
        format!(
            "{which}'s validation residual RMS {r:.4} is {ratio:.2} × the noise floor {:.4} \
             (> {EXPLAINED_FACTOR}): {:.0} % of the residual power is explained by no effect in \
             the catalogue",
            f.rms,
            100.0 * share
        )
    };
    Verdict {
        kind,
        unexplained_share: share,
        reason,
    }
}

/// Kind of a warning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WarningKind {
    /// DC gain `≤ 0`.
    NonpositiveGain,
    /// A time constant shorter than one sample period.
    TimeConstantBelowSample,
    /// The dominant mode outside the excited band.
    ModeOutsideBand,
    /// A drift of the output cannot be told from the gain (a one-way ramp of the command).
    BaselineDriftUnidentifiable,
    /// A dead time cannot be told from a shift of the thrust curve or a lag (a command smooth
    /// against the sample period).
    DeadTimeUnidentifiable,
    /// A supply sag could not show in this record: the voltage varies only with the throttle
    /// (or not at all), or the model's residual is larger than any plausible sag's change.
    SupplySagUnidentifiable,
}

/// An implausible result (`"warnings"`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Warning {
    /// What is implausible.
    pub kind: WarningKind,
    /// In words.
    pub message: String,
    /// `"baseline"` or `"extended"`.
    pub model: &'static str,
    /// The offending value (gain, seconds, Hz).
    pub value: f64,
    /// The excited band `[lo, hi]`, Hz (`mode_outside_band` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band_hz: Option<[f64; 2]>,
}

/// The `baseline_drift_unidentifiable` warning when `r2` (the share of `t` explained by the
/// command) reaches [`UNIDENTIFIABLE_R2`].
pub fn drift_warning(r2: f64) -> Option<Warning> {
    (r2 >= UNIDENTIFIABLE_R2).then(|| Warning {
        kind: WarningKind::BaselineDriftUnidentifiable,
        message: format!(
            "baseline drift not identifiable: the command runs one way through the record (time \
             is affine in it to R² = {r2:.5}), so a drift of the output cannot be told from a \
             change of the thrust curve; a ramp up and back down, or holds, would separate them"
        ),
        model: "baseline",
        value: r2,
        band_hz: None,
    })
}

/// The `dead_time_unidentifiable` warning when `r2` (the share of the command delayed by
/// [`CONFOUNDING_SHIFT`] samples that an affine function of the command explains) reaches
/// [`UNIDENTIFIABLE_R2`] ([`super::effects::dead_time::confounding`]).
pub fn dead_time_warning(r2: f64) -> Option<Warning> {
    (r2 >= UNIDENTIFIABLE_R2).then(|| Warning {
        kind: WarningKind::DeadTimeUnidentifiable,
        message: format!(
            "dead time not identifiable: the command is smooth against the sample period (delayed \
             by {CONFOUNDING_SHIFT} samples it is an affine function of itself to R² = {r2:.5}), \
             so a delay of the output cannot be told from a shift of the thrust curve or a lag; \
             steps or holds would show it"
        ),
        model: "baseline",
        value: r2,
        band_hz: None,
    })
}

/// The `supply_sag_unidentifiable` warning of model `model` (`"baseline"` or `"extended"`)
/// when `d.score`, the most a propeller-strong supply term driven by the voltage's own
/// variation could score on it ([`super::effects::supply_sag::detectability`]), is below
/// [`SCORE_THRESHOLD`].
pub fn supply_sag_warning(d: &Detectability, model: &'static str) -> Option<Warning> {
    (d.score < SCORE_THRESHOLD).then(|| Warning {
        kind: WarningKind::SupplySagUnidentifiable,
        message: format!(
            "supply sag not identifiable: the supply voltage varies by {:.3} V RMS beyond what \
             the throttle explains; even with thrust ∝ V^{EXPONENT_MAX} that would change the \
             output by {:.2} % RMS, which would score {:.0} < {SCORE_THRESHOLD} above the {model} \
             model's residual ({:.1} % RMS of the output): a sag can be neither found nor ruled \
             out in this record (the voltage's variation with the throttle cannot be told from \
             the thrust curve). A supply that discharges across repeated levels, or is stepped, \
             would show it",
            d.own_rms_v,
            100.0 * d.relative_change,
            d.score,
            100.0 * d.relative_residual,
        ),
        model,
        value: d.score,
        band_hz: None,
    })
}

/// The excited band `[1/T, f_hi]` of input `u` sampled every `dt_s` (see the module doc).
pub fn excited_band(u: &[f64], dt_s: f64) -> [f64; 2] {
    let lo = 1.0 / (u.len() as f64 * dt_s);
    let du: Vec<f64> = u.windows(2).map(|w| w[1] - w[0]).collect();
    let (freqs, power) = periodogram(&du, dt_s);
    let total: f64 = power.iter().sum();
    let nyquist = 0.5 / dt_s;
    if total.is_nan() || total <= 0.0 {
        return [lo, nyquist];
    }
    let mut acc = 0.0;
    for (f, p) in freqs.iter().zip(&power) {
        acc += p;
        if acc >= BAND_POWER * total {
            return [lo, f.max(lo)];
        }
    }
    [lo, nyquist]
}

/// The dominant mode's frequency, Hz: `fn` when underdamped, the slow real pole's otherwise.
pub fn dominant_mode_hz(fn_hz: f64, zeta: f64) -> f64 {
    if zeta < 1.0 {
        fn_hz
    } else {
        fn_hz * (zeta - (zeta * zeta - 1.0).sqrt())
    }
}

/// The warnings of one published model (`name`: `"baseline"` or `"extended"`).
pub fn warnings(m: &ModelSummary, name: &'static str, band: [f64; 2]) -> Vec<Warning> {
    let r = &m.report;
    let mut out = Vec::new();
    if let Some(gain) = propid_numerics::quality::nonpositive_gain(r) {
        out.push(Warning {
            kind: WarningKind::NonpositiveGain,
            message: format!(
                "{name} DC gain {gain:.4} ≤ 0: the output does not grow with the command"
            ),
            model: name,
            value: gain,
            band_hz: None,
        });
    }
    let taus = || {
        r.poles_s
            .iter()
            .filter(|s| s[0] < 0.0 && s[0].is_finite())
            .map(|s| -1.0 / s[0])
    };
    let (tau, slowest) = (
        taus().fold(f64::INFINITY, f64::min),
        taus().fold(0.0, f64::max),
    );
    if tau < r.dt_s {
        // Beside a resolved slow pole, a pole faster than a sample is an overdamped core
        // fitting a first-order response: said so, not as an unresolved dynamic.
        let message = if slowest >= r.dt_s {
            format!(
                "{name} second time constant {tau:.3e} s is shorter than one sample ({:.3e} s): \
                 at this rate the response is first-order, time constant {slowest:.4} s",
                r.dt_s
            )
        } else {
            format!(
                "{name} time constant {tau:.3e} s is shorter than one sample ({:.3e} s)",
                r.dt_s
            )
        };
        out.push(Warning {
            kind: WarningKind::TimeConstantBelowSample,
            message,
            model: name,
            value: tau,
            band_hz: None,
        });
    }
    let f = dominant_mode_hz(r.fn_hz, r.zeta);
    if f.is_finite() && (f < band[0] || f > band[1]) {
        out.push(Warning {
            kind: WarningKind::ModeOutsideBand,
            message: format!(
                "{name} dominant mode {f:.4} Hz is outside the excited band {:.4}..{:.4} Hz",
                band[0], band[1]
            ),
            model: name,
            value: f,
            band_hz: Some(band),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::FloorSource;

    fn floor(rms: f64) -> NoiseFloor {
        NoiseFloor {
            rms,
            from: FloorSource::SteadyHolds,
            samples: 100,
        }
    }

    #[test]
    fn the_rule_calls_explained_only_near_the_floor() {
        let res = |b, e| Residual {
            baseline_rms: b,
            extended_rms: e,
        };
        let f = floor(0.01);
        assert_eq!(
            verdict(Some(&f), &res(0.012, None), false).kind,
            VerdictKind::Explained
        );
        assert_eq!(
            verdict(Some(&f), &res(0.05, Some(0.012)), true).kind,
            VerdictKind::EffectsFound
        );
        let v = verdict(Some(&f), &res(0.05, None), false);
        assert_eq!(v.kind, VerdictKind::Unexplained);
        assert!((v.unexplained_share - (1.0 - 0.04)).abs() < 1e-12, "{v:?}");
        assert_eq!(
            verdict(Some(&f), &res(0.05, Some(0.03)), true).kind,
            VerdictKind::Unexplained
        );
        assert_eq!(
            verdict(None, &res(0.01, None), false).kind,
            VerdictKind::Unexplained
        );
    }

    #[test]
    fn a_step_input_excites_up_to_nyquist_and_a_slow_sine_only_its_band() {
        let dt = 0.01;
        let steps: Vec<f64> = (0..2000).map(|k| ((k / 100) % 2) as f64).collect();
        let b = excited_band(&steps, dt);
        assert!((b[0] - 0.05).abs() < 1e-12 && b[1] > 40.0, "{b:?}");
        let sine: Vec<f64> = (0..2000)
            .map(|k| (2.0 * std::f64::consts::PI * 0.5 * k as f64 * dt).sin())
            .collect();
        let b = excited_band(&sine, dt);
        assert!(b[1] < 2.0, "{b:?}");
    }

    #[test]
    fn a_pole_faster_than_a_sample_is_warned_and_named_second_beside_a_resolved_one() {
        use crate::fit::Fit;
        use crate::model::{Core, Model};
        let dt = 1e-3;
        let summary = |fn_hz, zeta| {
            let fit = Fit {
                model: Model::default().with_core(Core {
                    fn_hz,
                    zeta,
                    gain: 1.0,
                    ..Core::default()
                }),
                sse: 1.0,
                n: 100,
            };
            ModelSummary::from_fit(&fit, dt, None)
        };
        let band = [0.01, 500.0];
        let below = |m: &ModelSummary| {
            warnings(m, "extended", band)
                .into_iter()
                .find(|w| w.kind == WarningKind::TimeConstantBelowSample)
        };
        // Poles at τ 40 ms and 4 µs: a first-order response, the fast pole named second.
        let (t1, t2): (f64, f64) = (0.04, 4e-6);
        let wn = 1.0 / (t1 * t2).sqrt();
        let zeta = (t1 + t2) * wn / 2.0;
        let w = below(&summary(wn / std::f64::consts::TAU, zeta)).unwrap();
        assert!((w.value - t2).abs() < 1e-8, "{}", w.value);
        assert!(
            w.message.contains("second time constant") && w.message.contains("first-order"),
            "{}",
            w.message
        );
        // Every pole faster than a sample: unresolved.
        let w = below(&summary(2000.0, 1.5)).unwrap();
        assert!(!w.message.contains("second"), "{}", w.message);
        // Both resolved: no warning.
        assert!(below(&summary(5.0, 0.7)).is_none());
    }

    #[test]
    fn the_dominant_mode_of_an_overdamped_core_is_its_slow_pole() {
        assert_eq!(dominant_mode_hz(10.0, 0.5), 10.0);
        let f = dominant_mode_hz(10.0, 2.0);
        assert!((f - 10.0 * (2.0 - 3f64.sqrt())).abs() < 1e-12);
    }
}
