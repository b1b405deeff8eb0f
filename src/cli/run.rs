//! `propid run [--config F] [--port PATH] [--record FILE]`: the daemon against a stand.
//!
//! Opens the serial port (timeout always set), starts the experiment plan (handshake, arm,
//! operating points, pulses, heartbeats), identifies after every K pulses and publishes JSON
//! lines (stdout, file, UNIX socket as configured). `--record` stores the raw bytes received,
//! for `propid replay` (never overwriting a file: [`crate::daemon::recorder`]). Ctrl-C /
//! SIGTERM: STOP until acknowledged, flush, stats line, exit 0. The plan ended on a fault
//! (device reset, watchdog trip, refusal): the run stops by itself, exit 8.

use std::path::PathBuf;

use super::{CliError, UsageError};
use crate::daemon::recorder::Recorder;
use crate::daemon::runner::{self, RunParts};
use crate::daemon::source::SerialSource;
use crate::daemon::{Config, Publisher, Shutdown};

/// Arguments of `propid run`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (TOML, see config/propid.toml); built-in defaults without it.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Serial device of the stand (overrides `device.port`).
    #[arg(long)]
    pub port: Option<String>,
    /// Store the raw bytes received in FILE (overrides `daemon.record`); an existing FILE is
    /// kept and the recording goes to FILE's first free numbered name (rec.1.tsp, ...); a
    /// device or a pipe with a reader (`>(gzip > r.gz)`) is written to as it is.
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Start a new numbered recording file when this many bytes are in the current one
    /// (overrides `daemon.record_max_bytes`; 0 = no limit).
    #[arg(long, value_name = "BYTES")]
    pub record_max_bytes: Option<u64>,
    /// Serve the live web page on ADDR (a port or `:PORT`: 127.0.0.1 only; another interface
    /// only when its address is given, e.g. `0.0.0.0:8080`; port 0: any free port, printed).
    #[arg(long, value_name = "ADDR", value_parser = super::http_arg)]
    pub http: Option<std::net::SocketAddr>,
    /// Write the run report (Markdown and SVG: the static map, the steps, the frequency
    /// response of `[experiment] kind`) into DIR at the end.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Loads the configuration (defaults without a file).
pub fn load_config(path: Option<&PathBuf>) -> Result<Config, CliError> {
    match path {
        Some(p) => Ok(Config::load(p)?),
        None => Ok(Config::default()),
    }
}

/// Runs `propid run`.
pub fn run(args: Args) -> Result<(), CliError> {
    let mut cfg = load_config(args.config.as_ref())?;
    if let Some(p) = args.port {
        cfg.device.port = p;
    }
    if let Some(a) = args.http {
        cfg.publish.http = Some(a);
    }
    if let Some(r) = args.record {
        cfg.daemon.record = Some(r);
    }
    if let Some(m) = args.record_max_bytes {
        cfg.daemon.record_max_bytes =
            crate::daemon::config::record_max_bytes("--record-max-bytes", m)
                .map_err(|_| UsageError::RecordMaxBytes(m))?;
    }
    let shutdown = Shutdown::install()?;
    let plan = crate::daemon::plan::from_config(&cfg)?;
    let identifier = crate::daemon::identify::CoreIdentifier::new(&cfg)?;
    // the socket first: a live daemon on its path is found before the stand is touched
    let publisher = Publisher::open(&cfg.publish)?;
    let source = SerialSource::open(&cfg.device.port, cfg.device.baud, cfg.device.read_timeout)
        .map_err(CliError::Serial)?;
    let record = match &cfg.daemon.record {
        Some(p) => Some(
            Recorder::create(p, cfg.daemon.record_max_bytes)
                .map_err(|e| CliError::io(format!("create recording {}", p.display()), e))?,
        ),
        None => None,
    };
    let parts = RunParts {
        source: Box::new(source),
        plan: Some(plan),
        identifier,
        publisher,
        record,
        shutdown,
    };
    let summary = runner::run(&cfg, parts)?;
    if let (Some(dir), Some(material)) = (&args.report, &summary.kinds) {
        super::kinds_report::write_for(dir, material)?;
    }
    Ok(())
}
