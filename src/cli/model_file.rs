//! Model files on the command line (issue 30): `identify --save` / `diagnose --save` write one
//! (the schema and its checks live in `propid_model`), and
//! `propid compare MODEL DATA [--init-samples N] [--json] [--report DIR]`,
//! `propid simulate MODEL --input CSV [--out FILE]` and
//! `propid params MODEL --for TARGET [...]` read one. This file only reads and writes files;
//! docs/model_file.md and docs/params.md say what the numbers are.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::load::{self as shared, LoadedFile, Request};
use super::read::ReadFlags;
use super::CliError;
use propid_ingest::gaps::{fill_gaps, mark_missing};
use propid_model::file::{Channel, Linear, OperatingPoint, Provenance, Supply};
use propid_model::params::{self, Options, Record, Target};
use propid_model::simulate::{free_run, scores, Which};
use propid_model::{ModelError, ModelFile, SCHEMA};
use propid_wire::record::names;

/// The canonical unit of a record channel (`thrust_N` → `N`), else `fallback`.
pub fn unit_of(channel: &str, fallback: &str) -> String {
    match channel {
        names::THROTTLE => "throttle 0..1".into(),
        names::THRUST => "N".into(),
        names::TORQUE => "N·m".into(),
        names::RPM => "rev/min".into(),
        names::CURRENT => "A".into(),
        names::VOLTAGE => "V".into(),
        _ => fallback.into(),
    }
}

/// A model file's provenance for this run.
pub fn provenance(command: &str, file: &Path, rows: usize, options: Value) -> Provenance {
    let options = match options {
        Value::Object(m) => m
            .into_iter()
            .filter(|(_, v)| !v.is_null())
            .collect::<BTreeMap<_, _>>(),
        _ => BTreeMap::new(),
    };
    Provenance {
        command: command.into(),
        file: file.display().to_string(),
        rows,
        options,
        propid_version: env!("CARGO_PKG_VERSION").into(),
    }
}

/// The mean of the finite samples of `x` not marked in `missing`.
pub fn mean_of(x: &[f64], missing: &[bool]) -> f64 {
    let v: Vec<f64> = x
        .iter()
        .enumerate()
        .filter(|(k, v)| v.is_finite() && !missing.get(*k).copied().unwrap_or(false))
        .map(|(_, v)| *v)
        .collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// A linear section of a report's matrices about `op`.
pub fn linear(m: &propid_numerics::ModelReport, op: OperatingPoint) -> Linear {
    Linear {
        a: m.a.clone(),
        b: m.b.clone(),
        c: m.c.clone(),
        d: m.d.clone(),
        operating_point: op,
    }
}

/// A supply section of a logged voltage.
pub fn supply(v: Option<&[f64]>) -> Option<Supply> {
    v.and_then(Supply::of)
}

/// A channel of the model.
pub fn channel(name: &str, column: &str, unit: &str) -> Channel {
    Channel {
        name: name.into(),
        column: column.into(),
        unit: unit.into(),
    }
}

/// Writes `m` to `path`.
pub fn save(m: &ModelFile, path: &Path) -> Result<(), CliError> {
    let text = m.to_text().map_err(CliError::Model)?;
    std::fs::write(path, text + "\n")
        .map_err(|e| CliError::io(format!("writing the model to {}", path.display()), e))
}

/// Reads the model at `path`.
pub fn read(path: &Path) -> Result<ModelFile, CliError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::io(format!("reading the model {}", path.display()), e))?;
    ModelFile::from_text(&text).map_err(|e| {
        CliError::Model(match e {
            ModelError::NotJson(s) => ModelError::NotJson(format!("{}: {s}", path.display())),
            other => other,
        })
    })
}

/// DATA as the model needs it: its input (gaps held), its outputs (NaN where missing) and the
/// supply voltage when the model reads one.
struct Data {
    dt_s: f64,
    u: Vec<f64>,
    y: Vec<Vec<f64>>,
    voltage: Option<Vec<f64>>,
}

