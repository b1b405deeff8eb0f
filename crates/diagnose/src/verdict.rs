//! Honest verdicts (issue 11): is the final model's residual at the noise floor
//! ([`super::noise`]), and are the fitted models physically plausible?
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/verdict.rs`.

use serde::Serialize;

use super::noise::NoiseFloor;
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
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
        use crate::model::Model;
        use crate::signals::Core;
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
