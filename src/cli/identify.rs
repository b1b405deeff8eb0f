//! `propid identify FILE [--order N] [--json] [--report DIR] [--input NAME] [--output NAME]...
//! [--fs HZ] [--svd auto|dense|truncated] [--hankel auto|square|RxC]`: a model from a TSP/1
//! recording or a CSV file, by the pulse path for a clean pulse experiment and by OKID
//! otherwise.
//!
//! With `--json` exactly one JSON object: `{"model": {...}, "source": {...},
//! "operating_points": [...], "steps": [...], "static_map": {...}, "stabilization": {...}}`;
//! `"model"` holds the fields of [`ModelReport`](propid_numerics::ModelReport) (`dc_gain` a
//! number for one output, a list for several), `"source"` says which file format, columns,
//! rate and path were used, `"operating_points"` is the gain schedule (one model per level,
//! where the data allows) and `"stabilization"` the stabilization diagram of the model's Hankel
//! SVD ([`propid_numerics::stabilization`]; null when it cannot be realised).
//!
//! `"quality"` says whether the model passed the checks of [`propid_numerics::quality`] (the
//! daemon's rule: no pole with `Re(s) ≥ 0`, a DC gain larger than its jackknife scatter; and,
//! when the record has steady levels, a DC gain with their sign and size:
//! `dc_gain_contradicts_levels`, its hint naming both numbers); a
//! rejected model is still printed, with `"accepted": false`, its `"flaws"` and a `"hint"`, and
//! `identify` exits 4 (the data do not support an identification), as the daemon publishes it
//! as a `model_unreliable` warning instead of a model. `"warnings"` lists implausible results
//! that do not reject the model: `nonpositive_gain` (a DC gain `≤ 0` under a command: more
//! command, less output — a reversed load cell or a wrong model; the rule of `diagnose`,
//! [`propid_numerics::quality::nonpositive_gain`]), also printed in the summary. Isolated outlier samples of the outputs
//! ([`propid_numerics::outliers`]) are left out (marked missing) before identification and
//! counted in `"source"."outliers"`.
//!
//! `--report DIR` writes `stabilization.svg` (the diagram) and `identify.md` into `DIR`.
//!
//! `--hankel` sizes ERA's Hankel matrix: `auto` (default) from the noise floor, `square` the
//! largest near-square one the Markov sequence allows (`r = c ≈ (L − 1)/2` blocks), `RxC`
//! explicit block counts. The size used is `model.hankel_block_rows`/`hankel_block_cols`.
//! Large sizes take the truncated FFT + Lanczos SVD (O(N) memory; `docs/svd.md`).

mod report;
mod save;

pub use propid_report::identify::{load, stand, summary, Physics};
pub use stand::brief as stand_brief;
pub use summary::Quality;

use std::path::PathBuf;

use super::load::NoSteps;
use super::read::ReadArgs;
use super::CliError;
use propid_numerics::identify::{identify_any_with, AnyInput};
use propid_numerics::okid::OkidOptions;
use propid_numerics::operating_points::{operating_points, OpOptions};
use propid_numerics::order::HankelSize;
use propid_numerics::output_error::{self, SelectOptions};
use propid_numerics::segment::Command;
use propid_numerics::stabilization::StabOptions;
use propid_numerics::stand::{
    response_step_figures, stand_figures, steady_levels, OutputChannel, StandFigures,
};
use propid_numerics::static_map::{level_slope, LevelSlope};
use propid_numerics::svd::SvdChoice;
use propid_numerics::workspace::IdentOptions;

/// Arguments of `propid identify`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// FILE and how to read it (the flags every command that reads a file shares).
    #[command(flatten)]
    pub read: ReadArgs,
    /// Model order (0 or omitted: chosen from the singular values, as `order = 0` in the
    /// config).
    #[arg(long)]
    pub order: Option<usize>,
    /// Print exactly one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Write the stabilization diagram (stabilization.svg) and identify.md into this directory.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// SVD path: auto, dense or truncated.
    #[arg(long, default_value = "auto", value_parser = parse_svd)]
    pub svd: SvdChoice,
    /// Hankel size: auto (from the noise floor), square (largest near-square) or RxC blocks.
    #[arg(long, default_value = "auto", value_parser = parse_hankel)]
    pub hankel: HankelSize,
    /// Write the model to this file (docs/model_file.md).
    #[arg(long)]
    pub save: Option<PathBuf>,
}

fn parse_svd(s: &str) -> Result<SvdChoice, String> {
    match s {
        "auto" => Ok(SvdChoice::Auto),
        "dense" => Ok(SvdChoice::Dense),
        "truncated" => Ok(SvdChoice::Truncated),
        _ => Err(format!("expected auto, dense or truncated, got {s:?}")),
    }
}

/// Parses `auto`, `square` or `RxC` (block rows × columns, both >= 1).
fn parse_hankel(s: &str) -> Result<HankelSize, String> {
    match s {
        "auto" => return Ok(HankelSize::Auto),
        "square" => return Ok(HankelSize::Square),
        _ => {}
    }
    let bad = || format!("expected auto, square or RxC (e.g. 64x64), got {s:?}");
    let (r, c) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let r: usize = r.trim().parse().map_err(|_| bad())?;
    let c: usize = c.trim().parse().map_err(|_| bad())?;
    if r == 0 || c == 0 {
        return Err(format!(
            "Hankel block rows and columns must be >= 1, got {s:?}"
        ));
    }
    Ok(HankelSize::Blocks(r, c))
}