/// Whether a load error says that a channel asked for is absent.
fn lacks_channel(e: &CliError) -> bool {
    use propid_ingest::csv_file::CsvFileError;
    matches!(
        e,
        CliError::Load(super::load::LoadError::NoChannel { .. })
            | CliError::Load(super::load::LoadError::Csv {
                source: CsvFileError::MissingColumn { .. } | CsvFileError::NoCommand { .. },
                ..
            })
    )
}

/// Reads DATA with the model's input and outputs (or those given); a DATA without them is
/// [`CliError::ModelData`].
fn read_data(
    m: &ModelFile,
    file: &Path,
    r: &ReadFlags,
    output: &[String],
    outputs: bool,
) -> Result<Data, CliError> {
    let input = r
        .input
        .clone()
        .or_else(|| (m.input.name != names::THROTTLE).then(|| m.input.column.clone()));
    let outs: Vec<String> = if !output.is_empty() || !outputs {
        output.to_vec()
    } else if m.outputs.len() == 1 && m.outputs[0].name == names::THRUST {
        Vec::new()
    } else {
        m.outputs.iter().map(|c| c.column.clone()).collect()
    };
    let optional = if m.needs_voltage() {
        vec![names::VOLTAGE]
    } else {
        Vec::new()
    };
    let req = Request {
        input: input.as_deref(),
        ..r.request(&outs, &optional)
    };
    let lacking = |detail: String| CliError::ModelData {
        file: file.display().to_string(),
        detail,
    };
    let f: LoadedFile = match shared::load(file, &req) {
        Ok(f) => f,
        Err(e) if lacks_channel(&e) => return Err(lacking(e.to_string())),
        Err(e) => return Err(e),
    };
    let Some(input) = &f.input else {
        return Err(lacking(format!("no input column ({})", m.input.column)));
    };
    let u = fill_gaps(f.data(input));
    let y = f
        .outputs
        .iter()
        .map(|n| {
            let mut y = f.data(n);
            mark_missing(&mut y, &f.record.missing);
            y
        })
        .collect();
    let voltage = match (m.needs_voltage(), f.optional.first()) {
        (false, _) => None,
        (true, Some(n)) => Some(fill_gaps(f.data(n))),
        (true, None) => {
            return Err(lacking(
                "no supply voltage, which the model's supply_sag term reads".into(),
            ))
        }
    };
    if (f.record.dt_s - m.dt_s).abs() > 1e-6 * m.dt_s {
        return Err(lacking(format!(
            "sampled every {} s, the model every {} s (give --fs {})",
            f.record.dt_s,
            m.dt_s,
            1.0 / m.dt_s
        )));
    }
    Ok(Data {
        dt_s: f.record.dt_s,
        u,
        y,
        voltage,
    })
}

/// Arguments of `propid compare`.
#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// A model file (`identify --save`, `diagnose --save`).
    pub model: PathBuf,
    /// The record to compare it with.
    pub data: PathBuf,
    /// Samples of DATA's outputs the initial state is estimated from (not scored).
    #[arg(long, default_value_t = 0)]
    pub init_samples: usize,
    /// Print exactly one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write compare.svg (measured and simulated outputs) into this directory.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Output column, repeatable (default: the model's outputs).
    #[arg(long)]
    pub output: Vec<String>,
    /// How DATA is read (`identify`'s flags; `--input` defaults to the model's input).
    #[command(flatten)]
    pub read: ReadFlags,
}

