//! Model discrepancy (issue 5): show where the 2nd-order simulation departs from the
//! measurement, name the physical cause, extend the model with it and measure the gain on data
//! the models were not fitted on.
//!
//! 1. **Validation** ([`folds`]). A command with steps (at least 3 levels of the
//!    segmentation): blocked cross-validation, folds of whole levels, every model fitted on all
//!    samples and, for its held-out figure, refitted without each fold and scored on it (the
//!    mean of the folds' fits). A command without steps: the first 70 % of the samples
//!    (`estimation_fraction`) are fitted, the rest is held out ([`Split`], [`Validation`]).
//! 2. **Baseline.** A 2nd-order output-error model `T'' + 2ζωn T' + ωn² T = ωn² K u` plus an
//!    offset, exactly discretised (ZOH), fitted by least squares on the simulation error
//!    ([`fit`], [`search::baseline`]); simulated from the input alone, its fit on held-out
//!    samples is `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)`.
//! 3. **Catalogue** ([`effects`], one file per effect behind the [`effect::Effect`] and
//!    [`effect::Term`] traits): each effect extends the model ([`model`]), fitted jointly with
//!    every term already in it; its score is a likelihood ratio; the forward selection
//!    ([`search`]) adds the effects that pass the threshold and raise the held-out figure,
//!    one at a time, each with its held-out gain (`cv_gain_pp`).
//! 4. **Extended model**: the model with every effect found, validated on the same folds;
//!    the gain is the difference of held-out figures and the ratio of held-out residual RMS.
//!
//! The detector sees only the measured signals (input, output, and the supply voltage when the
//! record has one), never the simulator's configuration.

pub mod assemble;
pub mod baseline;
pub mod ctx;
pub mod effect;
pub mod effects;
pub mod era_start;
pub mod error;
pub mod file;
pub mod finding;
pub mod fit;
pub mod folds;
pub mod lead;
pub mod linear_part;
pub mod model;
pub mod noise;
pub mod pair;
pub mod par;
pub mod rejected;
pub mod result;
pub mod revise;
pub mod search;
pub mod signals;
pub mod spectrum;
pub mod stand;
pub mod summary;
pub mod term;
pub mod thresholds;
pub mod verdict;

use serde_json::Value;

use ctx::Ctx;
pub use error::DiagnoseError;
pub use finding::Finding;
use propid_numerics::outliers::isolated_outliers_of_readings;
use propid_numerics::quality::judge_sample_period;
use propid_numerics::segment::SegmentRules;
use propid_numerics::startup::start_transient;
use propid_wire::record::{names, Record};
pub use result::{
    Diagnosis, Extended, FoldFit, Gain, InputLead, Source, Split, Stage, Traces, Validation,
};
use signals::{Core, Signals};
pub use summary::ModelSummary;

/// Longest sample period diagnosed, s: above it the highest frequency a mode may take
/// ([`model::max_freq_hz`], 0.49/dt) falls below the fit's lowest (1e-6 Hz).
pub const MAX_SAMPLE_PERIOD_S: f64 = 0.49 / 1e-6;

/// Options of a diagnosis.
#[derive(Debug, Clone)]
pub struct Options {
    /// Share of the samples (from the start) used for estimation when the command has no steps;
    /// the rest is validation ([`folds`]).
    pub estimation_fraction: f64,
    /// Most effects named.
    pub max_effects: usize,
    /// The input is a stand's command (a throttle, an ESC signal): its holds are levels by the
    /// motor–propeller's time scale as well as by their sample count
    /// ([`SegmentRules::at_rate`]). `false` for a signal in its own units (a benchmark's pump
    /// voltage: cascaded tanks take minutes to settle), whose holds are levels by the sample
    /// count alone.
    pub input_is_a_command: bool,
    /// The test an effect's held-out gain must pass to be taken ([`folds::Gate`]).
    pub gate: folds::Gate,
    /// Take the stand model as the baseline whenever the record is a stand's and the model
    /// fits, even where the generic search predicts the held-out output better (a simulated
    /// stand's configuration, `diagnose --sim-config`, is a stand model); `why` says so.
    pub prefer_stand: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            estimation_fraction: 0.7,
            max_effects: 3,
            input_is_a_command: true,
            gate: folds::Gate::default(),
            prefer_stand: false,
        }
    }
}

/// Smallest record diagnosed, samples.
pub const MIN_SAMPLES: usize = 200;

