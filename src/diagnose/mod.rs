//! Model discrepancy (issue 5): show where the 2nd-order simulation departs from the
//! measurement, name the physical cause, extend the model with it and measure the gain on data
//! the models were not fitted on.
//!
//! 1. **Split.** The first 70 % of the samples are the estimation part, the rest is held out
//!    for validation ([`Split`]).
//! 2. **Baseline.** A 2nd-order output-error model `T'' + 2ζωn T' + ωn² T = ωn² K u` plus an
//!    offset, exactly discretised (ZOH), fitted by least squares on the simulation error
//!    ([`fit`]); simulated over the whole record from the input alone, its fit on the validation
//!    part is `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)`.
//! 3. **Catalogue** ([`catalogue`]): each effect extends the model ([`model`]); its score is a
//!    likelihood ratio; the forward search names the effects that pass the threshold.
//! 4. **Extended model**: the model with every effect found, validated on the same samples;
//!    the gain is the difference of fit percentages and the ratio of residual RMS.
//!
//! The detector sees only the measured signals (input, output, and the supply voltage when the
//! record has one), never the simulator's configuration.

pub mod catalogue;
pub mod era_start;
pub mod fit;
pub mod model;
pub mod report;
pub mod result;
pub mod spectrum;

use serde_json::{json, Map, Value};

use catalogue::{Ctx, EFFECTS, MIN_RMS_DROP, SCORE_THRESHOLD};
use fit::Fit;
use model::{ix, Signals, Spec};
use propid_wire::record::{names, Record};
pub use result::{Diagnosis, Extended, Finding, Gain, ModelSummary, Split, Stage, Traces};

/// Why a diagnosis could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    /// A channel the diagnosis needs is absent.
    #[error("the record has no `{0}` channel (diagnose needs the input and one output)")]
    MissingChannel(String),
    /// Too few samples.
    #[error("the record has {got} usable samples, diagnose needs at least {need}")]
    TooShort {
        /// Samples present.
        got: usize,
        /// Samples needed.
        need: usize,
    },
    /// A NaN or infinite value where the record does not mark a missing sample.
    #[error(
        "channel `{channel}` has a non-finite value at sample {index} that is not marked missing"
    )]
    NonFinite {
        /// Channel name.
        channel: String,
        /// Sample index.
        index: usize,
    },
    /// The sample period is not a positive number of at most [`MAX_SAMPLE_PERIOD_S`].
    #[error(
        "the sample period {0} s is outside 0 < dt <= 490000 s (a time column in ns read as s?)"
    )]
    BadSamplePeriod(f64),
    /// Input or output does not vary: nothing to identify.
    #[error("the {0} is constant on the estimation part: nothing to identify")]
    Constant(&'static str),
    /// The baseline fit failed (non-finite residuals).
    #[error("the 2nd-order baseline could not be fitted to this data")]
    FitFailed,
}

/// Longest sample period diagnosed, s: above it the highest frequency a mode may take
/// ([`model::max_freq_hz`], 0.49/dt) falls below the fit's lowest (1e-6 Hz).
pub const MAX_SAMPLE_PERIOD_S: f64 = 0.49 / 1e-6;

/// Options of a diagnosis.
#[derive(Debug, Clone)]
pub struct Options {
    /// Share of the samples (from the start) used for estimation; the rest is validation.
    pub estimation_fraction: f64,
    /// Most effects named.
    pub max_effects: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            estimation_fraction: 0.7,
            max_effects: 3,
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
    diagnose(rec.dt_s, &u, &y, volt.as_deref(), opts)
}

