//! The uniformly sampled record: what every reader (TSP/1 recording, live stream, CSV file)
//! produces and what the identification core consumes.
//!
//! Conventions:
//! - Sample `k` is at time `t0_s + k * dt_s`.
//! - Channel names are canonical (see [`names`]); units are SI except throttle, which is the
//!   fraction 0..1 (TSP/1 carries 0..10000).
//! - A sample that was not measured (a gap in `sample_index`, a dropped frame, a row that was
//!   skipped) is marked in `missing`, and every channel holds `f64::NAN` there. A CSV file's
//!   empty cell is a missing value of its own channel only: there `missing` marks the samples
//!   where the input or an output a reader was asked for has no value, and a channel read beside
//!   them (a static map's current, diagnose's voltage) keeps its own NaNs. A NaN in the input or
//!   an output at a sample that is *not* marked missing is bad input, and the core refuses it
//!   with a typed error.
//! - `events` carry device-side facts with exact sample indices (impulse edges, boot segments).

use serde::Serialize;

/// Canonical channel names.
pub mod names {
    /// Throttle applied during the sample period, fraction 0..1.
    pub const THROTTLE: &str = "throttle";
    /// Thrust, newtons.
    pub const THRUST: &str = "thrust_N";
    /// Torque, newton metres.
    pub const TORQUE: &str = "torque_Nm";
    /// Mechanical rotor speed, rev/min.
    pub const RPM: &str = "rpm";
    /// Supply voltage, volts.
    pub const VOLTAGE: &str = "voltage_V";
    /// Supply current, amperes.
    pub const CURRENT: &str = "current_A";
}

/// One sampled signal.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Channel {
    /// Canonical name (see [`names`]) or the source's own name when it has no canonical one.
    pub name: String,
    /// Unit as text, for reports ("N", "N·m", "rev/min", "V", "A", "1").
    pub unit: String,
    /// One value per sample; `NaN` exactly where the record marks the sample missing.
    pub data: Vec<f64>,
    /// True at the samples whose value a reader interpolated between two of the channel's own
    /// readings (a sensor written on fewer rows than the record has, or repeating its last
    /// reading): not a measurement at that instant. Empty when every value is a reading (every
    /// TSP/1 record). What needs the readings themselves (a noise floor) takes them from here.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub interpolated: Vec<bool>,
}

impl Channel {
    /// A channel whose every value is a reading.
    pub fn read(name: impl Into<String>, unit: impl Into<String>, data: Vec<f64>) -> Channel {
        Channel {
            name: name.into(),
            unit: unit.into(),
            data,
            interpolated: Vec::new(),
        }
    }
}

/// What happened at a sample, as the device (or a reader) reported it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum RecordEventKind {
    /// EVENT IMPULSE_START: the first sample of a device-timed pulse.
    ImpulseStart,
    /// EVENT IMPULSE_END: the first sample after the pulse.
    ImpulseEnd,
    /// A new device boot (`boot_id` changed): a new segment starts here.
    SegmentStart,
    /// The watchdog tripped.
    WatchdogTrip,
}

/// An event at an exact sample index of the record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct RecordEvent {
    /// Index into the record's samples.
    pub sample: usize,
    /// What happened.
    pub kind: RecordEventKind,
}

/// A uniformly sampled, multi-channel record.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Record {
    /// Sample period, seconds (> 0).
    pub dt_s: f64,
    /// Time of sample 0, seconds.
    pub t0_s: f64,
    /// The channels, all of the same length.
    pub channels: Vec<Channel>,
    /// `missing[k]` is true where sample `k` was not measured (see the module documentation).
    pub missing: Vec<bool>,
    /// Device events at sample indices, in order.
    pub events: Vec<RecordEvent>,
}

impl Record {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.missing.len()
    }

    /// True when the record holds no samples.
    pub fn is_empty(&self) -> bool {
        self.missing.is_empty()
    }

    /// The channel with this name, if present.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        self.channels.iter().find(|c| c.name == name)
    }

    /// Number of samples marked missing.
    pub fn missing_count(&self) -> usize {
        self.missing.iter().filter(|m| **m).count()
    }

    /// Sample indices of device-reported impulse starts.
    pub fn impulse_starts(&self) -> impl Iterator<Item = usize> + '_ {
        self.events
            .iter()
            .filter(|e| e.kind == RecordEventKind::ImpulseStart)
            .map(|e| e.sample)
    }
}
