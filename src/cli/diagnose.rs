//! `propid diagnose FILE [--json] [--report DIR]`: what the 2nd-order model gets wrong, why,
//! and how much an extended model gains on held-out data (issue 5). FILE is a TSP/1 recording
//! (binary or CSV dialect) or any CSV form `propid identify` reads; the supply voltage is used
//! when the file has one.

use propid_report::diagnose as report;

use std::fmt::Write as _;
use std::path::PathBuf;

use super::load::{self as shared, Request};
use super::read::ReadArgs;
#[cfg(test)]
use super::read::ReadFlags;
use super::{CliError, UsageError};
use propid_diagnose::file::{json, signals, Signals, DEFAULT_OUTPUT, OPTIONAL};
use propid_diagnose::noise::FloorSource;
use propid_diagnose::verdict::VerdictKind;
use propid_diagnose::{self as diagnose, DiagnoseError, Diagnosis};

/// Arguments of `propid diagnose`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// FILE and how to read it (the flags every command that reads a file shares; one
    /// `--output`).
    #[command(flatten)]
    pub read: ReadArgs,
    /// Print exactly one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Write a Markdown page with SVG plots into this directory.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Share of the samples (from the start) used for estimation, 0.3..0.9.
    #[arg(long, default_value_t = 0.7)]
    pub estimation_fraction: f64,
    /// Write the stand diagnose fitted (the stand baseline with the effects it took) as a
    /// `propid sim` configuration to OUT.toml (`propid sim --config OUT.toml --replay-command
    /// FILE`; docs/stand-model.md).
    #[arg(long, value_name = "OUT.toml")]
    pub sim_config: Option<PathBuf>,
    /// Write the final model to this file (docs/model_file.md).
    #[arg(long)]
    pub save: Option<PathBuf>,
}

/// Runs `propid diagnose`.
pub fn run(args: Args) -> Result<(), CliError> {
    if !(0.3..=0.9).contains(&args.estimation_fraction) {
        return Err(UsageError::EstimationFraction(args.estimation_fraction).into());
    }
    let s = load(&args)?;
    let opts = diagnose::Options {
        estimation_fraction: args.estimation_fraction,
        // The simulated stand is a stand model: `--sim-config` takes the stand baseline.
        prefer_stand: args.sim_config.is_some(),
        ..Default::default()
    };
    let d = s.diagnose(&opts)?;
    let written = match &args.sim_config {
        Some(out) => {
            let req = args.read.how.request(&args.read.output, &[]);
            let reported = d.stand.as_ref().map_or_else(Default::default, |st| {
                let f = st
                    .channels
                    .iter()
                    .map(|(k, c)| (k.to_string(), c.fit_percent));
                f.collect()
            });
            let (file, stand) = (&args.read.file, d.stand_baseline());
            Some(super::stand_log::write_config(
                file, &req, out, stand, reported,
            )?)
        }
        None => None,
    };
    if let Some(path) = &args.save {
        super::model_file::save(&model_file(&args, &s, &d)?, path)?;
    }
    if let Some(dir) = &args.report {
        let title = args.read.file.display().to_string();
        report::render(&title, &s.output_name, &d)
            .and_then(|files| {
                std::fs::create_dir_all(dir)?;
                files
                    .iter()
                    .try_for_each(|(name, text)| std::fs::write(dir.join(name), text))
            })
            .map_err(|e| CliError::io(format!("writing the report into {}", dir.display()), e))?;
    }
    if args.json {
        let mut v = json(&d, &s.file).map_err(CliError::DiagnosisJson)?;
        if let (Some(w), Some(obj)) = (&written, v.as_object_mut()) {
            let w = serde_json::to_value(w).map_err(CliError::DiagnosisJson)?;
            obj.insert("sim_config".into(), w);
        }
        super::stdout::line(&v.to_string())
    } else {
        let mut text = summary(&args, &s, &d);
        if let Some(w) = &written {
            let _ = writeln!(text, "{}", w.line());
        }
        super::stdout::write(&text)
    }
}