/// Runs `propid identify`.
pub fn run(args: Args) -> Result<(), CliError> {
    let mut loaded = read(&args)?;
    load::leave_out_outliers(&mut loaded);
    load::leave_out_start_transient(&mut loaded);
    let rules = loaded.segment_rules();
    let ident = IdentOptions {
        // 0 is automatic, as in the config (`identify.order = 0`).
        order: args.order.filter(|&n| n > 0),
        svd: args.svd,
        max_pulse_width: rules.max_pulse_samples,
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
    let stab = StabOptions::default();
    let okid = OkidOptions::default();
    let model = identify_any_with(&input, &ident, &okid, args.hankel, Some(&stab));
    let stand = stand_for(&loaded);
    let physics = Physics::of(&loaded);
    let mut model = match model {
        Ok(m) => m,
        Err(e) => {
            // The steps and the static map do not need a model: print them with the failure
            // stated, and keep exit 4 (no identification) so that a script never takes the
            // figures for a model.
            if !(stand.steps.is_empty() && stand.static_map.is_empty()) {
                let partial = summary::Partial::new(&loaded, &e, &stand, &physics);
                if args.json {
                    super::stdout::line(&partial.json().map_err(CliError::Json)?)?;
                } else {
                    super::stdout::write(&partial.human())?;
                }
            }
            return Err(e.into());
        }
    };
    // The output-error refinement (docs/benchmarks.md) of a record whose input is a signal in
    // its own units (not a stand's command: the stand's models stay the daemon's): replaces the
    // realisation only where it simulates the held-out tail of the record better.
    let refinement = (!loaded.input_is_a_command)
        .then(|| output_error::refine(&input, &model, &SelectOptions::default()))
        .flatten();
    let refined = refinement.as_ref().filter(|r| r.applied).map(|r| &r.model);
    if let Some(m) = refined {
        output_error::apply(&mut model.report, m);
    }
    let op_opts = OpOptions {
        segment: rules,
        ..OpOptions::default()
    };
    let ops = operating_points(&input, &ident, &op_opts);
    let levels = levels_slope(&loaded);
    let mut out = summary::Output::new(&loaded, &model, &ops, &stand, levels.as_ref(), &physics);
    out.refinement = refinement
        .as_ref()
        .map(serde_json::to_value)
        .transpose()
        .map_err(CliError::Json)?;
    let saved = save::model_file(&args, &loaded, &model.report, &out, refined)?;
    out.params = save::params(&saved);
    if let Some(path) = &args.save {
        super::model_file::save(&saved, path)?;
    }
    if let Some(dir) = &args.report {
        report::write(dir, &out)
            .map_err(|e| CliError::io(format!("writing the report into {}", dir.display()), e))?;
    }
    if args.json {
        super::stdout::line(&out.json().map_err(CliError::Json)?)?;
    } else {
        super::stdout::write(&out.human())?;
    }
    if out.quality.accepted {
        Ok(())
    } else {
        Err(CliError::ModelRejected {
            flaws: out.quality.names(),
        })
    }
}

/// The least-squares slope of the identified output's steady levels under the identified input
/// (the levels the static map reads, [`steady_levels`]; for any input, a command or a named
/// column): the gain the model's is judged against (`None` without levels).
fn levels_slope(loaded: &load::Loaded) -> Option<LevelSlope> {
    let y = loaded.outputs.first()?;
    let cmd = Command::with_missing(&loaded.input, &loaded.missing);
    level_slope(&steady_levels(cmd, &loaded.segment_rules(), y))
}

/// Reads FILE as the options say: the shared loader ([`crate::cli::load`]), then what identify
/// keeps of it ([`load::load`]).
fn read(args: &Args) -> Result<load::Loaded, CliError> {
    let file = args.read.load_window(&load::OPTIONAL)?;
    load::load(file).map_err(|e| match e.cause {
        NoSteps::TooShort => CliError::StepsTooShort { file: e.file },
        cause @ NoSteps::NoneFound => CliError::NoInput {
            file: e.file,
            cause,
            hint: "give --input NAME, or a record with steps",
        },
    })
}

/// The step figures and static maps of `args.file` as `identify` computes them (they need no
/// model): for the real-data tables.
pub fn stand_of(args: &Args) -> Result<StandFigures, CliError> {
    Ok(stand_for(&read(args)?))
}

/// The step figures and static maps of a loaded file: none when its input is a column that
/// is no command; only the steps' figures, timed from the response, when the steps were found
/// from the response ([`response_step_figures`]).
fn stand_for(loaded: &load::Loaded) -> StandFigures {
    if !loaded.commanded {
        if loaded.source.steps.is_none() {
            return StandFigures::default();
        }
        return StandFigures {
            command: "response",
            steps: response_step_figures(
                &loaded.input,
                loaded.dt_s,
                &loaded.segment_rules(),
                loaded.outputs.first().map_or(&[][..], Vec::as_slice),
            ),
            ..StandFigures::default()
        };
    }
    stand_figures(
        Command::with_missing(&loaded.input, &loaded.missing),
        loaded.dt_s,
        &loaded.segment_rules(),
        loaded.outputs.first().map_or(&[][..], Vec::as_slice),
        &loaded
            .stand
            .iter()
            .map(|(key, unit, y)| OutputChannel { key, unit, y })
            .collect::<Vec<_>>(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hankel_sizes_parse() {
        assert_eq!(parse_hankel("auto"), Ok(HankelSize::Auto));
        assert_eq!(parse_hankel("square"), Ok(HankelSize::Square));
        assert_eq!(parse_hankel("40x60"), Ok(HankelSize::Blocks(40, 60)));
        for bad in ["0x5", "5x0", "5", "x", "ax3", "-1x2", "big"] {
            assert!(parse_hankel(bad).is_err(), "{bad}");
        }
    }
}