/// Diagnoses a record: input `throttle`, output `output` (e.g. `thrust_N`), and the supply
/// voltage `voltage_V` when present. Missing samples are skipped in the fit; the input and the
/// voltage are held at their last value across them.
pub fn diagnose_record(
    rec: &Record,
    output: &str,
    opts: &Options,
) -> Result<Diagnosis, DiagnoseError> {
    let get = |name: &str| -> Result<Vec<f64>, DiagnoseError> {
        let ch = rec
            .channel(name)
            .ok_or_else(|| DiagnoseError::MissingChannel(name.to_string()))?;
        let mut out = Vec::with_capacity(ch.data.len());
        let mut last = f64::NAN;
        for (k, &v) in ch.data.iter().enumerate() {
            let missing = rec.missing.get(k).copied().unwrap_or(false);
            if !v.is_finite() && !missing {
                return Err(DiagnoseError::NonFinite {
                    channel: name.to_string(),
                    index: k,
                });
            }
            out.push(if v.is_finite() { v } else { last });
            if v.is_finite() {
                last = v;
            }
        }
        // Leading gaps take the first measured value.
        if let Some(first) = out.iter().copied().find(|v| v.is_finite()) {
            for v in out.iter_mut().take_while(|v| !v.is_finite()) {
                *v = first;
            }
        }
        Ok(out)
    };
    let u = get(names::THROTTLE)?;
    let mut y = get(output)?;
    for (k, m) in rec.missing.iter().enumerate() {
        if *m && k < y.len() {
            y[k] = f64::NAN;
        }
    }
    let volt = if rec.channel(names::VOLTAGE).is_some() {
        Some(get(names::VOLTAGE)?)
    } else {
        None
    };
    let interpolated = rec.channel(output).map_or(&[][..], |c| &c.interpolated[..]);
    diagnose(rec.dt_s, &u, &y, interpolated, volt.as_deref(), opts)
}

/// Diagnoses sampled signals: input `u` (finite), output `y` (`NaN` = missing), the output's
/// samples a reader interpolated between its readings (`interpolated[k]`; empty: every sample
/// a reading, [`propid_wire::record::Channel::interpolated`]; they count in the fit, not in the
/// noise floor, [`noise`], nor as outliers), optional supply voltage (finite). The output's
/// isolated outliers ([`propid_numerics::outliers`], judged at its readings) and a start-up
/// transient ([`propid_numerics::startup`]) are left out as missing and counted in
/// [`Diagnosis::source`]. See the module doc for the method.
pub fn diagnose(
    dt_s: f64,
    u: &[f64],
    y: &[f64],
    interpolated: &[bool],
    voltage: Option<&[f64]>,
    opts: &Options,
) -> Result<Diagnosis, DiagnoseError> {
    diagnose_with(dt_s, u, y, interpolated, voltage, None, opts)
}