/// The model file of a diagnosis: its final model (extended, else the baseline) exactly, and
/// its linear part about the reference throttle.
fn model_file(
    args: &Args,
    s: &Signals,
    d: &Diagnosis,
) -> Result<propid_model::ModelFile, CliError> {
    use super::model_file::{self as mf, channel, unit_of};
    let model = &d.traces.model;
    let extended =
        propid_model::terms::extended_of(model, d.traces.refs).map_err(CliError::Model)?;
    let summary = d.extended.as_ref().map_or(&d.baseline.model, |e| &e.model);
    let u0 = d.traces.refs[0];
    let op = propid_model::file::OperatingPoint {
        input: u0,
        outputs: vec![model.core.offset + model.core.gain * u0],
    };
    let options = serde_json::json!({
        "estimation_fraction": args.estimation_fraction,
        "fs": args.read.fs,
        "columns": args.read.columns,
        "esc_us": args.read.esc_us,
        "input_range": s.file.read.input_range,
        "input_range_from": s.file.read.input_range_from,
        "poles": args.read.poles,
        "split": d.split,
    });
    let raw = |col: &str| {
        s.file
            .read
            .units
            .as_ref()
            .and_then(|u| u.values().find(|c| c.column == col))
            .map_or(String::new(), |c| c.unit.clone())
    };
    Ok(propid_model::ModelFile {
        schema: propid_model::SCHEMA.into(),
        checksum: String::new(),
        provenance: mf::provenance("diagnose", &args.read.file, s.u.len(), options),
        dt_s: s.dt_s,
        input: channel(
            &s.input_name,
            &s.file.input,
            &unit_of(&s.input_name, &raw(&s.file.input)),
        ),
        outputs: vec![channel(
            &s.output_name,
            &s.file.output,
            &unit_of(&s.output_name, &raw(&s.file.output)),
        )],
        linear: Some(mf::linear(&summary.report, op)),
        extended: Some(extended),
        stand: None,
        static_map: serde_json::Value::Object(Default::default()),
        supply: mf::supply(s.voltage.as_deref()),
    })
}

/// Whether a diagnosis error is the input's fault (exit 3) rather than the data not supporting
/// an identification (exit 4).
pub(crate) fn is_input_error(e: &DiagnoseError) -> bool {
    matches!(
        e,
        DiagnoseError::MissingChannel(_)
            | DiagnoseError::NonFinite { .. }
            | DiagnoseError::BadSamplePeriod(_)
    )
}

