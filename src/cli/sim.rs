//! `propid sim`: the simulated stand on a pseudo-terminal, or a recording written faster than
//! real time.
//!
//! On a pty, the first line on stdout is the device path to open (the `--link` if given); when
//! the stand stops (Ctrl-C, `--seconds`, or a hang-up without re-open) one JSON line with the
//! runner's report follows (`{"type":"sim_stats", ...}`: boots, firmware and fault counters).
//! With `--record FILE --seconds S` the firmware and the host's experiment plan run in one loop
//! on a simulated clock and the device's bytes go to FILE; stdout gets one JSON summary line.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use super::{CliError, UsageError};
use propid_sim::config::WireProtocol;
use propid_sim::pty::{self, RunOptions};
use propid_sim::{plant_pipe, record, SimConfig};

/// Arguments of `propid sim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (default: config/sim.toml when it exists, else built-in defaults).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Make a symlink at PATH to the pty slave (re-pointed after a hang-up and re-open).
    #[arg(long, value_name = "PATH")]
    pub link: Option<PathBuf>,
    /// Stop after S seconds (with --record: simulated seconds at most; the recording ends 0.5 s
    /// after the experiment plan is over if that comes first).
    #[arg(long, value_name = "S")]
    pub seconds: Option<f64>,
    /// Inject the configured faults only during the first S seconds (on a pty; then a clean
    /// tail, so that a host can read everything before the stand stops: scripts/soak.sh).
    #[arg(long, value_name = "S")]
    pub faults_for: Option<f64>,
    /// Write a recording (raw device bytes) of the experiment plan to FILE, faster than real
    /// time, instead of opening a pty. Needs --seconds.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// Serve the configured plant on stdin/stdout for an emulated firmware (firmware/harness):
    /// one throttle (0..1) per line in, one `thrust torque rpm voltage current` line out, a
    /// 1 ms step each; no pty, no firmware.
    #[arg(long, conflicts_with_all = ["record", "link"])]
    pub plant_pipe: bool,
    /// Replay LOG's command through the configured plant at LOG's rows (without the thrust's
    /// noise) and write what the stand measures to --out, in LOG's columns and units; stdout
    /// gets one JSON line with each channel's fit against LOG (docs/stand-model.md).
    #[arg(long, value_name = "LOG", requires = "out",
          conflicts_with_all = ["record", "link", "plant_pipe"])]
    pub replay_command: Option<PathBuf>,
    /// The CSV file `--replay-command` writes.
    #[arg(long, value_name = "SIM.csv", requires = "replay_command")]
    pub out: Option<PathBuf>,
    /// How LOG is read (`identify`'s options).
    #[command(flatten)]
    pub read: Box<super::read::ReadFlags>,
    /// Overrides of config keys (boxed: keeps the binary's command enum small).
    #[command(flatten)]
    pub set: Box<Overrides>,
}