/// [`diagnose`] with the record's stand channels (`stand`, [`stand::StandInput`]): the
/// baseline is the stand model when the data call for it ([`stand::choose`]; `baseline.kind`
/// and `baseline.why` say which and why), the generic 2nd-order model otherwise. On a stand
/// baseline the findings, the held-out figures, the residual and the verdict are the stand
/// search's ([`stand::search`]) on the diagnosed output, `"stand"` has every channel's
/// figures and departures, and the 2nd-order `baseline.model` is still fitted and published
/// (the model the daemon publishes; `extended.model` repeats it).
pub fn diagnose_with(
    dt_s: f64,
    u: &[f64],
    y: &[f64],
    interpolated: &[bool],
    voltage: Option<&[f64]>,
    stand: Option<&stand::StandInput<'_>>,
    opts: &Options,
) -> Result<Diagnosis, DiagnoseError> {
    if !(dt_s.is_finite() && dt_s > 0.0 && dt_s <= MAX_SAMPLE_PERIOD_S) {
        return Err(DiagnoseError::BadSamplePeriod(dt_s));
    }
    let n = u
        .len()
        .min(y.len())
        .min(voltage.map_or(usize::MAX, |v| v.len()));
    if n < MIN_SAMPLES {
        return Err(DiagnoseError::TooShort {
            got: n,
            need: MIN_SAMPLES,
        });
    }
    // A command sampled more slowly than the plant settles shows no dynamics: every finding
    // would be the sampling's (a "dead time" of 11 samples on a 1 Hz table of steady states).
    if opts.input_is_a_command && judge_sample_period(dt_s).is_some() {
        return Err(DiagnoseError::SamplePeriodTooLong(dt_s));
    }
    if let Some(k) = u[..n].iter().position(|v| !v.is_finite()) {
        return Err(DiagnoseError::NonFinite {
            channel: names::THROTTLE.into(),
            index: k,
        });
    }
    if let Some(k) = voltage.and_then(|v| v[..n].iter().position(|x| !x.is_finite())) {
        return Err(DiagnoseError::NonFinite {
            channel: names::VOLTAGE.into(),
            index: k,
        });
    }
    if let Some(k) = y[..n].iter().position(|v| v.is_infinite()) {
        return Err(DiagnoseError::NonFinite {
            channel: "output".into(),
            index: k,
        });
    }
    let (u, y) = (&u[..n], &y[..n]);
    // Isolated outliers are left out like missing samples (the rule of `propid identify` and
    // the daemon, the command's changes guarded): one wrong sample would otherwise be
    // "explained" by an effect or pull every fit. An interpolated output is judged at its
    // readings.
    let missing = y.iter().filter(|v| v.is_nan()).count();
    let found = isolated_outliers_of_readings(y, &[], u, interpolated);
    let mut y_kept = y.to_vec();
    for &k in &found {
        y_kept[k] = f64::NAN;
    }
    // A start-up transient is left out too (the rule of `propid identify`): the output
    // settling under the first level for a reason the command does not show.
    let rules = SegmentRules::for_record(dt_s, opts.input_is_a_command);
    let transient = start_transient(&y_kept, &[], u, &rules).map_or(0, |t| t.end);
    y_kept[..transient].iter_mut().for_each(|v| *v = f64::NAN);
    let y = &y_kept[..];
    let source = Source {
        samples: n,
        missing,
        outliers: found.len(),
        start_up_transient: transient,
    };
    let folds = folds::Folds::from_input(u, y, opts.estimation_fraction, &rules);
    let est = folds.estimation.clone();
    let val = match folds.method {
        folds::Method::Holdout => est.end..n,
        folds::Method::BlockedCv => 0..n,
    };
    check_varies(&u[est.clone()], "input")?;
    check_varies(&y[est.clone()], "output")?;
    if y[val.clone()].iter().filter(|v| v.is_finite()).count() < 10 {
        return Err(DiagnoseError::TooShort {
            got: n,
            need: MIN_SAMPLES,
        });
    }
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    let sig = Signals {
        dt_s,
        u,
        y,
        voltage: voltage.map(|v| &v[..n]),
        u_ref: mean(&u[est.clone()]).max(1e-6),
        v_ref: voltage.map_or(0.0, |v| mean(&v[..n])),
    };
    let ctx = Ctx {
        sig,
        est,
        val,
        rules,
        gate: opts.gate,
    };
    let mut choice = stand::choose(opts.input_is_a_command, stand, &rules);
    let on_stand = match (&choice.kind, stand) {
        (stand::BaselineKind::Stand, Some(s)) => {
            let output = s.output.unwrap_or("thrust");
            let v = voltage.map(|v| &v[..n]);
            match stand::search(dt_s, u, v, s, output, &folds, (rules, opts.gate)) {
                Ok(run) => Some(run),
                Err(e) => {
                    choice = stand::BaselineChoice::generic(format!(
                        "the stand model could not be fitted ({e}): the generic baseline"
                    ));
                    None
                }
            }
        }
        _ => None,
    };
    let era = era_start::era_start(&ctx);
    let starts: Vec<Core> = era.iter().map(|e| e.core).collect();
    let searched = search::search(&ctx, &folds, &starts, opts.max_effects).ok_or_else(|| {
        DiagnoseError::FitFailed {
            core: era.as_ref().err().cloned(),
        }
    })?;
    let floor = noise::measure(u, y, interpolated, &rules);
    let mut d = assemble::assemble(
        &ctx,
        &folds,
        searched,
        era.as_ref().ok(),
        floor.clone().ok(),
    );
    d.source = source;
    // The data decide between the two: the stand model, the physics of a stand, is the
    // baseline unless the generic search's final model predicts the output's held-out folds
    // better by more than their own scatter (the paired test of `folds::HeldOutGain`, on the
    // same folds).
    let on_stand = on_stand.and_then(|run| {
        let stand_fit = run
            .cv
            .channel
            .get(run.report.output)
            .copied()
            .unwrap_or(f64::NAN);
        let generic_fit = d.validation.mean_fit_percent;
        let stand_folds = run
            .cv
            .folds
            .get(run.report.output)
            .cloned()
            .unwrap_or_default();
        let generic_folds: Vec<f64> = d.validation.folds.iter().map(|f| f.fit_percent).collect();
        let generic_better = if stand_folds.len() >= 2 && stand_folds.len() == generic_folds.len()
        {
            folds::HeldOutGain::paired(&stand_folds, &generic_folds, generic_fit - stand_fit)
                .significant()
        } else {
            generic_fit > stand_fit
        };
        if !generic_better || opts.prefer_stand {
            let asked = if generic_better {
                "; taken as asked (a simulated stand's configuration)"
            } else if stand_fit < generic_fit {
                "; the generic search's lead is within the folds' scatter"
            } else {
                ""
            };
            choice.why = format!(
                "{} (held out on {}: {stand_fit:.2} %, the generic search {generic_fit:.2} %{asked})",
                choice.why, run.report.output
            );
            Some(run)
        } else {
            choice = stand::BaselineChoice::generic(format!(
                "a motor stand, yet the generic search predicts the held-out {} better than the \
                 stand model beyond the folds' scatter ({generic_fit:.2} % against \
                 {stand_fit:.2} %): the generic baseline",
                run.report.output
            ));
            None
        }
    });
    d.baseline.choice = choice;
    if let Some(run) = on_stand {
        stand_overlay(&mut d, &folds, run);
    }
    // When no floor was measured the verdict says why (`noise::measure`).
    if let Err(why) = floor {
        d.verdict.reason = format!("{}: {why}", d.verdict.reason);
    }
    Ok(d)
}

