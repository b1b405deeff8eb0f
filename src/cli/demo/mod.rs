//! `propid demo`: the whole main job with no hardware and no set-up.
//!
//! Starts the simulated stand on a pseudo-terminal inside this process (the same firmware and
//! the same serial source as with a real stand), runs the daemon against it for about ten
//! seconds — handshake, arm, three operating points, one-sample pulses of alternating sign,
//! identification after every K pulses — and prints each published model beside the
//! simulator's true parameters, then the gain schedule. `--json` prints the daemon's JSON lines
//! instead. Both come from the publisher's tap ([`Publisher::with_tap`]): the typed lines as
//! they are published, and their bytes; nothing is parsed back.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::{stdout, CliError};
use crate::daemon::identify::CoreIdentifier;
use crate::daemon::line::{Line, ScheduleRow, WindowModel};
use crate::daemon::plan;
use crate::daemon::publish::Tap;
use crate::daemon::runner::{self, RunParts};
use crate::daemon::source::SerialSource;
use crate::daemon::{Config, Publisher, Shutdown};
use propid_sim::plant::PlantConfig;
use propid_sim::pty::{RunOptions, SimHandle};
use propid_sim::SimConfig;

/// Arguments of `propid demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Simulated stand configuration (config/sim.toml format); built-in demo stand without it.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// Print the daemon's JSON lines instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// The demo's stand: the default plant sampled at 250 Hz (one-sample pulses carry more energy
/// at a lower rate, so ten seconds give tight models).
fn demo_sim() -> SimConfig {
    let mut s = SimConfig::default();
    s.stand.sample_rate_hz = 250;
    s.experiment = demo_experiment(&s);
    s
}

/// Three operating points, eight pulses each (±0.10, ±0.15), ~9 s in all.
fn demo_experiment(s: &SimConfig) -> propid_wire::experiment::ExperimentConfig {
    let mut e = s.experiment.clone();
    e.levels = vec![0.3, 0.45, 0.6];
    e.pulse_amplitudes = vec![0.1, 0.15];
    e.ramp_ms = 300;
    e.settle_ms = 500;
    e.pulse_spacing_ms = 250;
    e.pulses_per_level = 8;
    e
}

/// The daemon's configuration for the demo: one model per operating point (K = all pulses).
fn demo_config(sim: &SimConfig) -> Config {
    let mut cfg = Config::default();
    cfg.identify.pulses_per_model = sim.experiment.pulses_per_level;
    cfg.publish.stdout = false;
    cfg.daemon.max_run = Some(Duration::from_secs(30));
    cfg
}

/// Runs `propid demo`.
pub fn run(args: Args) -> Result<(), CliError> {
    let sim = match &args.sim_config {
        Some(p) => SimConfig::load(p)?,
        None => demo_sim(),
    };
    let cfg = demo_config(&sim);
    let shutdown = Shutdown::install()?;
    let handle =
        SimHandle::spawn(sim.clone(), RunOptions::default()).map_err(CliError::SimulatedStand)?;
    let port = handle.path().display().to_string();
    eprintln!(
        "propid demo: simulated stand on {port} ({} Hz); daemon running ~10 s ...",
        sim.stand.sample_rate_hz
    );
    let source = SerialSource::open(&port, cfg.device.baud, cfg.device.read_timeout)
        .map_err(CliError::Serial)?;
    let publisher = Publisher::open(&cfg.publish)?;
    if !args.json {
        stdout::line(&format!(
            "{:>6} {:>8} {:>22} {:>20} {:>22}",
            "t_s", "throttle", "fn_hz (true)", "zeta (true)", "dc_gain N (true)"
        ))?;
    }
    let schedule = Arc::new(Mutex::new(None));
    let failed = Arc::new(Mutex::new(None));
    let publisher = publisher.with_tap(printer(
        args.json,
        sim.plant.clone(),
        schedule.clone(),
        failed.clone(),
    ));
    let parts = RunParts {
        source: Box::new(source),
        plan: Some(plan::from_experiment(sim.experiment.clone())?),
        identifier: CoreIdentifier::new(&cfg)?,
        publisher,
        record: None,
        shutdown,
    };
    let result = runner::run(&cfg, parts);
    let _ = handle.stop();
    let summary = result?;
    if let Some(e) = failed.lock().ok().and_then(|mut f| f.take()) {
        return Err(CliError::Stdout(e));
    }
    if args.json {
        return Ok(());
    }
    let mut t = String::new();
    if let Some(rows) = schedule.lock().ok().and_then(|mut s| s.take()) {
        schedule_table(&mut t, &rows, &sim.plant);
    }
    let _ = writeln!(
        t,
        "\n{} samples, {} lost, {} frames dropped, {} models in {:.1} s",
        summary.link.samples,
        summary.link.samples_lost,
        summary.link.frames_dropped.values().sum::<u64>(),
        summary.work.models,
        summary.elapsed_s
    );
    stdout::write(&t)
}

