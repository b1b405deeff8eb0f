//! Daemon configuration (`config/propid.toml`), read in two phases.
//!
//! 1. **Raw**: the TOML text is deserialised into [`RawConfig`], whose structs all have
//!    `deny_unknown_fields` and whose keys are all optional. Unknown keys and wrong types are
//!    refused here by `toml`/`serde`, and the error names the key.
//! 2. **Validated**: [`RawConfig::validate`] fills defaults and checks every value with a
//!    *positive* range check (`x.is_finite() && lo <= x && x <= hi`), so NaN and infinities fail
//!    as well. The error names the key and the value ([`ConfigError::OutOfRange`]).
//!
//! Every key, its unit and its range are documented in `config/propid.toml`; the defaults here
//! are the values written there.

pub mod mqtt;
mod range;
mod raw;

pub use raw::{RawConfig, RawCsv, RawDaemon, RawDevice, RawIdentify, RawPublish};

use propid_wire::experiment::{ExperimentConfigError, Limits, LimitsError};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Why a configuration was refused.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read config {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The TOML is malformed, has an unknown key or a value of the wrong type.
    #[error("config {origin}: {source}")]
    Parse {
        /// Where the text came from (a file, or `[experiment]` for that table).
        origin: String,
        /// The parser's error (names the key and shows the line).
        source: toml::de::Error,
    },
    /// The `[experiment]` table was refused by the experiment plan.
    #[error("config [experiment]: {0}")]
    Experiment(#[source] ExperimentConfigError),
    /// `[limits]` was refused, or the plan leaves its `max_throttle`.
    #[error("config [limits]: {0}")]
    Limits(#[source] LimitsError),
    /// A value is outside its range (or not a finite number).
    #[error("config key `{key}` = {value}: {expected}")]
    OutOfRange {
        /// Dotted key, for instance `identify.pulses_per_model`.
        key: &'static str,
        /// The value as written.
        value: String,
        /// What is accepted.
        expected: &'static str,
    },
    /// A file a key names cannot be used (read when the daemon starts: MQTT's TLS files and
    /// password).
    #[error("config key `{key}` = {path:?}: {reason}")]
    File {
        /// Dotted key, for instance `publish.mqtt_ca`.
        key: &'static str,
        /// The file.
        path: PathBuf,
        /// Why it cannot be used.
        reason: String,
    },
}

/// Validated serial-link settings.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceConfig {
    /// Serial device path.
    pub port: String,
    /// Baud rate (USB CDC ignores it).
    pub baud: u32,
    /// Read timeout: the longest a read blocks without data.
    pub read_timeout: Duration,
    /// First reconnect delay.
    pub reconnect_initial: Duration,
    /// Longest reconnect delay.
    pub reconnect_max: Duration,
    /// Wire format of the link.
    pub protocol: WireProtocol,
    /// Host-side watchdog: a live link that sends nothing (no data, no ACK) this long is
    /// stalled: STOP is tried, the port closed and reopened (None = off).
    pub stall_timeout: Option<Duration>,
}

pub use propid_link::wire::WireProtocol;

/// Validated daemon settings.
#[derive(Debug, Clone, PartialEq)]
pub struct DaemonConfig {
    /// Capacity of the sampler → worker queue, items.
    pub queue_capacity: usize,
    /// Raw-byte recording, if any.
    pub record: Option<PathBuf>,
    /// Size at which the recording goes on in the next numbered file (None = no limit).
    pub record_max_bytes: Option<u64>,
    /// Longest time to send STOP at shutdown.
    pub stop_timeout: Duration,
    /// Run length limit (None = until the plan ends or a signal).
    pub max_run: Option<Duration>,
}

/// Validated identification settings.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifyConfig {
    /// Identify after every K pulses at an operating point.
    pub pulses_per_model: u32,
    /// Model order; `None` = automatic.
    pub order: Option<usize>,
    /// Output channel name (`thrust_N`, `torque_Nm`, `rpm`).
    pub output: String,
    /// Longest window kept per operating point, samples (sizes the workspace).
    pub max_window_samples: usize,
    /// A throttle change larger than this (fraction) starts a new operating point.
    pub level_tolerance: f64,
    /// Compute the jackknife uncertainty of each model (about 3× the cost of a model).
    pub jackknife: bool,
}