/// The stand search's results in the diagnosis (see [`diagnose_with`]): the output's
/// held-out figures fold by fold, the findings and the rejected candidates, the residual and
/// the verdict on them.
fn stand_overlay(d: &mut Diagnosis, folds: &folds::Folds, run: stand::StandRun) {
    let out = run.report.output;
    let fold_fits = |cv: &stand::Cv| cv.folds.get(out).cloned().unwrap_or_default();
    let (bf, ef) = (fold_fits(&run.base_cv), fold_fits(&run.cv));
    let (b, e) = (
        run.base_cv.channel.get(out).copied().unwrap_or(f64::NAN),
        run.cv.channel.get(out).copied().unwrap_or(f64::NAN),
    );
    let rms = |cv: &stand::Cv| {
        let (Some(p), y) = (cv.prediction.get(out), &d.traces.y) else {
            return f64::NAN;
        };
        let (s, n) = y
            .iter()
            .zip(p)
            .filter(|(y, p)| y.is_finite() && p.is_finite())
            .fold((0.0, 0usize), |(s, n), (y, p)| (s + (y - p).powi(2), n + 1));
        (s / n.max(1) as f64).sqrt()
    };
    let (rms_b, rms_e) = (rms(&run.base_cv), rms(&run.cv));
    d.baseline.fit_percent = b;
    d.validation.baseline_mean_fit_percent = b;
    d.validation.mean_fit_percent = e;
    if bf.len() == folds.folds.len() && ef.len() == folds.folds.len() {
        for (i, f) in d.validation.folds.iter_mut().enumerate() {
            f.baseline_fit_percent = bf[i];
            f.fit_percent = ef[i];
        }
    }
    let found = !run.findings.is_empty();
    d.extended = found.then(|| Extended {
        effects: run.report.effects.clone(),
        model: d.baseline.model.clone(),
        fit_percent: e,
    });
    d.gain = found.then(|| Gain {
        fit_percent_points: e - b,
        rms_ratio: rms_e / rms_b.max(1e-300),
    });
    d.residual = verdict::Residual {
        baseline_rms: rms_b,
        extended_rms: found.then_some(rms_e),
    };
    d.verdict = verdict::verdict(d.noise_floor.as_ref(), &d.residual, found);
    d.findings = run.findings;
    d.rejected = run.rejected;
    let fill = |p: Option<&Vec<f64>>, into: &mut Vec<f64>| {
        if let Some(p) = p {
            for (t, v) in into.iter_mut().zip(p) {
                if v.is_finite() {
                    *t = *v;
                }
            }
        }
    };
    let pred = |f: &propid_numerics::stand_model::fit::StructuredFit| {
        f.prediction
            .iter()
            .find(|(k, _)| *k == out)
            .map(|(_, p)| p.clone())
    };
    fill(pred(&run.stand.baseline).as_ref(), &mut d.traces.baseline);
    fill(pred(&run.stand.extended).as_ref(), &mut d.traces.extended);
    d.stand = Some(run.report);
    d.stand_model = Some(run.stand);
}

fn check_varies(x: &[f64], what: &'static str) -> Result<(), DiagnoseError> {
    let fin = x.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = fin.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if hi - lo > 1e-12 * hi.abs().max(1.0) {
        Ok(())
    } else {
        Err(DiagnoseError::Constant(what))
    }
}