/// Runs `propid compare`.
pub fn compare(args: CompareArgs) -> Result<(), CliError> {
    let m = read(&args.model)?;
    let d = read_data(&m, &args.data, &args.read, &args.output, true)?;
    let which = Which::default_for(&m);
    let sim = free_run(
        &m,
        which,
        &d.u,
        d.voltage.as_deref(),
        &d.y,
        args.init_samples,
    )
    .map_err(CliError::Model)?;
    let from = args.init_samples.min(d.u.len());
    let outs = scores(&m, &d.y, &sim, from);
    if let Some(dir) = &args.report {
        report(dir, &m, &d, &sim)
            .map_err(|e| CliError::io(format!("writing the report into {}", dir.display()), e))?;
    }
    if args.json {
        let v = json!({
            "outputs": outs,
            "init_samples": args.init_samples,
            "model": which,
            "model_file": args.model.display().to_string(),
            "data": args.data.display().to_string(),
            "samples": d.u.len(),
        });
        return super::stdout::line(&v.to_string());
    }
    let mut t = format!(
        "model  {} ({:?}, from {} of {})\ndata   {} ({} samples; state from the first {})\n",
        args.model.display(),
        which,
        m.provenance.command,
        m.provenance.file,
        args.data.display(),
        d.u.len(),
        args.init_samples
    );
    for o in &outs {
        t.push_str(&format!(
            "{:<12} RMS {:.6} {}   fit {:.2} %  ({} samples)\n",
            o.name, o.rms, o.unit, o.fit_percent, o.samples
        ));
    }
    super::stdout::write(&t)
}

/// compare.svg: each output measured and simulated against time.
fn report(dir: &Path, m: &ModelFile, d: &Data, sim: &[Vec<f64>]) -> std::io::Result<()> {
    use plotters::style::RGBColor;
    std::fs::create_dir_all(dir)?;
    for (i, (ch, (y, s))) in m.outputs.iter().zip(d.y.iter().zip(sim)).enumerate() {
        let t = |v: &[f64]| -> Vec<(f64, f64)> {
            v.iter()
                .enumerate()
                .map(|(k, v)| (k as f64 * d.dt_s, *v))
                .collect()
        };
        let series = [
            ("measured", t(y), RGBColor(90, 90, 90)),
            ("simulated", t(s), RGBColor(200, 40, 40)),
        ];
        let name = if i == 0 {
            "compare.svg".to_string()
        } else {
            format!("compare_{i}.svg")
        };
        if let Some(svg) = propid_report::diagnose::plot(
            &format!("{}: measured and free-run simulation", ch.name),
            "time (s)",
            &ch.unit,
            &series,
            false,
            false,
        )? {
            std::fs::write(dir.join(name), svg)?;
        }
    }
    Ok(())
}

/// Arguments of `propid simulate`.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// A model file.
    pub model: PathBuf,
    /// The CSV (or recording) whose input column (the model's) drives the model.
    #[arg(long = "input", value_name = "CSV")]
    pub data: PathBuf,
    /// Write the CSV here instead of stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Sample rate, Hz (needed without a time column).
    #[arg(long)]
    pub fs: Option<f64>,
    /// Column names for a CSV file without a header, comma separated.
    #[arg(long, value_delimiter = ',')]
    pub columns: Option<Vec<String>>,
    /// ESC pulse range for throttle columns in µs, `MIN,MAX` (default 1000,2000).
    #[arg(long, value_delimiter = ',')]
    pub esc_us: Option<Vec<f64>>,
    /// Raw command values at throttle 0 and 1, `MIN,MAX`.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub input_range: Option<Vec<f64>>,
}

/// Runs `propid simulate`: `t_s`, the input and each simulated output as CSV.
pub fn simulate(args: SimulateArgs) -> Result<(), CliError> {
    let m = read(&args.model)?;
    let r = ReadFlags {
        input: None,
        fs: args.fs,
        columns: args.columns.clone(),
        esc_us: args.esc_us.clone(),
        input_range: args.input_range.clone(),
        poles: None,
    };
    let d = read_data(&m, &args.data, &r, &[], false)?;
    let which = Which::default_for(&m);
    let sim = free_run(&m, which, &d.u, d.voltage.as_deref(), &[], 0).map_err(CliError::Model)?;
    let mut t = format!("t_s,{}", m.input.name);
    for o in &m.outputs {
        t.push_str(&format!(",{}", o.name));
    }
    t.push('\n');
    for (k, u) in d.u.iter().enumerate() {
        t.push_str(&format!("{},{u}", k as f64 * d.dt_s));
        for s in &sim {
            t.push_str(&format!(",{}", s[k]));
        }
        t.push('\n');
    }
    match &args.out {
        Some(p) => {
            std::fs::write(p, t).map_err(|e| CliError::io(format!("writing {}", p.display()), e))
        }
        None => super::stdout::write(&t),
    }
}

