//! `propid demo`: the whole main job with no hardware and no set-up.
//!
//! Starts the simulated stand on a pseudo-terminal inside this process (the same firmware and
//! the same serial source as with a real stand), runs the daemon against it for about ten
//! seconds — handshake, arm, three operating points, one-sample pulses of alternating sign,
//! identification after every K pulses — and prints each published model beside the
//! simulator's true parameters, then the gain schedule. `--json` prints the daemon's JSON lines
//! instead.

use std::io::Write;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::run::daemon_error;
use super::CliError;
use crate::daemon::identify::CoreIdentifier;
use crate::daemon::plan;
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
        Some(p) => SimConfig::load(p).map_err(|e| CliError::Config(e.to_string()))?,
        None => demo_sim(),
    };
    let cfg = demo_config(&sim);
    let shutdown = Shutdown::install().map_err(daemon_error)?;
    let handle = SimHandle::spawn(sim.clone(), RunOptions::default())
        .map_err(|e| CliError::Device(format!("simulated stand: {e}")))?;
    let port = handle.path().display().to_string();
    eprintln!(
        "propid demo: simulated stand on {port} ({} Hz); daemon running ~10 s ...",
        sim.stand.sample_rate_hz
    );
    let source = SerialSource::open(&port, cfg.device.baud, cfg.device.read_timeout)
        .map_err(|e| CliError::Device(e.to_string()))?;
    let (publisher, lines) = Publisher::open(&cfg.publish)
        .map_err(daemon_error)?
        .with_capture();
    let printer = spawn_printer(lines.clone(), args.json, sim.plant.clone());
    let parts = RunParts {
        source: Box::new(source),
        plan: Some(plan::from_experiment(sim.experiment.clone()).map_err(daemon_error)?),
        identifier: CoreIdentifier::new(&cfg).map_err(daemon_error)?,
        publisher,
        record: None,
        shutdown,
    };
    let result = runner::run(&cfg, parts);
    let _ = handle.stop();
    let _ = printer.join();
    let summary = result.map_err(daemon_error)?;
    let lines = lines.lock().map(|l| l.clone()).unwrap_or_default();
    if args.json {
        return Ok(());
    }
    print_schedule(&lines, &sim.plant);
    println!(
        "\n{} samples, {} lost, {} frames dropped, {} models in {:.1} s",
        summary.link.samples,
        summary.link.samples_lost,
        summary.link.frames_dropped.values().sum::<u64>(),
        summary.work.models,
        summary.elapsed_s
    );
    Ok(())
}

/// Prints each line as it is published (models as table rows, or JSON with `--json`).
fn spawn_printer(
    lines: Arc<Mutex<Vec<String>>>,
    json: bool,
    plant: PlantConfig,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        let mut shown = 0;
        if !json {
            println!(
                "{:>6} {:>8} {:>22} {:>20} {:>22}",
                "t_s", "throttle", "fn_hz (true)", "zeta (true)", "dc_gain N (true)"
            );
        }
        loop {
            let (new, done) = match lines.lock() {
                Ok(l) => (
                    l[shown..].to_vec(),
                    l.last().is_some_and(|x| x.contains("\"type\":\"stats\"")),
                ),
                Err(_) => return,
            };
            shown += new.len();
            let mut out = std::io::stdout().lock();
            for l in &new {
                if json {
                    let _ = writeln!(out, "{l}");
                } else if let Ok(v) = serde_json::from_str::<serde_json::Value>(l) {
                    if v["type"] == "model" {
                        let _ = writeln!(out, "{}", model_row(&v, &plant));
                    }
                }
            }
            let _ = out.flush();
            if done {
                return;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    })
}

/// `value ± sd` of a model field.
fn with_sd(v: &serde_json::Value, key: &str) -> String {
    let x = v[key].as_f64().unwrap_or(f64::NAN);
    match v["uncertainty"][key].as_f64() {
        Some(sd) => format!("{x:.3} ± {sd:.3}"),
        None => format!("{x:.3}"),
    }
}

/// One table row: identified values beside the true ones.
fn model_row(v: &serde_json::Value, p: &PlantConfig) -> String {
    format!(
        "{:>6.2} {:>8.3} {:>14} ({:>5.2}) {:>12} ({:>5.3}) {:>14} ({:>5.2})",
        v["t_s"].as_f64().unwrap_or(f64::NAN),
        v["operating_point"].as_f64().unwrap_or(f64::NAN),
        with_sd(v, "fn_hz"),
        p.fn_hz,
        with_sd(v, "zeta"),
        p.zeta,
        with_sd(v, "dc_gain"),
        p.gain_n_per_throttle,
    )
}

/// The gain schedule (the last model per operating point).
fn print_schedule(lines: &[String], p: &PlantConfig) {
    let Some(sched) = lines
        .iter()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find(|v| v["type"] == "schedule")
    else {
        return;
    };
    println!(
        "\ngain schedule (true plant: fn {} Hz, zeta {}, gain {} N per unit throttle):",
        p.fn_hz, p.zeta, p.gain_n_per_throttle
    );
    println!(
        "{:>8} {:>8} {:>8} {:>10}",
        "throttle", "fn_hz", "zeta", "dc_gain"
    );
    for m in sched["models"].as_array().into_iter().flatten() {
        let f = |k: &str| m[k].as_f64().unwrap_or(f64::NAN);
        println!(
            "{:>8.3} {:>8.3} {:>8.3} {:>10.3}",
            f("operating_point"),
            f("fn_hz"),
            f("zeta"),
            f("dc_gain")
        );
    }
}