/// The findings as JSON values (for tables and tests).
pub fn findings_json(d: &Diagnosis) -> Vec<Value> {
    d.findings
        .iter()
        .map(|f| serde_json::to_value(f).unwrap_or(Value::Null))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_numerics::EffectName;
    use propid_sim::synth;

    /// The object keys of a JSON text in document order (what `--json` prints: derived
    /// structs in field order, maps sorted).
    fn keys_in_order(text: &str) -> Vec<String> {
        let mut keys = Vec::new();
        let mut chars = text.chars().peekable();
        while let Some(c) = chars.next() {
            if c != '"' {
                continue;
            }
            let mut s = String::new();
            while let Some(c) = chars.next() {
                match c {
                    '\\' => {
                        chars.next();
                    }
                    '"' => break,
                    _ => s.push(c),
                }
            }
            if chars.peek() == Some(&':') {
                keys.push(s);
            }
        }
        keys
    }

    #[test]
    fn the_json_shape_is_pinned() {
        let (_, m) = synth::case(Some(EffectName::DeadTime), 0).unwrap();
        let d = diagnose(
            synth::DT_S,
            &m.u,
            &m.y,
            &[],
            Some(&m.voltage),
            &Options::default(),
        )
        .unwrap();
        let text = serde_json::to_string(&d).unwrap();
        assert!(d.validation.folds.len() >= folds::MIN_FOLDS);
        let folds = "samples baseline_fit_percent fit_percent ".repeat(d.validation.folds.len());
        let rejected = "effect score cv_gain_pp reason ".repeat(d.rejected.len());
        let model = "order dt_s fn_hz zeta dc_gain time_constants_s poles_s poles_z a b c d \
                     singular_values indicators msv mac emac mpc cmi msv mac emac mpc cmi \
                     uncertainty fn_hz zeta dc_gain pulses pulses_skipped missing_samples noise_rms \
                     mass_spring_damper m d k hankel_block_rows hankel_block_cols svd terms";
        let want = format!(
            "source samples missing outliers start_up_transient baseline kind why model {model} gain offset fit_percent \
             core_model path fn_hz zeta dc_gain fit_percent \
             findings effect score cv_gain_pp evidence delay_s delay_samples \
             extended effects model {model} delay_s delay_samples gain offset fit_percent \
             gain fit_percent_points rms_ratio split estimation validation \
             validation method folds {folds}baseline_mean_fit_percent mean_fit_percent \
             noise_floor rms from samples residual baseline_rms extended_rms \
             verdict kind unexplained_share reason warnings rejected {rejected}"
        );
        let want: Vec<&str> = want.split_whitespace().collect();
        assert_eq!(keys_in_order(&text), want, "{text}");
        assert!(text.contains(r#"{"effect":"dead_time","score":"#), "{text}");
        assert!(text.contains(r#""extended":{"effects":["dead_time"],"model":{"order":2,"#));
    }

    #[test]
    fn no_effect_of_the_catalogue_is_taken_for_outliers_or_a_start_up_transient() {
        // the detection table's simulated cases: every effect (and none), 20 plants each; an
        // effect must never be left out as isolated outliers or a start-up transient before it
        // can be named (a baseline drift is linear: never a start-up transient)
        let names = std::iter::once(None).chain(effects::names().map(Some));
        for name in names {
            for i in 0..20 {
                let Ok((_, m)) = synth::case(name, i) else {
                    continue;
                };
                let found = propid_numerics::outliers::isolated_outliers(&m.y, &[], &m.u);
                assert!(found.is_empty(), "{name:?} #{i}: {found:?}");
                let t = start_transient(&m.y, &[], &m.u, &SegmentRules::DEFAULT);
                assert_eq!(t, None, "{name:?} #{i}");
            }
        }
    }

    #[test]
    fn a_baseline_that_cannot_be_fitted_carries_the_cores_refusal() {
        use std::error::Error as _;
        let refusal = era_start::CoreRefusal::Unusable {
            fn_hz: f64::NAN,
            zeta: 0.5,
            gain: 1.0,
        };
        let e = DiagnoseError::FitFailed {
            core: Some(refusal.clone()),
        };
        assert_eq!(
            e.to_string(),
            "the 2nd-order baseline could not be fitted to this data"
        );
        let source = e.source().expect("the core's refusal is the source");
        assert_eq!(source.to_string(), refusal.to_string());
        assert!(DiagnoseError::FitFailed { core: None }.source().is_none());
    }
}