/// Where the printer keeps the first stdout write error (printing stops there).
type Failed = Arc<Mutex<Option<std::io::Error>>>;

/// Prints each line as it is published (models as table rows, or every line's JSON with
/// `--json`) and keeps the gain schedule for the end. The first write error stops the printing
/// and is kept in `failed`: the run goes on, and `run` reports it as [`CliError::Stdout`].
fn printer(
    json: bool,
    plant: PlantConfig,
    schedule: Arc<Mutex<Option<Vec<ScheduleRow>>>>,
    failed: Failed,
) -> Tap {
    Box::new(move |line: &Line<'_>, text: &str| {
        let printed = match line {
            _ if json => Some(text.to_string()),
            Line::Model(m) => Some(model_row(m, &plant)),
            _ => None,
        };
        if let Line::Schedule(rows) = line {
            if let Ok(mut s) = schedule.lock() {
                *s = Some(rows.to_vec());
            }
        }
        let Some(printed) = printed else { return };
        let Ok(mut failed) = failed.lock() else {
            return;
        };
        if failed.is_none() {
            if let Err(CliError::Stdout(e)) = stdout::line(&printed) {
                *failed = Some(e);
            }
        }
    })
}

/// `value ± sd`, the sd when it is known.
fn with_sd(x: f64, sd: f64) -> String {
    if sd.is_finite() {
        format!("{x:.3} ± {sd:.3}")
    } else {
        format!("{x:.3}")
    }
}

/// One table row: identified values beside the true ones.
fn model_row(m: &WindowModel, p: &PlantConfig) -> String {
    let (r, u) = (&m.report, &m.report.uncertainty);
    format!(
        "{:>6.2} {:>8.3} {:>14} ({:>5.2}) {:>12} ({:>5.3}) {:>14} ({:>5.2})",
        m.window.t_s,
        m.window.operating_point,
        with_sd(r.fn_hz, u.fn_hz),
        p.fn_hz,
        with_sd(r.zeta, u.zeta),
        p.zeta,
        with_sd(r.dc_gain.get(0), u.dc_gain.get(0)),
        p.gain_n_per_throttle,
    )
}

/// The gain schedule (the last model per operating point), appended to `t`.
fn schedule_table(t: &mut String, rows: &[ScheduleRow], p: &PlantConfig) {
    let _ = writeln!(
        t,
        "\ngain schedule (true plant: fn {} Hz, zeta {}, gain {} N per unit throttle):",
        p.fn_hz, p.zeta, p.gain_n_per_throttle
    );
    let _ = writeln!(
        t,
        "{:>8} {:>8} {:>8} {:>10}",
        "throttle", "fn_hz", "zeta", "dc_gain"
    );
    for m in rows {
        let _ = writeln!(
            t,
            "{:>8.3} {:>8.3} {:>8.3} {:>10.3}",
            m.operating_point,
            m.fn_hz,
            m.zeta,
            m.dc_gain.get(0)
        );
    }
}