/// The human summary of a diagnosis (writing into a `String` cannot fail).
fn summary(args: &Args, s: &Signals, d: &Diagnosis) -> String {
    let mut t = String::new();
    let b = &d.baseline;
    let _ = writeln!(
        t,
        "{}: {} → {}, {} samples at {:.4} s",
        args.read.file.display(),
        s.input_name,
        s.output_name,
        s.u.len(),
        s.dt_s
    );
    if let Some(line) = s.file.read.input_range_line() {
        let _ = writeln!(t, "input {}: {line}", s.file.input);
    }
    if let Some(line) = s.file.read.units_line() {
        let _ = writeln!(t, "units {line}");
    }
    if d.source.outliers > 0 {
        let _ = writeln!(
            t,
            "outliers: {} isolated sample(s) of the output left out (marked missing)",
            d.source.outliers
        );
    }
    if d.source.start_up_transient > 0 {
        let _ = writeln!(
            t,
            "start-up transient: the first {} samples ({:.3} s) left out (marked missing): the \
             output was still settling under the first command level",
            d.source.start_up_transient,
            d.source.start_up_transient as f64 * s.dt_s
        );
    }
    let _ = writeln!(t, "{}", d.validation.describe(&d.split));
    let scored = match b.choice.kind {
        diagnose::stand::BaselineKind::Generic => "validation fit",
        diagnose::stand::BaselineKind::Stand => "the stand baseline's validation fit",
    };
    let _ = writeln!(
        t,
        "baseline 2nd order: fn {:.3} Hz, zeta {:.3}, dc gain {:.4}; {scored} {:.2} %",
        b.model.report.fn_hz,
        b.model.report.zeta,
        b.model.report.dc_gain.get(0),
        b.fit_percent
    );
    let kind = match b.choice.kind {
        diagnose::stand::BaselineKind::Stand => "stand model",
        diagnose::stand::BaselineKind::Generic => "generic 2nd order",
    };
    let _ = writeln!(t, "baseline: {kind}: {}", b.choice.why);
    if let Some(st) = &d.stand {
        let _ = writeln!(
            t,
            "stand model: held-out fit {:.2} % (mean over its channels; reference channel {}), \
             {:.2} % with the effects found",
            st.baseline_mean_fit_percent, st.reference_channel, st.mean_fit_percent
        );
        for (key, c) in &st.channels {
            let _ = writeln!(
                t,
                "  {key}: held-out fit {:.2} → {:.2} %; where the stand simulation departs: {}",
                c.baseline_fit_percent,
                c.fit_percent,
                c.departures.line()
            );
        }
    }
    if let Some(l) = &d.input_lead {
        let _ = writeln!(
            t,
            "input lead {:.2} sample ({:.1} ms): the output answers a command within the \
             command's own sample (a logger that reads the sensor after sending the command \
             and writes both on one row, or an input sampled rather than held), so the models \
             take each input sample as acting that much before its row",
            l.samples,
            1e3 * l.seconds
        );
    }
    if let Some(c) = &b.core_model {
        let _ = writeln!(
            t,
            "  (identification core, {:?} path: fn {:.3} Hz, zeta {:.3}, fit {:.2} %)",
            c.path, c.fn_hz, c.zeta, c.fit_percent
        );
    }
    if d.findings.is_empty() && d.verdict.kind == VerdictKind::Explained {
        let _ = writeln!(
            t,
            "no effect found: the 2nd-order model explains the data to the noise"
        );
    } else if d.findings.is_empty() {
        let _ = writeln!(t, "no effect in the catalogue found");
    }
    for f in &d.findings {
        let _ = writeln!(
            t,
            "- {} (score {:.0}, held-out gain {:+.2} points): {}",
            f.effect, f.score, f.cv_gain_pp, f.evidence
        );
    }
    for r in &d.rejected {
        let held_out = r
            .cv_gain_pp
            .map_or(String::new(), |g| format!(", held-out {g:+.2} points"));
        let _ = writeln!(
            t,
            "- not taken: {} (score {:.0}{held_out}): {}",
            r.effect, r.score, r.reason
        );
    }
    if let (Some(e), Some(g)) = (&d.extended, &d.gain) {
        let _ = writeln!(
            t,
            "extended by {}: validation fit {:.2} % ({:+.2} points, residual RMS × {:.3})",
            e.effects
                .iter()
                .map(|e| e.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            e.fit_percent,
            g.fit_percent_points,
            g.rms_ratio
        );
    }
    match &d.noise_floor {
        Some(f) => {
            let from = match f.from {
                FloorSource::SteadyHolds => "steady holds",
                FloorSource::HighOrderFit => "high-order fit",
            };
            let _ = writeln!(
                t,
                "noise floor {:.4} (from {from}, {} samples)",
                f.rms, f.samples
            );
        }
        None => {
            let _ = writeln!(t, "noise floor: could not be measured");
        }
    }
    let kind = match d.verdict.kind {
        VerdictKind::Explained => "explained",
        VerdictKind::EffectsFound => "effects found",
        VerdictKind::Unexplained => "UNEXPLAINED",
    };
    let _ = writeln!(t, "verdict: {kind}: {}", d.verdict.reason);
    for w in &d.warnings {
        let _ = writeln!(t, "warning: {}", w.message);
    }
    t
}

/// Reads FILE with the loader `propid identify` uses ([`crate::cli::load`]; the output
/// defaults to thrust, the supply voltage and the stand's channels are read when the file has
/// them), then makes the [`Signals`] diagnose works on ([`signals`]).
pub fn load(args: &Args) -> Result<Signals, CliError> {
    let read = &args.read;
    if read.output.len() > 1 {
        return Err(UsageError::OneOutput.into());
    }
    let outputs = [read
        .output
        .first()
        .cloned()
        .unwrap_or(DEFAULT_OUTPUT.into())];
    let req = Request {
        outputs: &outputs,
        ..read.request(&OPTIONAL)
    };
    let file = shared::load(&read.file, &req)?;
    signals(&file, read.input.as_deref()).map_err(|cause| CliError::NoInput {
        file: file.name.clone(),
        cause,
        hint: "give --input NAME",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_response_without_steps_and_without_input_is_an_identification_error() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("flat.csv");
        let rows: String = (0..300)
            .map(|k| format!("{},1.0\n", k as f64 * 0.01))
            .collect();
        std::fs::write(&file, format!("t_s,thrust_N\n{rows}")).unwrap();
        let args = Args {
            read: ReadArgs {
                file,
                how: ReadFlags {
                    input: Some("none".into()),
                    ..ReadFlags::default()
                },
                ..ReadArgs::default()
            },
            json: true,
            report: None,
            estimation_fraction: 0.7,
            sim_config: None,
            save: None,
        };
        let e = load(&args).unwrap_err();
        assert_eq!(e.exit_code(), 4, "{e}");
        assert!(e.to_string().ends_with("(give --input NAME)"), "{e}");
    }
}