/// Command-line overrides of `config/sim.toml` keys.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct Overrides {
    /// Override stand.seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Override stand.sample_rate_hz (Hz).
    #[arg(long, value_name = "HZ")]
    pub rate: Option<u32>,
    /// Override stand.protocol ("tsp" or "csv").
    #[arg(long, value_parser = ["tsp", "csv"])]
    pub protocol: Option<String>,
    /// Override stand.initial_t_us (µs; near 4294967295 makes the device clock wrap soon).
    #[arg(long, value_name = "US")]
    pub initial_t_us: Option<u32>,
    /// Fault: probability per output byte of a flipped bit (faults.bit_flip_per_byte).
    #[arg(long, value_name = "P")]
    pub bit_flips: Option<f64>,
    /// Fault: garbage bursts per second (faults.garbage_bursts_per_s).
    #[arg(long, value_name = "RATE")]
    pub garbage: Option<f64>,
    /// Fault: bytes per garbage burst (faults.garbage_burst_bytes).
    #[arg(long, value_name = "N")]
    pub garbage_bytes: Option<u32>,
    /// Fault: probability per SAMPLE that it is dropped (faults.drop_sample_prob).
    #[arg(long, value_name = "P")]
    pub drop_samples: Option<f64>,
    /// Fault: probability per SAMPLE that a burst of dropped SAMPLEs starts
    /// (faults.drop_burst_prob).
    #[arg(long, value_name = "P")]
    pub drop_burst: Option<f64>,
    /// Fault: SAMPLEs dropped per burst (faults.drop_burst_samples).
    #[arg(long, value_name = "N")]
    pub drop_burst_samples: Option<u32>,
    /// Fault: stalls per second (faults.stalls_per_s).
    #[arg(long, value_name = "RATE")]
    pub stalls: Option<f64>,
    /// Fault: stall length, ms (faults.stall_ms).
    #[arg(long, value_name = "MS")]
    pub stall_ms: Option<u32>,
    /// Fault: hang up after S seconds (faults.hangup_after_s).
    #[arg(long, value_name = "S")]
    pub hangup_after: Option<f64>,
    /// Fault: hang up every S seconds of the run, re-opening after --reopen-after
    /// (faults.hangup_every_s).
    #[arg(long, value_name = "S")]
    pub hangup_every: Option<f64>,
    /// Fault: reset the device every S seconds of the run, the port kept open: a new boot id
    /// (faults.reset_every_s).
    #[arg(long, value_name = "S")]
    pub reset_every: Option<f64>,
    /// Fault: re-open as a new boot MS ms after a hang-up (faults.reopen_after_ms; <0 never).
    #[arg(long, value_name = "MS", allow_negative_numbers = true)]
    pub reopen_after: Option<i64>,
    /// Fault: freeze after S seconds, the port kept open, until the host closes it
    /// (faults.freeze_after_s).
    #[arg(long, value_name = "S")]
    pub freeze_after: Option<f64>,
}

/// Runs `propid sim`.
pub fn run(args: Args) -> Result<(), CliError> {
    let cfg = load_config(&args)?;
    let positive = |s: f64| s.is_finite() && s > 0.0;
    if let Some(s) = args.seconds.filter(|&s| !positive(s)) {
        return Err(UsageError::Seconds(s).into());
    }
    if let Some(s) = args.faults_for.filter(|&s| !positive(s)) {
        return Err(UsageError::FaultsFor(s).into());
    }
    if args.plant_pipe {
        return run_plant_pipe(&cfg);
    }
    if let (Some(log), Some(out)) = (&args.replay_command, &args.out) {
        return run_replay(&cfg, log, out, &args.read);
    }
    match &args.record {
        Some(file) => run_record(&cfg, file, &args),
        None => run_pty(&cfg, &args),
    }
}

/// The configuration with the command-line overrides applied, validated.
pub fn load_config(args: &Args) -> Result<SimConfig, CliError> {
    let default = Path::new("config/sim.toml");
    let mut cfg = match &args.config {
        Some(p) => SimConfig::load(p)?,
        None if default.exists() => SimConfig::load(default)?,
        None => SimConfig::default(),
    };
    let o = &args.set;
    let s = &mut cfg.stand;
    set(&mut s.seed, o.seed);
    set(&mut s.sample_rate_hz, o.rate);
    set(&mut s.initial_t_us, o.initial_t_us);
    if let Some(p) = &o.protocol {
        s.protocol = if p == "csv" {
            WireProtocol::Csv
        } else {
            WireProtocol::Tsp
        };
    }
    let f = &mut cfg.faults;
    set(&mut f.bit_flip_per_byte, o.bit_flips);
    set(&mut f.garbage_bursts_per_s, o.garbage);
    set(&mut f.garbage_burst_bytes, o.garbage_bytes);
    set(&mut f.drop_sample_prob, o.drop_samples);
    set(&mut f.drop_burst_prob, o.drop_burst);
    set(&mut f.drop_burst_samples, o.drop_burst_samples);
    set(&mut f.stalls_per_s, o.stalls);
    set(&mut f.stall_ms, o.stall_ms);
    set(&mut f.hangup_after_s, o.hangup_after);
    set(&mut f.reopen_after_ms, o.reopen_after);
    set(&mut f.freeze_after_s, o.freeze_after);
    set(&mut f.hangup_every_s, o.hangup_every);
    set(&mut f.reset_every_s, o.reset_every);
    cfg.validate()?;
    Ok(cfg)
}

