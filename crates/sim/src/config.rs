//! `config/sim.toml`: the simulated stand's configuration, in two phases (parse, then validate).
//!
//! Parsing refuses unknown keys and wrong types (serde, `deny_unknown_fields`; the TOML error
//! shows the offending line). [`SimConfig::validate`] then refuses NaN and out-of-range values,
//! naming the key and the value. Every range check is written as a positive condition
//! (`x.is_finite() && x >= lo`) so that NaN never passes.

use serde::Deserialize;
use std::path::Path;

use super::plant::{PlantConfig, PlantError};
use propid_wire::experiment::ExperimentConfig;

/// A refused configuration.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file is not valid TOML, has an unknown key or a value of the wrong type.
    #[error("{path}: {source}")]
    Parse {
        /// The file (or `<string>`).
        path: String,
        /// The parser's error, whose message shows the offending line.
        source: toml::de::Error,
    },
    /// A value is NaN or outside its range.
    #[error("config key `{key}` = {value}: {reason}")]
    Invalid {
        /// Full dotted key, e.g. `stand.sample_rate_hz`.
        key: String,
        /// The refused value, as written.
        value: String,
        /// The allowed range or form.
        reason: String,
    },
    /// The file could not be read.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
}

/// Which wire format the simulated stand speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum WireProtocol {
    /// TSP/1 binary frames (COBS + CRC), docs/PROTOCOL.md §2–4.
    #[default]
    Tsp,
    /// The CSV text fallback, docs/PROTOCOL.md §6.
    Csv,
}

/// `[stand]`: the firmware's identity, clock and sample rate.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StandConfig {
    /// Name in HELLO, ASCII, at most 16 characters.
    pub name: String,
    /// Wire format: `"tsp"` (default) or `"csv"`.
    pub protocol: WireProtocol,
    /// Nominal sample rate, Hz, 10..=20000.
    pub sample_rate_hz: u32,
    /// Firmware version reported in HELLO (0..=65535).
    pub fw_version: u16,
    /// ESC protocol code reported in HELLO (0..=6, or 255 = none).
    pub esc_protocol: u8,
    /// Motor pole count reported in HELLO, 0 (unknown) ..= 64.
    pub motor_poles: u8,
    /// Device clock (`t_us`) at boot, µs, 0..=4294967295; set it near 2^32 to make the
    /// 32-bit clock wrap soon.
    pub initial_t_us: u32,
    /// Period of the unsolicited HELLO, ms, 100..=10000 (the protocol says one second).
    pub hello_period_ms: u32,
    /// Seed for boot ids, noise and faults (any non-negative integer): same seed, same bytes.
    pub seed: u64,
}

impl Default for StandConfig {
    fn default() -> Self {
        StandConfig {
            name: "propid-sim".into(),
            protocol: WireProtocol::Tsp,
            sample_rate_hz: 1000,
            fw_version: 1,
            esc_protocol: 5,
            motor_poles: 14,
            initial_t_us: 0,
            hello_period_ms: 1000,
            seed: 1,
        }
    }
}

