//! Wires a run together: sampler thread → bounded queue → worker thread → publisher, then the
//! final stats line. `propid run`, `propid replay` and `propid demo` all go through [`run`].

use crossbeam_channel::bounded;
use std::time::Instant;

use super::config::Config;
use super::csv_link::CsvLinkOptions;
use super::line::Line;
use super::publish::Publisher;
use super::recorder::Recorder;
use super::sampler::{Plan, Sampler, SamplerConfig};
use super::shutdown::Shutdown;
use super::source::Source;
use super::stats::{quantile, LinkStats, StatsLine, WorkStats};
use super::window::{OutputChannel, Window};
use super::worker::{Identifier, Worker};
use super::DaemonError;
use propid_wire::protocol::csv::CsvOptions;
use propid_wire::protocol::csv_columns::ConvOptions;

/// What a finished run reports.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Link counters.
    pub link: LinkStats,
    /// Worker counters.
    pub work: WorkStats,
    /// Latencies from a window's last sample to its published model line, s, sorted.
    pub latencies_s: Vec<f64>,
    /// Wall-clock duration, s.
    pub elapsed_s: f64,
    /// The run report's material (`--report`).
    pub kinds: Option<propid_kinds::Material>,
}

impl RunSummary {
    /// The `q`-quantile (0..1) of the latencies, s (NaN without models).
    pub fn latency_quantile(&self, q: f64) -> f64 {
        quantile(&self.latencies_s, q)
    }
}

/// How the CSV link reads a bench, from `[csv]` and `identify.level_tolerance`.
pub fn csv_options(cfg: &Config) -> CsvLinkOptions {
    CsvLinkOptions {
        csv: CsvOptions {
            conv: ConvOptions {
                esc_min_us: Some(cfg.csv.esc_min_us),
                esc_max_us: Some(cfg.csv.esc_max_us),
                motor_poles: cfg.csv.motor_poles,
            },
            ..CsvOptions::default()
        },
        level_tolerance: cfg.identify.level_tolerance,
        max_pulse_samples: cfg.csv.max_pulse_samples,
    }
}

/// The analysis of `[experiment] kind` (run and replay alike: the samples and this
/// configuration are all it reads).
fn kinds_analysis(cfg: &Config) -> Result<Option<propid_kinds::Analysis>, DaemonError> {
    let ecfg: propid_wire::experiment::ExperimentConfig =
        cfg.experiment.clone().try_into().map_err(|source| {
            DaemonError::Config(super::config::ConfigError::Parse {
                origin: "[experiment]".into(),
                source,
            })
        })?;
    if ecfg.kind != propid_wire::experiment::Kind::Pulses {
        ecfg.validate()
            .map_err(|e| DaemonError::Config(super::config::ConfigError::Experiment(e)))?;
    }
    Ok(Some(propid_kinds::Analysis::new(&ecfg)))
}

/// Everything a run needs besides the configuration.
pub struct RunParts<I: Identifier> {
    /// The byte source (serial port, pty, recording).
    pub source: Box<dyn Source>,
    /// The experiment plan (live runs), or none (replay, passive benches).
    pub plan: Option<Box<dyn Plan>>,
    /// The identifier, sized at start-up.
    pub identifier: I,
    /// Where lines go.
    pub publisher: Publisher,
    /// Raw-byte recording of everything received.
    pub record: Option<Recorder>,
    /// The stop flag.
    pub shutdown: Shutdown,
}

