//! Phase 1 and 2 of reading a configuration: the file as written ([`RawConfig`], every key
//! optional, unknown keys refused) and its validation into [`Config`] (defaults filled, every
//! value range-checked, NaN refused).

use propid_numerics::segment::SegmentRules;
use serde::Deserialize;
use std::path::PathBuf;
use std::time::Duration;

use super::range::{float_in, int_in};
use super::{
    Config, ConfigError, CsvConfig, DaemonConfig, DeviceConfig, IdentifyConfig, PublishConfig,
    WireProtocol,
};

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
    /// Host-side watchdog: nothing heard for this long → STOP, reopen, ms (0 = off).
    pub stall_timeout_ms: Option<u64>,
}

/// `[daemon]` as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDaemon {
    /// Capacity of the sampler → worker queue, items.
    pub queue_capacity: Option<usize>,
    /// Raw-byte recording path.
    pub record: Option<String>,
    /// Recording size at which the next numbered file starts, bytes (0 = no limit).
    pub record_max_bytes: Option<u64>,
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
    /// Most socket clients at once.
    pub max_clients: Option<usize>,
    /// Group (name or number) that may connect to the socket (mode 0660).
    pub socket_group: Option<String>,
    /// Serve the live web page on this address (`8080`, `:8080`, `127.0.0.1:8080`).
    pub http: Option<String>,
    /// Publish to this MQTT broker (`mqtt://HOST:PORT`, `mqtts://HOST:PORT`; docs/mqtt.md).
    pub mqtt: Option<String>,
    /// The stand's name in the MQTT topics (`propid/<stand>/...`).
    pub stand: Option<String>,
    /// CA certificate (PEM) of an `mqtts://` broker.
    pub mqtt_ca: Option<String>,
    /// Client certificate (PEM) for an `mqtts://` broker.
    pub mqtt_cert: Option<String>,
    /// Its private key (PEM).
    pub mqtt_key: Option<String>,
    /// User name given to the broker.
    pub mqtt_username: Option<String>,
    /// File whose first line is the password.
    pub mqtt_password_file: Option<String>,
    /// Also publish the live samples, batched (QoS 0).
    pub mqtt_samples: Option<bool>,
    /// MQTT keep-alive, s.
    pub mqtt_keep_alive_s: Option<u64>,
    /// Messages queued while the broker is away.
    pub mqtt_queue_messages: Option<usize>,
}

/// `[csv]` as written: how a CSV bench (docs/PROTOCOL.md §6) is read.
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
    /// `[limits]`: the safety limits (`propid_wire::experiment::Limits`, its keys its own).
    #[serde(default)]
    pub limits: propid_wire::experiment::Limits,
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
            limits: {
                self.limits.validate().map_err(ConfigError::Limits)?;
                self.limits
            },
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
            stall_timeout: match self.stall_timeout_ms.unwrap_or(1_000) {
                0 => None,
                v => Some(ms(int_in(
                    "device.stall_timeout_ms",
                    v,
                    50,
                    600_000,
                    "0 (off) or 50..=600000 ms",
                )?)),
            },
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
            record_max_bytes: super::record_max_bytes(
                "daemon.record_max_bytes",
                self.record_max_bytes.unwrap_or(0),
            )?,
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
                self.level_tolerance
                    .unwrap_or(SegmentRules::CSV_BENCH.level_tolerance),
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
        let mqtt = super::mqtt::RawMqtt {
            url: non_empty(self.mqtt),
            stand: self.stand,
            ca: non_empty(self.mqtt_ca),
            cert: non_empty(self.mqtt_cert),
            key: non_empty(self.mqtt_key),
            username: non_empty(self.mqtt_username),
            password_file: non_empty(self.mqtt_password_file),
            samples: self.mqtt_samples,
            keep_alive_s: self.mqtt_keep_alive_s,
            queue_messages: self.mqtt_queue_messages,
        }
        .validate()?;
        Ok(PublishConfig {
            mqtt,
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
            max_clients: int_in(
                "publish.max_clients",
                self.max_clients.unwrap_or(64),
                1,
                4_096,
                "1..=4096 clients",
            )?,
            http: match non_empty(self.http) {
                None => None,
                Some(a) => Some(super::http_address(&a).ok_or(ConfigError::OutOfRange {
                    key: "publish.http",
                    value: format!("{a:?}"),
                    expected: "a port (8080, :8080: loopback) or an address (127.0.0.1:8080)",
                })?),
            },
            http_hold: false,
            socket_group: match non_empty(self.socket_group) {
                None => None,
                Some(g) => Some(group_id(&g).ok_or(ConfigError::OutOfRange {
                    key: "publish.socket_group",
                    value: format!("{g:?}"),
                    expected: "a group of this system, by name or number",
                })?),
            },
        })
    }
}

/// The gid of a group given by name or number, if the system has it.
fn group_id(name: &str) -> Option<u32> {
    let mut buf = vec![0 as libc::c_char; 16_384];
    let mut grp: libc::group = unsafe { std::mem::zeroed() };
    let mut found: *mut libc::group = std::ptr::null_mut();
    let r = match name.parse::<u32>() {
        // SAFETY: every pointer is to a live local of the size given
        Ok(gid) => unsafe {
            libc::getgrgid_r(gid, &mut grp, buf.as_mut_ptr(), buf.len(), &mut found)
        },
        Err(_) => {
            let c = std::ffi::CString::new(name).ok()?;
            // SAFETY: as above; `c` is NUL-terminated
            unsafe {
                libc::getgrnam_r(
                    c.as_ptr(),
                    &mut grp,
                    buf.as_mut_ptr(),
                    buf.len(),
                    &mut found,
                )
            }
        }
    };
    (r == 0 && !found.is_null()).then_some(grp.gr_gid)
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
                self.max_pulse_samples
                    .unwrap_or(SegmentRules::CSV_BENCH.max_pulse_samples),
                1,
                4_096,
                "1..=4096 samples",
            )?,
        })
    }
}
