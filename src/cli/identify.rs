//! `propid identify FILE [--order N] [--json] [--input NAME] [--output NAME]... [--fs HZ]
//! [--svd auto|dense|truncated]`: a model from a TSP/1 recording or a CSV file, by the pulse path
//! for a clean pulse experiment and by OKID otherwise.
//!
//! With `--json` exactly one JSON object: `{"model": {...}, "source": {...},
//! "operating_points": [...]}`; `"model"` holds the fields of
//! [`ModelReport`](crate::core::ModelReport) (`dc_gain` a number for one output, a list for
//! several), `"source"` says which file format, columns, rate and path were used, and
//! `"operating_points"` is the gain schedule (one model per level, where the data allows).

mod load;
mod summary;

use std::path::PathBuf;

use super::CliError;
use crate::core::okid::select::{identify_any, AnyError, AnyInput};
use crate::core::okid::OkidOptions;
use crate::core::operating_points::{operating_points, OpOptions};
use crate::core::svd::SvdChoice;
use crate::core::workspace::IdentOptions;

/// Arguments of `propid identify`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A TSP/1 recording (raw bytes) or a CSV file.
    pub file: PathBuf,
    /// Model order (default: chosen from the singular values).
    #[arg(long)]
    pub order: Option<usize>,
    /// Print exactly one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Input column (default: the throttle column; none: steps are found from the response).
    #[arg(long)]
    pub input: Option<String>,
    /// Output column, repeatable (default: thrust).
    #[arg(long)]
    pub output: Vec<String>,
    /// Sample rate, Hz (needed without a time column; resamples onto this rate otherwise).
    #[arg(long)]
    pub fs: Option<f64>,
    /// SVD path: auto, dense or truncated.
    #[arg(long, default_value = "auto", value_parser = parse_svd)]
    pub svd: SvdChoice,
    /// Column names for a CSV file without a header, comma separated.
    #[arg(long, value_delimiter = ',')]
    pub columns: Option<Vec<String>>,
    /// ESC pulse range for throttle columns in µs, `MIN,MAX` (default 1000,2000).
    #[arg(long, value_delimiter = ',')]
    pub esc_us: Option<Vec<f64>>,
}

fn parse_svd(s: &str) -> Result<SvdChoice, String> {
    match s {
        "auto" => Ok(SvdChoice::Auto),
        "dense" => Ok(SvdChoice::Dense),
        "truncated" => Ok(SvdChoice::Truncated),
        _ => Err(format!("expected auto, dense or truncated, got {s:?}")),
    }
}

/// Runs `propid identify`.
pub fn run(args: Args) -> Result<(), CliError> {
    let loaded = load::load(&args)?;
    let ident = IdentOptions {
        order: args.order,
        svd: args.svd,
        ..IdentOptions::default()
    };
    let u: Vec<&[f64]> = vec![loaded.input.as_slice()];
    let y: Vec<&[f64]> = loaded.outputs.iter().map(|c| c.as_slice()).collect();
    let input = AnyInput {
        dt_s: loaded.dt_s,
        u: &u,
        y: &y,
        missing: &loaded.missing,
        pulse_starts: loaded.pulse_starts.as_deref(),
    };
    let model = identify_any(&input, &ident, &OkidOptions::default()).map_err(ident_error)?;
    let ops = operating_points(&input, &ident, &OpOptions::default());
    let out = summary::Output::new(&loaded, &model, &ops);
    if args.json {
        println!(
            "{}",
            out.json().map_err(|e| CliError::Input(e.to_string()))?
        );
    } else {
        print!("{}", out.human());
    }
    Ok(())
}

fn ident_error(e: AnyError) -> CliError {
    CliError::Identification(e.to_string())
}
