//! `propid demo`: the whole main job with no hardware and no set-up.
//!
//! Starts the simulated stand on a pseudo-terminal inside this process (the same firmware and
//! the same serial source as with a real stand), runs the daemon against it for about ten
//! seconds — handshake, arm, three operating points, one-sample pulses of alternating sign,
//! identification after every K pulses — and prints each published model beside the
//! simulator's truth, then the gain schedule. The built-in stand is the motor plant, whose
//! truth is its linearisation at each level ([`truth`], with how far spin-down being slower
//! than spin-up keeps any linear model from it); a `--sim-config` of the 2nd-order plant has
//! one truth everywhere. The schedule is printed when the run ends (at the final stats line),
//! so with `--http` it is on the terminal while the page stays up until Ctrl-C; the page also
//! gets each level's truth ([`live`]). `--json` prints the daemon's JSON lines instead. Both come from the publisher's tap ([`Publisher::with_tap`]): the typed lines as
//! they are published, and their bytes; nothing is parsed back.

mod live;
mod table;

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::{stdout, CliError};
use crate::daemon::http::{Kind, LiveSender};
use crate::daemon::identify::CoreIdentifier;
use crate::daemon::line::{Line, ScheduleRow};
use crate::daemon::plan;
use crate::daemon::publish::Tap;
use crate::daemon::runner::{self, RunParts};
use crate::daemon::source::SerialSource;
use crate::daemon::stats::StatsLine;
use crate::daemon::{Config, Publisher, Shutdown};
use propid_sim::plant::{PlantConfig, PlantKind};
use propid_sim::pty::{RunOptions, SimHandle};
use propid_sim::SimConfig;
use table::MotorRow;

/// Arguments of `propid demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Simulated stand configuration (config/sim.toml format); built-in demo stand without it.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// Print the daemon's JSON lines instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Serve the live web page on ADDR (a port or `:PORT`: 127.0.0.1 only; another interface
    /// only when its address is given, e.g. `0.0.0.0:8080`; port 0: any free port, printed); the page stays
    /// up after the demo, with its final state, until Ctrl-C.
    #[arg(long, value_name = "ADDR", value_parser = super::http_arg)]
    pub http: Option<std::net::SocketAddr>,
}

/// The demo's stand: the motor plant (`config/sim.toml`'s) sampled at 250 Hz (one-sample
/// pulses carry more energy at a lower rate, so ten seconds give tight models).
fn demo_sim() -> SimConfig {
    let mut s = SimConfig::default();
    s.plant.kind = PlantKind::Motor;
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
    let mut cfg = demo_config(&sim);
    cfg.publish.http = args.http;
    cfg.publish.http_hold = args.http.is_some();
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
        stdout::line(&table::header(&sim.plant))?;
    }
    let kept = Mutex::new(Kept::default());
    let failed = Arc::new(Mutex::new(None));
    let live = publisher.live_sender();
    let publisher = publisher.with_tap(printer(
        args.json,
        sim.plant.clone(),
        live,
        kept,
        failed.clone(),
    ));
    let parts = RunParts {
        source: Box::new(source),
        plan: Some(plan::from_experiment(sim.experiment.clone(), &cfg)?),
        identifier: CoreIdentifier::new(&cfg)?,
        publisher,
        record: None,
        shutdown,
    };
    let result = runner::run(&cfg, parts);
    let _ = handle.stop();
    result?;
    if let Some(e) = failed.lock().ok().and_then(|mut f| f.take()) {
        return Err(CliError::Stdout(e));
    }
    Ok(())
}

/// What the terminal shows when the run ends: the gain schedule (beside the truth) and the
/// run's counters from the final stats line.
fn final_text(k: &mut Kept, plant: &PlantConfig, s: &StatsLine<'_>) -> String {
    let mut t = String::new();
    match (plant.kind, k.schedule.take()) {
        (PlantKind::Motor, _) => table::motor_schedule(&mut t, &k.motor, plant),
        (PlantKind::SecondOrder, Some(rows)) => table::second_order_schedule(&mut t, &rows, plant),
        (PlantKind::SecondOrder, None) => {}
    }
    let _ = write!(
        t,
        "\n{} samples, {} lost, {} frames dropped, {} models in {:.1} s",
        s.link.samples,
        s.link.samples_lost,
        s.link.frames_dropped.values().sum::<u64>(),
        s.work.models,
        s.elapsed_s
    );
    t
}

/// Where the printer keeps the first stdout write error (printing stops there).
type Failed = Arc<Mutex<Option<std::io::Error>>>;

/// What the printer keeps for the end: the daemon's gain schedule, the motor's rows (the
/// last per level, in level order), and the page's truth rows.
#[derive(Debug, Default)]
struct Kept {
    schedule: Option<Vec<ScheduleRow>>,
    motor: Vec<MotorRow>,
    truth: Vec<live::TruthRow>,
}

/// Prints each line as it is published (models as table rows beside the truth, or every line's
/// JSON with `--json`), keeps the gain schedule and prints it at the final stats line (before
/// a page served with `--http` is held until Ctrl-C), and sends the page each level's truth
/// (`live`: the page's sender). The first write error stops the printing and is kept in
/// `failed`: the run goes on, and `run` reports it as [`CliError::Stdout`].
fn printer(
    json: bool,
    plant: PlantConfig,
    live: Option<LiveSender>,
    kept: Mutex<Kept>,
    failed: Failed,
) -> Tap {
    Box::new(move |line: &Line<'_>, text: &str| {
        let mut printed = None;
        if json {
            printed = Some(text.to_string());
        }
        if let (Line::Model(m), Ok(mut k)) = (line, kept.lock()) {
            let truth = match MotorRow::of(m, &plant) {
                Some(row) => {
                    k.motor.retain(|r| r.level != row.level);
                    k.motor.push(row);
                    k.motor.sort_by(|a, b| a.level.total_cmp(&b.level));
                    printed = printed.or_else(|| Some(table::motor_row(&row)));
                    live::TruthRow::motor(&row)
                }
                None => {
                    printed = printed.or_else(|| Some(table::second_order_row(m, &plant)));
                    live::TruthRow::second_order(m.window.operating_point, &plant)
                }
            };
            live::keep(&mut k.truth, truth);
            if let Some(sender) = &live {
                let line = live::TruthLine {
                    kind: "truth",
                    plant: match plant.kind {
                        PlantKind::Motor => "motor",
                        PlantKind::SecondOrder => "second_order",
                    },
                    levels: &k.truth,
                };
                if let Ok(text) = serde_json::to_string(&line) {
                    sender.send(Kind::State("truth"), &text);
                }
            }
        }
        if let (Line::Schedule(rows), Ok(mut k)) = (line, kept.lock()) {
            k.schedule = Some(rows.to_vec());
        }
        if let (Line::Stats(s), false, Ok(mut k)) = (line, json, kept.lock()) {
            printed = Some(final_text(&mut k, &plant, s));
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