/// Diagnoses sampled signals: input `u` (finite), output `y` (`NaN` = missing), optional
/// supply voltage (finite). See the module doc for the method.
pub fn diagnose(
    dt_s: f64,
    u: &[f64],
    y: &[f64],
    voltage: Option<&[f64]>,
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
    let frac = opts.estimation_fraction.clamp(0.3, 0.9);
    let n_est = ((n as f64) * frac).round() as usize;
    let est = 0..n_est;
    let val = n_est..n;
    let (u, y) = (&u[..n], &y[..n]);
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
        v_ref: voltage.map_or(0.0, |v| mean(&v[est.clone()])),
    };
    let ctx = Ctx { sig, est, val };
    let mut spec0 = Spec::default();
    let mut findings = Vec::new();
    let mut found: Vec<String> = Vec::new();
    if let Some((level, count)) = catalogue::sensor_clip(&ctx) {
        spec0.clip_sensor = Some(level);
        findings.push(sensor_finding(level, count, ctx.est.len()));
        found.push("saturation".into());
    }
    let era = era_start::era_start(&ctx);
    let era_starts: Vec<model::Params> = era.iter().map(|e| e.params).collect();
    let base = catalogue::baseline(&ctx, Spec::default(), &era_starts);
    if !base.sse.is_finite() || base.n == 0 {
        return Err(DiagnoseError::FitFailed);
    }
    let mut cur = if spec0.clip_sensor.is_some() {
        catalogue::baseline(&ctx, spec0, &era_starts)
    } else {
        base
    };
    while found.len() < opts.max_effects {
        let val_cur = ctx.val_sse(&cur);
        let mut best: Option<(f64, &str, Fit)> = None;
        for name in EFFECTS {
            if found.iter().any(|f| f == name) {
                continue;
            }
            let Some(f) = catalogue::extend(&ctx, &cur, name) else {
                continue;
            };
            let usable = f.sse.is_finite() && f.sse > 0.0 && cur.sse > 0.0;
            if !(usable && catalogue::plausible(&ctx, name, &f)) {
                continue;
            }
            let score = f.n as f64 * (cur.sse / f.sse).ln();
            let rms_drop = 1.0 - (f.sse / cur.sse).sqrt();
            let passes =
                score >= SCORE_THRESHOLD && rms_drop >= MIN_RMS_DROP && ctx.val_sse(&f) < val_cur;
            if passes && best.as_ref().map_or(true, |b| score > b.0) {
                best = Some((score, name, f));
            }
        }
        let Some((score, name, f)) = best else { break };
        findings.push(finding(name, score, &cur, &f, &ctx));
        found.push(name.to_string());
        cur = f;
    }
    Ok(assemble(&ctx, &base, &cur, findings, found, era))
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

/// Validation fit percent and residual RMS of a fit.
fn validate(ctx: &Ctx, f: &Fit, sim: &mut Vec<f64>) -> (f64, f64) {
    sim.resize(ctx.sig.u.len(), 0.0);
    model::simulate(&f.spec, &f.params, &ctx.sig, sim);
    let ys: Vec<f64> = ctx
        .val
        .clone()
        .filter(|&k| ctx.sig.y[k].is_finite())
        .collect::<Vec<_>>()
        .iter()
        .map(|&k| ctx.sig.y[k])
        .collect();
    let mean = ys.iter().sum::<f64>() / ys.len().max(1) as f64;
    let mut e2 = 0.0;
    let mut d2 = 0.0;
    let mut m = 0usize;
    for k in ctx.val.clone() {
        let yk = ctx.sig.y[k];
        if yk.is_finite() {
            e2 += (yk - sim[k]).powi(2);
            d2 += (yk - mean).powi(2);
            m += 1;
        }
    }
    let fit = 100.0 * (1.0 - (e2 / d2.max(1e-300)).sqrt());
    (fit, (e2 / m.max(1) as f64).sqrt())
}

fn assemble(
    ctx: &Ctx,
    base: &Fit,
    cur: &Fit,
    findings: Vec<Finding>,
    found: Vec<String>,
    era: Option<era_start::EraStart>,
) -> Diagnosis {
    let dt = ctx.sig.dt_s;
    let mut sim_b = Vec::new();
    let mut sim_e = Vec::new();
    let (fit_b, rms_b) = validate(ctx, base, &mut sim_b);
    let core = era.as_ref().map(|e| &e.report);
    let core_model = era.as_ref().map(|e| {
        let q = era_start::with_offset(ctx, &e.params);
        let f = Fit {
            spec: Spec::default(),
            params: q,
            sse: 0.0,
            n: 0,
        };
        let (fit, _) = validate(ctx, &f, &mut sim_e);
        era_start::summary(&q, e.path, fit)
    });
    let baseline = Stage {
        model: ModelSummary::from_fit(base, dt, core),
        fit_percent: fit_b,
        core_model,
    };
    let (extended, gain) = if found.is_empty() {
        sim_e = sim_b.clone();
        (None, None)
    } else {
        let (fit_e, rms_e) = validate(ctx, cur, &mut sim_e);
        let ext = Extended {
            effects: found,
            model: ModelSummary::from_fit(cur, dt, core),
            fit_percent: fit_e,
        };
        let gain = Gain {
            fit_percent_points: fit_e - fit_b,
            rms_ratio: rms_e / rms_b.max(1e-300),
        };
        (Some(ext), Some(gain))
    };
    Diagnosis {
        baseline,
        findings,
        extended,
        gain,
        split: Split {
            estimation: [ctx.est.start, ctx.est.end],
            validation: [ctx.val.start, ctx.val.end],
        },
        traces: Traces {
            dt_s: dt,
            u: ctx.sig.u.to_vec(),
            y: ctx.sig.y.to_vec(),
            baseline: sim_b,
            extended: sim_e,
        },
    }
}

fn sensor_finding(level: f64, count: usize, n: usize) -> Finding {
    let mut params = Map::new();
    params.insert("level".into(), json!(level));
    params.insert("signal".into(), json!("sensor"));
    Finding {
        effect: "saturation".into(),
        score: count as f64,
        evidence: format!(
            "the output reads exactly {level:.6} on {count} of {n} estimation samples and never more: \
             the sensor clips there (flat tops where the response should peak)"
        ),
        params,
    }
}