/// Runs the sampler and the worker until the source ends, the plan finishes or ends on a fault,
/// or a stop is requested; then publishes the final stats line and flushes every output.
///
/// The error, when there is one, is the first of: what stopped the sampler or the worker (a
/// failed link, a bug), [`DaemonError::PlanHalted`] (the plan ended on a fault, exit 8), an
/// output the run went on without ([`DaemonError::Output`]: the recording, stdout; exit 7).
/// Everything is published before it is returned.
pub fn run<I: Identifier + 'static>(
    cfg: &Config,
    parts: RunParts<I>,
) -> Result<RunSummary, DaemonError> {
    let start = Instant::now();
    parts.shutdown.begin_run();
    let channel = OutputChannel::from_name(&cfg.identify.output).unwrap_or(OutputChannel::Thrust);
    let window = Window::new(
        super::window::window_capacity(cfg),
        cfg.identify.pulses_per_model as usize,
        cfg.identify.level_tolerance,
        channel,
    );
    let (tx, rx) = bounded(cfg.daemon.queue_capacity);
    let mut publisher = parts.publisher;
    let shutdown = parts.shutdown.clone();
    if let Some(url) = publisher.http_url() {
        eprintln!("propid: the live page is at {url}");
        let line = Line::Event(super::line::Event::Http { url });
        if let Err(e) = publisher.publish_line(&line) {
            eprintln!("propid: {e}");
        }
    }
    // the web page's lines (and MQTT's live samples) need the sampler's counters too
    let live_link = publisher
        .is_live()
        .then(|| std::sync::Arc::new(std::sync::Mutex::new(LinkStats::default())));
    let mut worker =
        Worker::new(window, parts.identifier, publisher).with_kinds(kinds_analysis(cfg)?);
    if let Some(link) = &live_link {
        worker = worker.with_live(link.clone());
    }
    let worker = std::thread::Builder::new()
        .name("propid-worker".into())
        .spawn(move || worker.run(rx))
        .map_err(|e| DaemonError::io("spawn the worker thread", e))?;
    let sampler = Sampler::new(
        parts.source,
        tx,
        parts.plan,
        parts.record,
        parts.shutdown,
        SamplerConfig {
            stop_timeout: cfg.daemon.stop_timeout,
            max_run: cfg.daemon.max_run,
            reconnect_initial: cfg.device.reconnect_initial,
            reconnect_max: cfg.device.reconnect_max,
            protocol: cfg.device.protocol,
            csv: csv_options(cfg),
            silence_timeout: super::sampler::SILENCE_TIMEOUT,
            stall_timeout: cfg.device.stall_timeout,
        },
    );
    let sampler = match live_link {
        Some(link) => sampler.with_live_stats(link),
        None => sampler,
    };
    let sampler = std::thread::Builder::new()
        .name("propid-sampler".into())
        .spawn(move || sampler.run())
        .map_err(|e| DaemonError::io("spawn the sampler thread", e))?;
    // The sampler drops its sender when it ends, which ends the worker.
    let sampled = sampler
        .join()
        .map_err(|_| DaemonError::ThreadPanicked { thread: "sampler" })?;
    let worked = worker
        .join()
        .map_err(|_| DaemonError::ThreadPanicked { thread: "worker" })?;
    let mut publisher = worked.publisher;
    let elapsed_s = start.elapsed().as_secs_f64();
    let mut stats = StatsLine::new(
        &sampled.stats,
        &worked.stats,
        publisher.dropped_clients(),
        elapsed_s,
        &worked.latencies_s,
    );
    stats.clients_refused = publisher.clients_refused();
    stats.mqtt = publisher.mqtt_stats();
    publisher.publish_line(&Line::Stats(&stats))?;
    let output_error = publisher.take_error();
    if publisher.http_url().is_some() && cfg.publish.http_hold {
        eprintln!("propid: the run is over; the page stays up until Ctrl-C");
        while !shutdown.requested() {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
    publisher.close();
    if let Some(e) = sampled.error.or(worked.error) {
        return Err(e);
    }
    if sampled.plan_halted {
        return Err(DaemonError::PlanHalted);
    }
    if let Some(e) = sampled.record_error.or(output_error) {
        return Err(e);
    }
    Ok(RunSummary {
        link: sampled.stats,
        work: worked.stats,
        latencies_s: worked.latencies_s,
        elapsed_s,
        kinds: worked.kinds,
    })
}

#[cfg(test)]
mod replay_tests {
    use super::*;
    use crate::daemon::identify::CoreIdentifier;
    use crate::daemon::source::RecordingSource;
    use propid_sim::SimConfig;
    use std::path::Path;

    fn replay(bytes: Vec<u8>, chunk: usize) -> (RunSummary, Vec<serde_json::Value>) {
        let cfg = Config::default();
        let (publisher, lines) = Publisher::capture();
        let parts = RunParts {
            source: Box::new(RecordingSource::from_bytes(
                Path::new("sim.tsp"),
                bytes,
                chunk,
            )),
            plan: None,
            identifier: CoreIdentifier::new(&cfg).unwrap(),
            publisher,
            record: None,
            shutdown: Shutdown::manual(),
        };
        let summary = run(&cfg, parts).unwrap();
        let lines = lines
            .lock()
            .unwrap()
            .iter()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        (summary, lines)
    }

    #[test]
    fn replay_of_a_clean_simulated_stand_recovers_the_plant() {
        // the simulated stand without noise or quantisation, three levels of 8 pulses
        let mut cfg = SimConfig::default();
        cfg.plant.fn_hz = 25.0;
        cfg.plant.zeta = 0.5;
        cfg.plant.gain_n_per_throttle = 8.0;
        cfg.plant.noise_rms_n = 0.0;
        cfg.plant.quantum_n = 0.0;
        let mut bytes = Vec::new();
        let facts = propid_sim::record::record(&cfg, 60.0, &mut bytes).unwrap();
        assert!(facts.finished);
        let (summary, lines) = replay(bytes, 4096);
        assert_eq!(summary.link.samples, facts.firmware.samples);
        assert_eq!(summary.link.samples_lost, 0);
        let models: Vec<_> = lines.iter().filter(|l| l["type"] == "model").collect();
        assert_eq!(models.len(), 6, "{lines:#?}");
        for m in &models {
            let f = m["fn_hz"].as_f64().unwrap();
            let z = m["zeta"].as_f64().unwrap();
            let g = m["dc_gain"].as_f64().unwrap();
            // f32 thrust on the wire limits the accuracy to ~1e-5 relative
            assert!((f - 25.0).abs() < 1e-3, "fn {f}");
            assert!((z - 0.5).abs() < 1e-4, "zeta {z}");
            assert!((g - 8.0).abs() < 1e-3, "gain {g}");
        }
        let last = lines.last().unwrap();
        assert_eq!(last["type"], "stats");
        assert_eq!(lines[lines.len() - 2]["type"], "schedule");
    }
}