/// Arguments of `propid params`.
#[derive(Debug, clap::Args)]
pub struct ParamsArgs {
    /// A model file (`identify --save`).
    pub model: PathBuf,
    /// ardupilot, px4, betaflight, gazebo, px4-sih or paparazzi.
    #[arg(long = "for", value_parser = parse_target)]
    pub target: Target,
    /// All-up weight, kg (ArduPilot's MOT_THST_HOVER).
    #[arg(long)]
    pub auw_kg: Option<f64>,
    /// Motors (MOT_THST_HOVER; Paparazzi's per-actuator list).
    #[arg(long)]
    pub motors: Option<u32>,
    /// ArduPilot's MOT_SPIN_MIN (default: suggested from the record), Betaflight's idle.
    #[arg(long)]
    pub spin_min: Option<f64>,
    /// ArduPilot's MOT_SPIN_MAX (default 0.95).
    #[arg(long)]
    pub spin_max: Option<f64>,
    /// The controller's output pulse at actuator 0, µs (default 1000).
    #[arg(long, default_value_t = 1000.0)]
    pub pwm_min: f64,
    /// The controller's output pulse at actuator 1, µs (default 2000).
    #[arg(long, default_value_t = 2000.0)]
    pub pwm_max: f64,
    /// Print the parameters as JSON.
    #[arg(long)]
    pub json: bool,
}

fn parse_target(s: &str) -> Result<Target, String> {
    Target::parse(s).ok_or_else(|| {
        "expected ardupilot, px4, betaflight, gazebo, px4-sih or paparazzi".to_string()
    })
}

/// The record's command range in µs from a file's provenance (the `input_range` read in µs),
/// else 1000..2000.
fn record_us(m: &ModelFile) -> [f64; 2] {
    let o = &m.provenance.options;
    let from = o
        .get("input_range_from")
        .and_then(Value::as_str)
        .unwrap_or("");
    match o.get("input_range").and_then(Value::as_array) {
        Some(r) if from.contains("µs") || from.contains("esc-us") => {
            let v: Vec<f64> = r.iter().filter_map(Value::as_f64).collect();
            if v.len() == 2 {
                [v[0], v[1]]
            } else {
                [1000.0, 2000.0]
            }
        }
        _ => [1000.0, 2000.0],
    }
}

/// The parameters' options of a model and the flags.
pub fn options(m: Option<&ModelFile>, a: Option<&ParamsArgs>) -> Options {
    let mut o = Options {
        record_us: m.map_or([1000.0, 2000.0], record_us),
        ..Options::default()
    };
    if let Some(a) = a {
        o.auw_kg = a.auw_kg;
        o.motors = a.motors;
        o.spin_min = a.spin_min;
        o.spin_max = a.spin_max;
        o.pwm = [a.pwm_min, a.pwm_max];
    }
    o
}

/// Runs `propid params`.
pub fn params(args: ParamsArgs) -> Result<(), CliError> {
    if args.pwm_max.is_nan() || args.pwm_min.is_nan() || args.pwm_max <= args.pwm_min {
        return Err(CliError::Model(ModelError::Invalid(format!(
            "--pwm-min {} must be below --pwm-max {}",
            args.pwm_min, args.pwm_max
        ))));
    }
    let m = read(&args.model)?;
    let rec = Record {
        stand: m.stand.as_ref(),
        static_map: &m.static_map,
        supply: m.supply.as_ref(),
    };
    let p = params::params(args.target, &rec, &options(Some(&m), Some(&args)));
    if args.json {
        let v = json!({"for": args.target, "params": p, "schema": SCHEMA});
        return super::stdout::line(&v.to_string());
    }
    super::stdout::write(&params::render(args.target, &p, args.motors.unwrap_or(4)))
}