fn set<T>(slot: &mut T, v: Option<T>) {
    if let Some(v) = v {
        *slot = v;
    }
}

fn run_record(cfg: &SimConfig, file: &Path, args: &Args) -> Result<(), CliError> {
    let seconds = args.seconds.ok_or(UsageError::RecordNeedsSeconds)?;
    let f = std::fs::File::create(file)
        .map_err(|e| CliError::io(format!("creating {}", file.display()), e))?;
    let mut w = std::io::BufWriter::new(f);
    let summary = record::record(cfg, seconds, &mut w)?;
    let mut line = serde_json::json!({ "type": "sim_record", "file": file.display().to_string() });
    if let (Some(obj), Ok(serde_json::Value::Object(s))) =
        (line.as_object_mut(), serde_json::to_value(&summary))
    {
        obj.extend(s);
    }
    super::stdout::line(&line.to_string())
}

fn run_replay(
    cfg: &SimConfig,
    log: &Path,
    out: &Path,
    read: &super::read::ReadFlags,
) -> Result<(), CliError> {
    let log_file = super::stand_log::read(log, &read.request(&[], &[]))?;
    let (sim, voltage) = log_file.replay(&cfg.plant)?;
    std::fs::write(out, log_file.csv(&sim, &voltage))
        .map_err(|e| CliError::io(format!("writing {}", out.display()), e))?;
    let line = serde_json::json!({
        "type": "sim_replay",
        "file": out.display().to_string(),
        "log": log.display().to_string(),
        "rows": log_file.command.len(),
        "fit_percent": log_file.score(&sim, &log_file.folds()),
    });
    super::stdout::line(&line.to_string())
}

fn run_plant_pipe(cfg: &SimConfig) -> Result<(), CliError> {
    let mut plant = propid_sim::plant::Plant::new(&cfg.plant, plant_pipe::STEP_S, cfg.stand.seed)
        .map_err(propid_sim::SimError::from)?;
    let stats = plant_pipe::serve(
        &mut plant,
        std::io::stdin().lock(),
        std::io::stdout().lock(),
    )
    .map_err(|e| CliError::io("serving the plant on stdin/stdout".to_string(), e))?;
    eprintln!(
        "propid sim: plant pipe ended after {} steps ({} bad lines)",
        stats.steps, stats.bad_lines
    );
    Ok(())
}

fn run_pty(cfg: &SimConfig, args: &Args) -> Result<(), CliError> {
    let stop = Arc::new(AtomicBool::new(false));
    let s2 = Arc::clone(&stop);
    // A second Ctrl-C while stopping exits at once.
    let _ = ctrlc::set_handler(move || {
        if s2.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    let opts = RunOptions {
        link: args.link.clone(),
        seconds: args.seconds,
        faults_for: args.faults_for,
    };
    let mut print_err = None;
    let report = pty::run(cfg, &opts, &stop, |p, slave| {
        if let Err(e) = super::stdout::line(&p.display().to_string()) {
            print_err.get_or_insert(e);
        }
        let via = if p == slave {
            String::new()
        } else {
            format!(" (link {})", p.display())
        };
        eprintln!(
            "propid sim: stand on {}{via}, {} Hz, {:?}",
            slave.display(),
            cfg.stand.sample_rate_hz,
            cfg.stand.protocol
        );
    })?;
    if let Some(l) = &args.link {
        let _ = std::fs::remove_file(l);
    }
    if let Some(e) = print_err {
        return Err(e);
    }
    let mut line = serde_json::json!({ "type": "sim_stats" });
    if let (Some(obj), Ok(serde_json::Value::Object(s))) =
        (line.as_object_mut(), serde_json::to_value(&report))
    {
        obj.extend(s);
    }
    super::stdout::line(&line.to_string())
}