/// `[faults]`: what goes wrong on the link, on request. All off by default.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FaultConfig {
    /// Probability per output byte of one flipped bit, 0..=0.1. At most one flip per frame and
    /// never onto the 0x00 delimiter, so each flip costs exactly one frame.
    pub bit_flip_per_byte: f64,
    /// Rate of garbage bursts inserted between frames, per second, 0..=1000.
    pub garbage_bursts_per_s: f64,
    /// Length of one garbage burst, bytes, 1..=1024 (non-zero bytes, then one 0x00).
    pub garbage_burst_bytes: u32,
    /// Probability per SAMPLE that it is not sent (its `sample_index` is skipped), 0..=0.5.
    pub drop_sample_prob: f64,
    /// Probability per SAMPLE that a burst of `drop_burst_samples` dropped SAMPLEs starts
    /// there (a serial link losing a run of bytes), 0..=0.1.
    pub drop_burst_prob: f64,
    /// SAMPLEs dropped per burst, 1..=100000.
    pub drop_burst_samples: u32,
    /// Rate of stalls (no output, then everything at once), per second, 0..=100.
    pub stalls_per_s: f64,
    /// Length of one stall, ms, 1..=10000.
    pub stall_ms: u32,
    /// Hang up (close the pty master: the host sees EOF/BrokenPipe) after this many seconds of
    /// running, s, 0 (never) ..= 86400. Repeats after every reopen.
    pub hangup_after_s: f64,
    /// After a hang-up, open a new pty (and re-point `--link`) as a new boot after this delay, ms,
    /// 0..=60000; negative means never reopen (the runner ends).
    pub reopen_after_ms: i64,
    /// Hang up every this many seconds of the run (the run's clock, not the boot's), s, 0
    /// (never) ..= 86400: the link is cut, what is on the wire is given time to reach the host,
    /// the pty closes and re-opens as a new boot after `reopen_after_ms` (at least 0 here).
    /// Skipped while no host has the port open or the faults are off (`--faults-for`).
    pub hangup_every_s: f64,
    /// Reset the device every this many seconds of the run, the port kept open (a brown-out or
    /// watchdog reset behind a USB-serial bridge): a new boot on the same pty, new boot id,
    /// disarmed, counters restarted; output not yet sent is lost. s, 0 (never) ..= 86400;
    /// skipped like `hangup_every_s`.
    pub reset_every_s: f64,
    /// Freeze (the firmware hangs: nothing sent, commands dropped, the pty kept open) after this
    /// many seconds of the first boot, s, 0 (never) ..= 86400. The host closing the port resets
    /// the board (a new boot on the same pty, as DTR resets an Arduino); once per run.
    pub freeze_after_s: f64,
    /// SAMPLEs never sent, by `sample_index` (as the device counts them, from 0 at boot): drops
    /// at exact places, for tests that assert exact counts. At most 65536 indices.
    pub drop_samples_at: Vec<u32>,
    /// SAMPLEs whose frame gets one flipped bit, by `sample_index` (each costs the host that
    /// frame and that sample). At most 65536 indices.
    pub corrupt_samples_at: Vec<u32>,
    /// SAMPLEs before whose frame a garbage burst is inserted, by `sample_index` (each costs the
    /// host one dropped frame). At most 65536 indices.
    pub garbage_before_samples_at: Vec<u32>,
    /// A stand that lies (issue 27; the faults below are the firmware's, not the link's): a
    /// runaway ESC — while armed with any throttle above 0, the motor gets full throttle and
    /// every SAMPLE says so.
    pub runaway_throttle: bool,
    /// Every IMPULSE is answered BUSY (and not executed).
    pub busy_impulses: bool,
    /// SET_THROTTLE and IMPULSE are acknowledged OK and never executed (the motor never
    /// moves; ARM, STOP, DISARM work).
    pub ignore_commands: bool,
    /// The rate the HELLO claims, Hz (0..=65535), whatever the stand samples at; absent: the
    /// true one.
    pub hello_rate_hz: Option<u16>,
    /// The device clock (`t_us`) steps by `clock_jump_us` every this many samples while the
    /// sample index runs on, 0 (never) ..= 2^32-1.
    pub clock_jump_every_samples: u32,
    /// The step of each clock jump, µs (negative: backwards), -10^9..=10^9.
    pub clock_jump_us: i64,
    /// Every this many SAMPLEs (from index 0) four in a row carry an absurd thrust with
    /// THRUST_VALID set: 3e38, -inf, -3e38, +inf; 0 = never, else 4 or more.
    pub absurd_thrust_every_samples: u32,
}

impl Default for FaultConfig {
    fn default() -> Self {
        FaultConfig {
            bit_flip_per_byte: 0.0,
            garbage_bursts_per_s: 0.0,
            garbage_burst_bytes: 32,
            drop_sample_prob: 0.0,
            drop_burst_prob: 0.0,
            drop_burst_samples: 20,
            stalls_per_s: 0.0,
            stall_ms: 50,
            hangup_after_s: 0.0,
            reopen_after_ms: -1,
            freeze_after_s: 0.0,
            hangup_every_s: 0.0,
            reset_every_s: 0.0,
            drop_samples_at: Vec::new(),
            corrupt_samples_at: Vec::new(),
            garbage_before_samples_at: Vec::new(),
            runaway_throttle: false,
            busy_impulses: false,
            ignore_commands: false,
            hello_rate_hz: None,
            clock_jump_every_samples: 0,
            clock_jump_us: 0,
            absurd_thrust_every_samples: 0,
        }
    }
}