/// Validated publishing settings.
#[derive(Debug, Clone, PartialEq)]
pub struct PublishConfig {
    /// Write lines to stdout.
    pub stdout: bool,
    /// Append lines to this file (flushed per line).
    pub file: Option<PathBuf>,
    /// Serve lines on this UNIX socket.
    pub socket: Option<PathBuf>,
    /// Lines queued per socket client before it is dropped.
    pub client_queue_lines: usize,
    /// Most socket clients served at once; more are refused and counted.
    pub max_clients: usize,
    /// Group (gid) given the socket, mode 0660 (None: owner only, 0600).
    pub socket_group: Option<u32>,
    /// Serve the live web page on this address (None: off); see [`http_address`].
    pub http: Option<std::net::SocketAddr>,
    /// After the run, keep serving the page (its final state) until a stop is requested
    /// (`replay` and `demo` with `--http`; not from the file).
    pub http_hold: bool,
    /// Publish to an MQTT broker (None: off; [`mqtt`]).
    pub mqtt: Option<mqtt::MqttConfig>,
}

/// Validated CSV-bench settings.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvConfig {
    /// ESC pulse width at zero throttle, µs.
    pub esc_min_us: f64,
    /// ESC pulse width at full throttle, µs.
    pub esc_max_us: f64,
    /// Motor magnet poles; `None` = unknown (an `erpm` column is then not read).
    pub motor_poles: Option<u32>,
    /// Longest throttle excursion read as a pulse, samples.
    pub max_pulse_samples: usize,
}

/// The validated configuration (phase 2).
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// `[device]`.
    pub device: DeviceConfig,
    /// `[daemon]`.
    pub daemon: DaemonConfig,
    /// `[identify]`.
    pub identify: IdentifyConfig,
    /// `[publish]`.
    pub publish: PublishConfig,
    /// `[csv]`.
    pub csv: CsvConfig,
    /// `[experiment]` table, validated by the experiment plan.
    pub experiment: toml::Table,
    /// `[limits]` (validated; the plan holds the stand to them, [`propid_wire::experiment`]).
    pub limits: Limits,
}

/// `[publish] http` / `--http ADDR`: a bare port (`8080`) or `:PORT` binds the loopback
/// `127.0.0.1`; any other interface only when its address is written out (`0.0.0.0:8080`,
/// `[::1]:8080`). `localhost:PORT` is the loopback too. Port 0 asks the OS for a free port.
pub fn http_address(text: &str) -> Option<std::net::SocketAddr> {
    use std::net::{Ipv4Addr, SocketAddr};
    let t = text.trim();
    let port = t.strip_prefix(':').unwrap_or(t);
    let port = port.strip_prefix("localhost:").unwrap_or(port);
    if let Ok(p) = port.parse::<u16>() {
        return Some(SocketAddr::from((Ipv4Addr::LOCALHOST, p)));
    }
    t.parse().ok()
}

/// Smallest `daemon.record_max_bytes` other than 0 (a file holds at least 64 KiB).
pub const RECORD_MAX_BYTES_MIN: u64 = 65_536;

/// `daemon.record_max_bytes` (or `--record-max-bytes`, named by `key`): 0 = no limit, else
/// 65536..=2^50 bytes.
pub fn record_max_bytes(key: &'static str, v: u64) -> Result<Option<u64>, ConfigError> {
    if v == 0 {
        return Ok(None);
    }
    range::int_in(
        key,
        v,
        RECORD_MAX_BYTES_MIN,
        1 << 50,
        "0 (no limit) or 65536..=1125899906842624 bytes",
    )
    .map(Some)
}

impl Default for Config {
    fn default() -> Self {
        RawConfig::default()
            .validate()
            .expect("the built-in defaults are valid")
    }
}

impl Config {
    /// Reads and validates a config file.
    pub fn load(path: &Path) -> Result<Config, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Config::parse(&text, &path.display().to_string())
    }

    /// Parses and validates config text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Config, ConfigError> {
        let raw: RawConfig = toml::from_str(text).map_err(|source| ConfigError::Parse {
            origin: origin.to_string(),
            source,
        })?;
        raw.validate()
    }
}

#[cfg(test)]
mod tests;