/// The finding for effect `name`: parameters from the extended fit, evidence in words.
fn finding(name: &str, score: f64, before: &Fit, after: &Fit, ctx: &Ctx) -> Finding {
    let v = &after.params.v;
    let dt = ctx.sig.dt_s;
    let rms = |f: &Fit| (f.sse / f.n.max(1) as f64).sqrt();
    let drop = format!(
        "the estimation residual RMS falls from {:.4} to {:.4} ({:.0} % lower)",
        rms(before),
        rms(after),
        100.0 * (1.0 - rms(after) / rms(before).max(1e-300))
    );
    let mut p = Map::new();
    let evidence = match name {
        "dead_time" => {
            let d = after.spec.delay;
            p.insert("delay_s".into(), json!(d as f64 * dt));
            p.insert("delay_samples".into(), json!(d));
            format!(
                "the output starts to move {d} samples ({:.1} ms) after the throttle does; \
                 with the input delayed by that much {drop}",
                1e3 * d as f64 * dt
            )
        }
        "static_nonlinearity" => {
            let e = v[ix::EXPONENT];
            let how = if e > 1.0 { "hardens" } else { "softens" };
            p.insert("exponent".into(), json!(e));
            p.insert("curvature".into(), json!(how));
            let (lo, hi) = throttle_span(ctx);
            let g = |u: f64| v[ix::GAIN] * e * (u / ctx.sig.u_ref).powf(e - 1.0);
            format!(
                "the small-signal gain changes with the operating point ({:.3} per unit throttle at \
                 {lo:.2}, {:.3} at {hi:.2}): the static map follows throttle^{e:.2} and {how}; \
                 with that map before the linear part {drop}",
                g(lo),
                g(hi)
            )
        }
        "extra_mode" => {
            p.insert("fn_hz".into(), json!(v[ix::MODE_FN]));
            p.insert("zeta".into(), json!(v[ix::MODE_ZETA]));
            p.insert("gain".into(), json!(v[ix::MODE_GAIN]));
            format!(
                "the residual rings at {:.2} Hz (damping {:.3}) after every input change, which a \
                 2nd-order model cannot produce; with a series mode there (4th order) {drop}",
                v[ix::MODE_FN],
                v[ix::MODE_ZETA]
            )
        }
        "baseline_drift" => {
            p.insert("rate_per_s".into(), json!(v[ix::DRIFT]));
            format!(
                "the output creeps by {:.5} units per second ({:.4} over the record) whatever the \
                 input does; with a drift term {drop}",
                v[ix::DRIFT],
                v[ix::DRIFT] * ctx.sig.u.len() as f64 * dt
            )
        }
        "periodic_disturbance" => {
            let a = v[ix::SIN_A].hypot(v[ix::SIN_B]);
            p.insert("freq_hz".into(), json!(v[ix::SIN_FREQ]));
            p.insert("amplitude".into(), json!(a));
            format!(
                "a steady {:.3} Hz oscillation of amplitude {a:.4} runs through the residual, \
                 unrelated to the input (a line in the residual spectrum); with a sinusoid term {drop}",
                v[ix::SIN_FREQ]
            )
        }
        "supply_sag" => {
            p.insert("gain_per_volt".into(), json!(v[ix::GAIN_PER_VOLT]));
            let (lo, hi) = ctx.sig.voltage.map_or((0.0, 0.0), |x| {
                x.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                        (a.min(v), b.max(v))
                    })
            });
            format!(
                "the gain follows the supply voltage ({:+.1} % per volt while the supply ranged \
                 {lo:.2}..{hi:.2} V); with a voltage-scaled input {drop}",
                100.0 * v[ix::GAIN_PER_VOLT]
            )
        }
        "saturation" => {
            let l = v[ix::CLIP];
            p.insert("level".into(), json!(l));
            p.insert("signal".into(), json!("throttle"));
            let above = ctx.sig.u.iter().filter(|&&x| x > l).count();
            format!(
                "throttle above {l:.3} gives no more thrust ({above} samples above that level respond \
                 as if at it); with the throttle clipped there {drop}"
            )
        }
        _ => drop,
    };
    Finding {
        effect: name.to_string(),
        score,
        evidence,
        params: p,
    }
}

/// 10th and 90th percentile of the throttle.
fn throttle_span(ctx: &Ctx) -> (f64, f64) {
    let mut u: Vec<f64> = ctx.sig.u.to_vec();
    u.sort_by(|a, b| a.total_cmp(b));
    let q = |f: f64| u[((u.len() - 1) as f64 * f) as usize];
    (q(0.1), q(0.9))
}

/// The findings as JSON values (for tables and tests).
pub fn findings_json(d: &Diagnosis) -> Vec<Value> {
    d.findings
        .iter()
        .map(|f| serde_json::to_value(f).unwrap_or(Value::Null))
        .collect()
}