/// The whole of `config/sim.toml`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimConfig {
    /// Firmware identity, clock and rate.
    pub stand: StandConfig,
    /// Link faults.
    pub faults: FaultConfig,
    /// The simulated motor + propeller + load cell and its effects (`[plant]`,
    /// `[plant.effects.*]`; keys as defined by [`PlantConfig`]).
    pub plant: PlantConfig,
    /// The host-side plan that `propid sim --record` runs against the firmware.
    pub experiment: ExperimentConfig,
}

impl SimConfig {
    /// Parses and validates a configuration from TOML text; `path` only labels errors.
    pub fn from_toml_str(text: &str, path: &str) -> Result<SimConfig, ConfigError> {
        let cfg: SimConfig = toml::from_str(text).map_err(|source| ConfigError::Parse {
            path: path.to_string(),
            source,
        })?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// Reads, parses and validates a configuration file.
    pub fn load(path: &Path) -> Result<SimConfig, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Refuses NaN and out-of-range values, naming the key and the value.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.stand.validate()?;
        self.faults.validate()?;
        let dt_s = 1.0 / self.stand.sample_rate_hz as f64;
        self.plant.validate(dt_s).map_err(|e| match e {
            PlantError::InvalidParameter { key, value, reason } => {
                let key = if key.starts_with("plant.") {
                    key.to_string()
                } else {
                    format!("plant.{key}")
                };
                invalid(&key, &value.to_string(), reason)
            }
            PlantError::NotForKind { key, kind, reason } => invalid(
                key,
                "(set)",
                &format!("does not apply to a plant of kind \"{kind}\": {reason}"),
            ),
        })?;
        self.experiment
            .validate()
            .map_err(|e| invalid(&format!("experiment.{}", e.key), &e.value, &e.reason))
    }
}

impl StandConfig {
    /// Range checks of `[stand]`.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let name_ok = self.name.len() <= 16 && self.name.bytes().all(|b| (0x20..0x7f).contains(&b));
        if !name_ok {
            return Err(invalid(
                "stand.name",
                &self.name,
                "printable ASCII, at most 16 characters",
            ));
        }
        check_int(
            "stand.sample_rate_hz",
            self.sample_rate_hz as i64,
            10,
            20_000,
        )?;
        if !(self.esc_protocol <= 6 || self.esc_protocol == 255) {
            return Err(invalid(
                "stand.esc_protocol",
                &self.esc_protocol.to_string(),
                "0..=6 or 255",
            ));
        }
        check_int("stand.motor_poles", self.motor_poles as i64, 0, 64)?;
        check_int(
            "stand.hello_period_ms",
            self.hello_period_ms as i64,
            100,
            10_000,
        )?;
        if self.seed > i64::MAX as u64 {
            return Err(invalid("stand.seed", &self.seed.to_string(), "0..=2^63-1"));
        }
        Ok(())
    }
}

