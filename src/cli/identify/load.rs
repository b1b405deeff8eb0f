//! FILE → input, outputs and a description of where they came from.

use serde::Serialize;

use super::Args;
use crate::cli::CliError;
use crate::ingest::csv_file::{read_csv, CsvFileOptions, CsvSource};
use crate::ingest::steps::{find_steps, FoundStep};
use crate::ingest::{read_record_with, IngestOptions, IngestStats};
use crate::protocol::detect::{detect, Detection, WireFormat};
use crate::record::names;

/// What `identify` works on.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// Sample period, s.
    pub dt_s: f64,
    /// The input (throttle, a chosen column, or the levels of the steps found).
    pub input: Vec<f64>,
    /// The outputs.
    pub outputs: Vec<Vec<f64>>,
    /// Missing samples.
    pub missing: Vec<bool>,
    /// Device pulse starts (TSP/1 events), if any.
    pub pulse_starts: Option<Vec<usize>>,
    /// Description for the output.
    pub source: Source,
}

/// `"source"` in the JSON output.
#[derive(Debug, Clone, Serialize)]
pub struct Source {
    /// The file as given.
    pub file: String,
    /// `"csv"` or `"tsp1"`.
    pub format: &'static str,
    /// The input column, or `"steps found from the response"`.
    pub input: String,
    /// The output columns.
    pub outputs: Vec<String>,
    /// Sample rate used, Hz.
    pub rate_hz: f64,
    /// Samples in the record.
    pub samples: usize,
    /// Samples marked missing.
    pub missing: usize,
    /// `"pulse"` or `"okid"` (filled in after identification).
    pub path: &'static str,
    /// TSP/1 decoding counters (binary recordings).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tsp1: Option<IngestStats>,
    /// CSV details (columns, time base, jitter, skipped rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub csv: Option<CsvSource>,
    /// Steps found from the response (when the file has no input column).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<Vec<StepOut>>,
    /// The OKID regression (when that path was taken).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub okid: Option<crate::core::okid::select::OkidSummary>,
}

/// A step found from the response, with its time.
#[derive(Debug, Clone, Serialize)]
pub struct StepOut {
    /// Sample index of the command change.
    pub sample: usize,
    /// Its time, s.
    pub t_s: f64,
    /// Level before, output units.
    pub from: f64,
    /// Level after, output units.
    pub to: f64,
}

/// Reads FILE as the options say.
pub fn load(args: &Args) -> Result<Loaded, CliError> {
    let name = args.file.display().to_string();
    let bytes =
        std::fs::read(&args.file).map_err(|e| CliError::io(format!("reading {name}"), e))?;
    if bytes.is_empty() {
        return Err(CliError::Input(format!("{name}: the file is empty")));
    }
    match detect(&bytes, true) {
        Detection::Format(WireFormat::Binary) => load_tsp(args, name, &bytes),
        _ => load_csv(args, name, &bytes),
    }
}

fn load_csv(args: &Args, name: String, bytes: &[u8]) -> Result<Loaded, CliError> {
    let text = String::from_utf8_lossy(bytes);
    let esc_us = match args.esc_us.as_deref() {
        Some([lo, hi]) => Some((*lo, *hi)),
        Some(_) => return Err(CliError::Usage("--esc-us takes MIN,MAX".into())),
        None => None,
    };
    let opts = CsvFileOptions {
        input: args.input.clone(),
        outputs: args.output.clone(),
        fs_hz: args.fs,
        columns: args.columns.clone(),
        esc_us,
        motor_poles: None,
    };
    let file = read_csv(&text, &opts).map_err(|e| CliError::Input(format!("{name}: {e}")))?;
    let rec = &file.record;
    let outputs: Vec<Vec<f64>> = file
        .outputs
        .iter()
        .filter_map(|n| rec.channel(n).map(|c| c.data.clone()))
        .collect();
    let (input, input_name, steps) = match &file.input {
        Some(n) => {
            let data = rec.channel(n).map(|c| c.data.clone()).unwrap_or_default();
            let label = file.source.input.clone().unwrap_or_else(|| n.clone());
            (data, label, None)
        }
        None => {
            let f = find_steps(&outputs[0]).ok_or_else(|| {
                CliError::Identification(format!("{name}: too short to find steps in"))
            })?;
            if f.steps.is_empty() {
                return Err(CliError::Identification(format!(
                    "{name}: no input column and no step found in the response \
                     (give --input NAME, or a record with steps)"
                )));
            }
            let steps = f.steps.iter().map(|s| step_out(s, rec.t0_s, rec.dt_s));
            let label = "steps found from the response".to_string();
            (f.input, label, Some(steps.collect()))
        }
    };
    Ok(Loaded {
        dt_s: rec.dt_s,
        input,
        outputs,
        missing: rec.missing.clone(),
        pulse_starts: None,
        source: Source {
            file: name,
            format: "csv",
            input: input_name,
            outputs: file.source.outputs.clone(),
            rate_hz: file.source.rate_hz,
            samples: rec.len(),
            missing: rec.missing_count(),
            path: "",
            tsp1: None,
            csv: Some(file.source),
            steps,
            okid: None,
        },
    })
}

/// A binary TSP/1 recording: channels by canonical name (`--input`, `--output` pick others),
/// device impulse events as pulse starts.
fn load_tsp(args: &Args, name: String, bytes: &[u8]) -> Result<Loaded, CliError> {
    let opts = IngestOptions {
        fs_hz: args.fs,
        ..IngestOptions::default()
    };
    let (rec, stats) =
        read_record_with(bytes, &opts).map_err(|e| CliError::Input(format!("{name}: {e}")))?;
    let pick = |want: &str| {
        rec.channel(want).map(|c| c.data.clone()).ok_or_else(|| {
            let have: Vec<&str> = rec.channels.iter().map(|c| c.name.as_str()).collect();
            CliError::Input(format!(
                "{name}: no channel {want}; the recording has {}",
                have.join(", ")
            ))
        })
    };
    let input_name = args.input.clone().unwrap_or(names::THROTTLE.into());
    let output_names = if args.output.is_empty() {
        vec![names::THRUST.to_string()]
    } else {
        args.output.clone()
    };
    let input = pick(&input_name)?;
    let outputs = output_names
        .iter()
        .map(|n| pick(n))
        .collect::<Result<Vec<_>, _>>()?;
    let starts: Vec<usize> = rec.impulse_starts().collect();
    Ok(Loaded {
        dt_s: rec.dt_s,
        input,
        outputs,
        missing: rec.missing.clone(),
        pulse_starts: (!starts.is_empty()).then_some(starts),
        source: Source {
            file: name,
            format: "tsp1",
            input: input_name,
            outputs: output_names,
            rate_hz: 1.0 / rec.dt_s,
            samples: rec.len(),
            missing: rec.missing_count(),
            path: "",
            tsp1: Some(stats),
            csv: None,
            steps: None,
            okid: None,
        },
    })
}

fn step_out(s: &FoundStep, t0: f64, dt: f64) -> StepOut {
    StepOut {
        sample: s.sample,
        t_s: t0 + s.sample as f64 * dt,
        from: s.from,
        to: s.to,
    }
}
