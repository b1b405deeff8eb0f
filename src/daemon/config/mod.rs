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

use propid_wire::experiment::ExperimentConfigError;
use serde::Deserialize;
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
}

/// `[device]` as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDevice {
    /// Serial device path.
    pub port: Option<String>,
    /// Baud rate.
    pub baud: Option<u32>,
    /// Read timeout, ms.
    pub read_timeout_ms: Option<u64>,
    /// First reconnect delay, ms.
    pub reconnect_initial_ms: Option<u64>,
    /// Longest reconnect delay, ms.
    pub reconnect_max_ms: Option<u64>,
    /// Wire format: `auto`, `tsp` or `csv`.
    pub protocol: Option<String>,
}

/// `[daemon]` as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDaemon {
    /// Capacity of the sampler → worker queue, items.
    pub queue_capacity: Option<usize>,
    /// Raw-byte recording path.
    pub record: Option<String>,
    /// Longest time to send STOP at shutdown, ms.
    pub stop_timeout_ms: Option<u64>,
    /// Run length limit, s (0 = until the plan ends or a signal).
    pub max_run_s: Option<f64>,
}

/// `[identify]` as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawIdentify {
    /// Identify after every K pulses.
    pub pulses_per_model: Option<u32>,
    /// Model order (0 = automatic).
    pub order: Option<u32>,
    /// Output channel.
    pub output: Option<String>,
    /// Longest window, samples.
    pub max_window_samples: Option<usize>,
    /// Throttle change that means a new operating point, fraction.
    pub level_tolerance: Option<f64>,
    /// Jackknife uncertainty per model.
    pub jackknife: Option<bool>,
}

/// `[publish]` as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawPublish {
    /// Write lines to stdout.
    pub stdout: Option<bool>,
    /// Append lines to this file.
    pub file: Option<String>,
    /// Serve lines on this UNIX socket.
    pub socket: Option<String>,
    /// Lines queued per socket client before it is dropped.
    pub client_queue_lines: Option<usize>,
}

/// `[csv]` as written: how a CSV bench (PROTOCOL.md §6) is read.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCsv {
    /// ESC pulse width at zero throttle, µs (for a `throttle_us` column).
    pub esc_min_us: Option<f64>,
    /// ESC pulse width at full throttle, µs.
    pub esc_max_us: Option<f64>,
    /// Motor magnet poles (for an `erpm` column; 0 = unknown).
    pub motor_poles: Option<u32>,
    /// A throttle excursion that returns within this many samples is a pulse.
    pub max_pulse_samples: Option<usize>,
}

/// The whole file as written (phase 1).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawConfig {
    /// `[device]`.
    #[serde(default)]
    pub device: RawDevice,
    /// `[daemon]`.
    #[serde(default)]
    pub daemon: RawDaemon,
    /// `[identify]`.
    #[serde(default)]
    pub identify: RawIdentify,
    /// `[publish]`.
    #[serde(default)]
    pub publish: RawPublish,
    /// `[csv]`.
    #[serde(default)]
    pub csv: RawCsv,
    /// `[experiment]`: passed through to the experiment plan, which validates it.
    #[serde(default)]
    pub experiment: Option<toml::Table>,
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
}

/// `[device] protocol`: which wire format the daemon expects (PROTOCOL.md §6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WireProtocol {
    /// Decide from the first bytes ([`propid_wire::protocol::detect`]).
    Auto,
    /// Binary TSP/1 only.
    Tsp,
    /// The CSV fallback (read through [`super::csv_link`]).
    Csv,
}