impl FaultConfig {
    /// Range checks of `[faults]`.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_f64("faults.bit_flip_per_byte", self.bit_flip_per_byte, 0.0, 0.1)?;
        check_f64(
            "faults.garbage_bursts_per_s",
            self.garbage_bursts_per_s,
            0.0,
            1000.0,
        )?;
        check_int(
            "faults.garbage_burst_bytes",
            self.garbage_burst_bytes as i64,
            1,
            1024,
        )?;
        check_f64("faults.drop_sample_prob", self.drop_sample_prob, 0.0, 0.5)?;
        check_f64("faults.drop_burst_prob", self.drop_burst_prob, 0.0, 0.1)?;
        check_int(
            "faults.drop_burst_samples",
            self.drop_burst_samples as i64,
            1,
            100_000,
        )?;
        check_f64("faults.stalls_per_s", self.stalls_per_s, 0.0, 100.0)?;
        check_int("faults.stall_ms", self.stall_ms as i64, 1, 10_000)?;
        check_f64("faults.hangup_after_s", self.hangup_after_s, 0.0, 86_400.0)?;
        check_f64("faults.freeze_after_s", self.freeze_after_s, 0.0, 86_400.0)?;
        check_f64("faults.hangup_every_s", self.hangup_every_s, 0.0, 86_400.0)?;
        check_f64("faults.reset_every_s", self.reset_every_s, 0.0, 86_400.0)?;
        if self.absurd_thrust_every_samples > 0 {
            check_int(
                "faults.absurd_thrust_every_samples",
                self.absurd_thrust_every_samples as i64,
                4,
                u32::MAX as i64,
            )?;
        }
        check_int(
            "faults.clock_jump_us",
            self.clock_jump_us,
            -1_000_000_000,
            1_000_000_000,
        )?;
        check_int(
            "faults.reopen_after_ms",
            self.reopen_after_ms,
            i64::MIN,
            60_000,
        )?;
        for (key, list) in [
            ("faults.drop_samples_at", &self.drop_samples_at),
            ("faults.corrupt_samples_at", &self.corrupt_samples_at),
            (
                "faults.garbage_before_samples_at",
                &self.garbage_before_samples_at,
            ),
        ] {
            check_int(&format!("{key}.len()"), list.len() as i64, 0, 65_536)?;
        }
        Ok(())
    }

    /// True when no fault is switched on.
    pub fn is_clean(&self) -> bool {
        self.bit_flip_per_byte == 0.0
            && self.garbage_bursts_per_s == 0.0
            && self.drop_sample_prob == 0.0
            && self.drop_burst_prob == 0.0
            && self.stalls_per_s == 0.0
            && self.hangup_after_s == 0.0
            && self.freeze_after_s == 0.0
            && self.hangup_every_s == 0.0
            && self.reset_every_s == 0.0
            && self.drop_samples_at.is_empty()
            && self.corrupt_samples_at.is_empty()
            && self.garbage_before_samples_at.is_empty()
            && !self.lies()
    }

    /// True when the firmware lies (runaway throttle, BUSY, ignored commands, a HELLO rate, clock
    /// jumps, absurd values).
    pub fn lies(&self) -> bool {
        self.runaway_throttle
            || self.busy_impulses
            || self.ignore_commands
            || self.hello_rate_hz.is_some()
            || self.clock_jump_every_samples > 0
            || self.absurd_thrust_every_samples > 0
    }
}

/// An [`ConfigError::Invalid`].
pub fn invalid(key: &str, value: &str, reason: &str) -> ConfigError {
    ConfigError::Invalid {
        key: key.to_string(),
        value: value.to_string(),
        reason: reason.to_string(),
    }
}

/// `lo <= v <= hi` and finite, else an error naming `key` and `v`.
pub fn check_f64(key: &str, v: f64, lo: f64, hi: f64) -> Result<(), ConfigError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(invalid(
            key,
            &v.to_string(),
            &format!("a finite number in {lo}..={hi}"),
        ))
    }
}

