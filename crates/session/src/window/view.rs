//! What the window shows the outside: the output channel it keeps, why it is identified, the
//! read-only view the identifier gets, and what a sample did.

use std::time::Instant;

use super::super::item::SampleItem;

/// Which output channel is identified.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputChannel {
    /// Thrust, N.
    Thrust,
    /// Torque, N·m.
    Torque,
    /// Rotor speed, rev/min.
    Rpm,
}

impl OutputChannel {
    /// From the config name (`thrust_N`, `torque_Nm`, `rpm`).
    pub fn from_name(name: &str) -> Option<OutputChannel> {
        match name {
            "thrust_N" => Some(OutputChannel::Thrust),
            "torque_Nm" => Some(OutputChannel::Torque),
            "rpm" => Some(OutputChannel::Rpm),
            _ => None,
        }
    }

    pub(super) fn pick(self, s: &SampleItem) -> f64 {
        f64::from(match self {
            OutputChannel::Thrust => s.thrust_n,
            OutputChannel::Torque => s.torque_nm,
            OutputChannel::Rpm => s.rpm,
        })
    }
}

/// Why a window is identified (published as the model line's `reason`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    /// K pulses done and the next one started.
    Pulses,
    /// The operating point ended (ramp or level change).
    LevelEnd,
    /// The window reached its capacity.
    #[serde(rename = "window_full")]
    Full,
    /// The device started a new segment.
    Segment,
    /// The device clock jumped (no fit spans it).
    ClockJump,
    /// The stream ended.
    End,
}

/// A read-only view of a window handed to the identifier.
#[derive(Debug, Clone, Copy)]
pub struct WindowView<'a> {
    /// Throttle, fraction 0..1 (NaN where missing).
    pub input: &'a [f64],
    /// The output channel (NaN where missing).
    pub output: &'a [f64],
    /// Missing-sample mask.
    pub missing: &'a [bool],
    /// Sample positions (in the window) of the pulse starts.
    pub pulse_starts: &'a [usize],
    /// Sample period from the device clock, s.
    pub dt_s: f64,
    /// Operating point: the throttle level, fraction 0..1.
    pub level: f64,
    /// Operating points seen so far (0-based number of this one).
    pub level_number: u32,
    /// Device sample index of the window's first sample.
    pub first_index: u64,
    /// Device time of the window's last sample, µs (unwrapped).
    pub last_t_us: u64,
    /// When the window's last sample was received (latency measurement).
    pub last_received: Option<Instant>,
    /// Why it is identified.
    pub reason: Reason,
}

/// What a sample did to the window, for counters and events.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Outcome {
    /// A pulse started at this sample.
    pub pulse: bool,
    /// A new operating point started at this sample.
    pub new_level: bool,
    /// The window was full and restarted without K pulses (data discarded).
    pub overflowed: bool,
    /// Samples missing just before this one that no gap announced (an index jump).
    pub unannounced_lost: u64,
    /// A window this sample closed with fewer than K pulses (the index going back, the
    /// operating point's end).
    pub cut: Option<super::Interrupted>,
}