/// Validated daemon settings.
#[derive(Debug, Clone, PartialEq)]
pub struct DaemonConfig {
    /// Capacity of the sampler → worker queue, items.
    pub queue_capacity: usize,
    /// Raw-byte recording, if any.
    pub record: Option<PathBuf>,
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

/// Checks an integer range; names the key and the value on failure.
fn int_in<T>(
    key: &'static str,
    v: T,
    lo: T,
    hi: T,
    expected: &'static str,
) -> Result<T, ConfigError>
where
    T: PartialOrd + std::fmt::Display + Copy,
{
    if lo <= v && v <= hi {
        Ok(v)
    } else {
        Err(ConfigError::OutOfRange {
            key,
            value: v.to_string(),
            expected,
        })
    }
}

/// Checks a float range positively (`finite && lo <= x <= hi`), so NaN is refused.
fn float_in(
    key: &'static str,
    v: f64,
    lo: f64,
    hi: f64,
    expected: &'static str,
) -> Result<f64, ConfigError> {
    if v.is_finite() && lo <= v && v <= hi {
        Ok(v)
    } else {
        Err(ConfigError::OutOfRange {
            key,
            value: v.to_string(),
            expected,
        })
    }
}

/// An empty string means "not set".
fn non_empty(s: Option<String>) -> Option<String> {
    s.filter(|s| !s.is_empty())
}

impl RawConfig {
    /// Phase 2: defaults and range checks.
    pub fn validate(self) -> Result<Config, ConfigError> {
        Ok(Config {
            device: self.device.validate()?,
            daemon: self.daemon.validate()?,
            identify: self.identify.validate()?,
            publish: self.publish.validate()?,
            csv: self.csv.validate()?,
            experiment: self.experiment.unwrap_or_default(),
        })
    }
}

impl RawDevice {
    fn validate(self) -> Result<DeviceConfig, ConfigError> {
        let ms = Duration::from_millis;
        let initial = int_in(
            "device.reconnect_initial_ms",
            self.reconnect_initial_ms.unwrap_or(100),
            10,
            60_000,
            "10..=60000 ms",
        )?;
        let max = int_in(
            "device.reconnect_max_ms",
            self.reconnect_max_ms.unwrap_or(2_000),
            initial,
            600_000,
            "reconnect_initial_ms..=600000 ms",
        )?;
        Ok(DeviceConfig {
            port: non_empty(self.port).unwrap_or_else(|| "/dev/propid-stand".into()),
            baud: int_in(
                "device.baud",
                self.baud.unwrap_or(921_600),
                1_200,
                4_000_000,
                "1200..=4000000 baud",
            )?,
            read_timeout: ms(int_in(
                "device.read_timeout_ms",
                self.read_timeout_ms.unwrap_or(10),
                1,
                50,
                "1..=50 ms (heartbeats go out every 100 ms)",
            )?),
            reconnect_initial: ms(initial),
            reconnect_max: ms(max),
            protocol: match self.protocol.as_deref().unwrap_or("auto") {
                "auto" => WireProtocol::Auto,
                "tsp" => WireProtocol::Tsp,
                "csv" => WireProtocol::Csv,
                other => {
                    return Err(ConfigError::OutOfRange {
                        key: "device.protocol",
                        value: format!("{other:?}"),
                        expected: "one of \"auto\", \"tsp\", \"csv\"",
                    })
                }
            },
        })
    }
}

impl RawDaemon {
    fn validate(self) -> Result<DaemonConfig, ConfigError> {
        let max_run_s = float_in(
            "daemon.max_run_s",
            self.max_run_s.unwrap_or(0.0),
            0.0,
            1.0e7,
            "0..=1e7 s (0 = no limit)",
        )?;
        Ok(DaemonConfig {
            queue_capacity: int_in(
                "daemon.queue_capacity",
                self.queue_capacity.unwrap_or(65_536),
                16,
                16_777_216,
                "16..=16777216 items",
            )?,
            record: non_empty(self.record).map(PathBuf::from),
            stop_timeout: Duration::from_millis(int_in(
                "daemon.stop_timeout_ms",
                self.stop_timeout_ms.unwrap_or(1_000),
                50,
                1_000,
                "50..=1000 ms",
            )?),
            max_run: (max_run_s > 0.0).then(|| Duration::from_secs_f64(max_run_s)),
        })
    }
}

impl RawIdentify {
    fn validate(self) -> Result<IdentifyConfig, ConfigError> {
        let output = self.output.unwrap_or_else(|| "thrust_N".into());
        if !matches!(output.as_str(), "thrust_N" | "torque_Nm" | "rpm") {
            return Err(ConfigError::OutOfRange {
                key: "identify.output",
                value: format!("{output:?}"),
                expected: "one of \"thrust_N\", \"torque_Nm\", \"rpm\"",
            });
        }
        let order = int_in(
            "identify.order",
            self.order.unwrap_or(2),
            0,
            8,
            "0..=8 (0 = automatic)",
        )?;
        Ok(IdentifyConfig {
            pulses_per_model: int_in(
                "identify.pulses_per_model",
                self.pulses_per_model.unwrap_or(4),
                1,
                1_000,
                "1..=1000 pulses",
            )?,
            order: (order > 0).then_some(order as usize),
            output,
            max_window_samples: int_in(
                "identify.max_window_samples",
                self.max_window_samples.unwrap_or(16_384),
                64,
                1_048_576,
                "64..=1048576 samples",
            )?,
            level_tolerance: float_in(
                "identify.level_tolerance",
                self.level_tolerance.unwrap_or(0.005),
                1.0e-4,
                0.5,
                "1e-4..=0.5 (throttle fraction)",
            )?,
            jackknife: self.jackknife.unwrap_or(true),
        })
    }
}

impl RawPublish {
    fn validate(self) -> Result<PublishConfig, ConfigError> {
        Ok(PublishConfig {
            stdout: self.stdout.unwrap_or(true),
            file: non_empty(self.file).map(PathBuf::from),
            socket: non_empty(self.socket).map(PathBuf::from),
            client_queue_lines: int_in(
                "publish.client_queue_lines",
                self.client_queue_lines.unwrap_or(1_024),
                1,
                1_048_576,
                "1..=1048576 lines",
            )?,
        })
    }
}

impl RawCsv {
    fn validate(self) -> Result<CsvConfig, ConfigError> {
        let esc_min_us = float_in(
            "csv.esc_min_us",
            self.esc_min_us.unwrap_or(1_000.0),
            0.0,
            3_000.0,
            "0..=3000 µs",
        )?;
        let esc_max_us = self.esc_max_us.unwrap_or(2_000.0);
        if !(esc_max_us.is_finite() && esc_max_us > esc_min_us && esc_max_us <= 3_000.0) {
            return Err(ConfigError::OutOfRange {
                key: "csv.esc_max_us",
                value: esc_max_us.to_string(),
                expected: "above csv.esc_min_us, at most 3000 µs",
            });
        }
        let poles = self.motor_poles.unwrap_or(0);
        if !(poles == 0 || (2..=64).contains(&poles) && poles % 2 == 0) {
            return Err(ConfigError::OutOfRange {
                key: "csv.motor_poles",
                value: poles.to_string(),
                expected: "0 (unknown) or an even number 2..=64",
            });
        }
        Ok(CsvConfig {
            esc_min_us,
            esc_max_us,
            motor_poles: (poles > 0).then_some(poles),
            max_pulse_samples: int_in(
                "csv.max_pulse_samples",
                self.max_pulse_samples.unwrap_or(64),
                1,
                4_096,
                "1..=4096 samples",
            )?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        Config::parse(text, "test").unwrap_err().to_string()
    }

    #[test]
    fn empty_text_gives_defaults() {
        let c = Config::parse("", "test").unwrap();
        assert_eq!(c, Config::default());
        assert_eq!(c.identify.pulses_per_model, 4);
        assert_eq!(c.device.baud, 921_600);
        assert!(c.publish.stdout);
    }

    #[test]
    fn shipped_config_file_is_valid() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/propid.toml");
        let c = Config::load(&path).unwrap();
        assert_eq!(c.identify.output, "thrust_N");
        // the [experiment] table is the plan's, and the plan accepts it
        assert_eq!(c.experiment["levels"].as_array().unwrap().len(), 3);
        crate::daemon::plan::from_config(&c).unwrap();
    }

    #[test]
    fn unknown_key_is_named() {
        let e = err("[identify]\npulses_per_modle = 3\n");
        assert!(e.contains("pulses_per_modle"), "{e}");
        let e = err("[nonsense]\nx = 1\n");
        assert!(e.contains("nonsense"), "{e}");
    }

    #[test]
    fn wrong_type_is_refused() {
        let e = err("[device]\nbaud = \"fast\"\n");
        assert!(e.contains("baud") || e.contains("fast"), "{e}");
    }

    #[test]
    fn nan_and_out_of_range_name_key_and_value() {
        let e = err("[identify]\nlevel_tolerance = nan\n");
        assert!(
            e.contains("identify.level_tolerance") && e.contains("NaN"),
            "{e}"
        );
        let e = err("[identify]\npulses_per_model = 0\n");
        assert!(
            e.contains("identify.pulses_per_model") && e.contains("= 0"),
            "{e}"
        );
        let e = err("[device]\nread_timeout_ms = 500\n");
        assert!(
            e.contains("device.read_timeout_ms") && e.contains("500"),
            "{e}"
        );
        let e = err("[daemon]\nmax_run_s = inf\n");
        assert!(e.contains("daemon.max_run_s") && e.contains("inf"), "{e}");
        let e = err("[identify]\noutput = \"voltage\"\n");
        assert!(
            e.contains("identify.output") && e.contains("voltage"),
            "{e}"
        );
    }

    #[test]
    fn bad_experiment_keys_are_refused_by_the_plan() {
        for text in [
            "[experiment]\nlevles = [0.3]\n",
            "[experiment]\nlevels = [1.5]\n",
            "[experiment]\npulse_spacing_ms = \"x\"\n",
        ] {
            let c = Config::parse(text, "t").unwrap();
            let e = crate::daemon::plan::from_config(&c)
                .err()
                .unwrap()
                .to_string();
            assert!(e.contains("lev") || e.contains("pulse_spacing_ms"), "{e}");
        }
    }

    #[test]
    fn reconnect_max_below_initial_is_refused() {
        let e = err("[device]\nprotocol = \"nmea\"\n");
        assert!(e.contains("device.protocol") && e.contains("nmea"), "{e}");
        let e = err("[device]\nreconnect_initial_ms = 500\nreconnect_max_ms = 100\n");
        assert!(e.contains("device.reconnect_max_ms"), "{e}");
    }

    #[test]
    fn csv_keys_are_checked() {
        let c = Config::parse("[csv]\nesc_min_us = 1100\nmotor_poles = 14\n", "t").unwrap();
        assert_eq!(c.csv.esc_min_us, 1100.0);
        assert_eq!(c.csv.motor_poles, Some(14));
        assert_eq!(c.csv.max_pulse_samples, 64);
        let e = err("[csv]\nesc_min_us = 1500\nesc_max_us = 1200\n");
        assert!(e.contains("csv.esc_max_us") && e.contains("1200"), "{e}");
        let e = err("[csv]\nmotor_poles = 7\n");
        assert!(e.contains("csv.motor_poles") && e.contains('7'), "{e}");
        let e = err("[csv]\nmax_pulse_samples = 0\n");
        assert!(e.contains("csv.max_pulse_samples"), "{e}");
        let e = err("[csv]\nesc_min_us = nan\n");
        assert!(e.contains("csv.esc_min_us") && e.contains("NaN"), "{e}");
        let e = err("[csv]\nbaud = 3\n");
        assert!(e.contains("baud"), "{e}");
    }

    #[test]
    fn empty_strings_mean_unset() {
        let c = Config::parse("[publish]\nfile = \"\"\nsocket = \"\"\n", "t").unwrap();
        assert_eq!(c.publish.file, None);
        assert_eq!(c.publish.socket, None);
    }
}