/// `lo <= v <= hi`, else an error naming `key` and `v`.
pub fn check_int(key: &str, v: i64, lo: i64, hi: i64) -> Result<(), ConfigError> {
    if v >= lo && v <= hi {
        Ok(())
    } else {
        Err(invalid(
            key,
            &v.to_string(),
            &format!("an integer in {lo}..={hi}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_text_gives_defaults() {
        let cfg = SimConfig::from_toml_str("", "t").unwrap();
        assert_eq!(cfg, SimConfig::default());
    }

    #[test]
    fn unknown_key_is_refused_with_its_name() {
        let err = SimConfig::from_toml_str("[stand]\nsample_rate = 5\n", "t").unwrap_err();
        assert!(err.to_string().contains("sample_rate"), "{err}");
    }

    #[test]
    fn wrong_type_is_refused() {
        let err =
            SimConfig::from_toml_str("[stand]\nsample_rate_hz = \"fast\"\n", "t").unwrap_err();
        assert!(matches!(err, ConfigError::Parse { .. }), "{err}");
        assert!(err.to_string().contains("sample_rate_hz"), "{err}");
    }

    #[test]
    fn nan_is_refused_naming_key_and_value() {
        let err = SimConfig::from_toml_str("[faults]\nbit_flip_per_byte = nan\n", "t").unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("faults.bit_flip_per_byte") && msg.contains("NaN"),
            "{msg}"
        );
    }

    #[test]
    fn out_of_range_is_refused_naming_key_and_value() {
        let err = SimConfig::from_toml_str("[stand]\nsample_rate_hz = 5\n", "t").unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("stand.sample_rate_hz") && msg.contains("= 5"),
            "{msg}"
        );
    }

    #[test]
    fn fault_index_lists_are_read_and_bounded() {
        let cfg = SimConfig::from_toml_str("[faults]\ndrop_samples_at = [3, 1]\n", "t").unwrap();
        assert_eq!(cfg.faults.drop_samples_at, vec![3, 1]);
        assert!(!cfg.faults.is_clean());
        let err = SimConfig::from_toml_str("[faults]\ncorrupt_samples_at = [-1]\n", "t");
        assert!(matches!(err, Err(ConfigError::Parse { .. })), "{err:?}");
        let mut cfg = SimConfig::default();
        cfg.faults.garbage_before_samples_at = vec![0; 65_537];
        let msg = cfg.validate().unwrap_err().to_string();
        assert!(
            msg.contains("faults.garbage_before_samples_at.len()") && msg.contains("65537"),
            "{msg}"
        );
    }

    #[test]
    fn plant_values_are_checked_against_the_sample_rate() {
        let text = "[stand]\nsample_rate_hz = 100\n[plant]\nfn_hz = 80.0\n";
        let msg = SimConfig::from_toml_str(text, "t").unwrap_err().to_string();
        assert!(msg.contains("plant.fn_hz") && msg.contains("80"), "{msg}");
        let text = "[plant.effects.dead_time]\ndelay_s = 0.004\n";
        let cfg = SimConfig::from_toml_str(text, "t").unwrap();
        assert!(cfg.plant.effects.dead_time.is_some());
    }

    #[test]
    fn shipped_config_effect_examples_are_valid_when_uncommented() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml");
        let text = std::fs::read_to_string(path).unwrap();
        let (head, tail) = text.split_once("# Effects (issue 5)").unwrap();
        let (effects, rest) = tail.split_once("[experiment]").unwrap();
        let mut lines = effects.lines();
        lines.next(); // the rest of the heading comment
                      // the examples are the commented tables and keys; prose comments stay comments
        fn example(l: &str) -> Option<&str> {
            l.strip_prefix("# ").filter(|e| {
                e.starts_with('[') || e.split_once(" = ").is_some_and(|(k, _)| !k.contains(' '))
            })
        }
        let uncommented: Vec<&str> = lines.map(|l| example(l).unwrap_or(l)).collect();
        let all = format!("{head}\n{}\n[experiment]{rest}", uncommented.join("\n"));
        // the two core effects are the 2nd-order plant's: the shipped motor refuses them
        let msg = SimConfig::from_toml_str(&all, "uncommented")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("plant.effects.asymmetric_dynamics"), "{msg}");
        let second_order = all.replacen("kind = \"motor\"", "kind = \"second_order\"", 1);
        let cfg = SimConfig::from_toml_str(&second_order, "uncommented").unwrap();
        assert_eq!(cfg.plant.effects.names().len(), 9);
    }

    #[test]
    fn shipped_config_file_loads() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml");
        let cfg = SimConfig::load(&path).unwrap();
        assert_eq!(cfg.stand.protocol, WireProtocol::Tsp);
        // the motor, every other key at its default
        assert_eq!(cfg.plant.kind, crate::plant::PlantKind::Motor);
        let mut default = SimConfig::default();
        default.plant.kind = crate::plant::PlantKind::Motor;
        assert_eq!(cfg, default);
    }
}
