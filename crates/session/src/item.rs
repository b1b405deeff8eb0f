//! What the sampler hands the worker over the bounded queue.
//!
//! Items are small values without heap (but for the rare [`Item::Record`]), so queueing one
//! never allocates. Samples carry
//! their unwrapped device index and time; gaps and new segments travel as their own items so
//! the worker never bridges them.

use std::time::Instant;

/// SAMPLE flag bits (docs/PROTOCOL.md §3).
pub mod flags {
    /// The motor is armed.
    pub const ARMED: u16 = 1 << 0;
    /// A device-timed pulse is being applied.
    pub const IMPULSE_ACTIVE: u16 = 1 << 6;
    /// A throttle ramp is running.
    pub const RAMP_ACTIVE: u16 = 1 << 7;
    /// The watchdog tripped.
    pub const WATCHDOG_TRIPPED: u16 = 1 << 8;
}

/// One decoded, placed SAMPLE.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleItem {
    /// Unwrapped sample index within the segment.
    pub index: u64,
    /// Unwrapped device time, µs.
    pub t_us: u64,
    /// Throttle applied during the sample period, raw 0..10000.
    pub throttle_raw: u16,
    /// Flags as sent.
    pub flags: u16,
    /// Thrust, N (NaN if not valid).
    pub thrust_n: f32,
    /// Torque, N·m (NaN if not valid).
    pub torque_nm: f32,
    /// Rotor speed, rev/min (NaN if not valid).
    pub rpm: f32,
    /// Supply voltage, V (NaN if not valid).
    pub voltage_v: f32,
    /// Current, A (NaN if not valid).
    pub current_a: f32,
    /// When the sampler decoded it (for latency measurements only; never published).
    pub received: Instant,
}

impl SampleItem {
    /// Throttle as a fraction 0..1.
    pub fn throttle(&self) -> f64 {
        f64::from(self.throttle_raw) / 10_000.0
    }

    /// Whether a flag bit is set.
    pub fn has(&self, flag: u16) -> bool {
        self.flags & flag != 0
    }
}

/// A device EVENT, placed in the segment's numbering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventItem {
    /// Event code (docs/PROTOCOL.md §3, 0x44).
    pub code: u8,
    /// Code-specific argument.
    pub arg: u16,
    /// Unwrapped device time, µs.
    pub t_us: u64,
    /// Unwrapped sample index.
    pub sample_index: u64,
}

/// A fact about the link, published as an `"event"` or `"warning"` line
/// ([`super::line::Line::notice`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Notice {
    /// The link dropped.
    Disconnected,
    /// The link was reopened.
    Reconnected {
        /// The device node the configured path now is (a symlink resolved), when it resolves.
        device_node: Option<String>,
    },
    /// STOP was acknowledged at shutdown.
    Stopped,
    /// STOP was not acknowledged within the shutdown timeout.
    StopUnacknowledged,
    /// The link speaks the CSV fallback (docs/PROTOCOL.md §6).
    CsvLink,
    /// A CSV bench that never acknowledged a command: sampled only, no plan (docs/PROTOCOL.md §6).
    PassiveBench,
    /// Nothing heard from a live link for [`super::sampler::SILENCE_TIMEOUT`] after it opened.
    NoData,
    /// The link went silent (no data, no ACK) for `[device] stall_timeout_ms`: STOP was tried
    /// and the port is closed and reopened.
    LinkStalled {
        /// How long nothing was heard, ms.
        silent_ms: u64,
        /// Whether the STOP was acknowledged.
        stop_acknowledged: bool,
    },
    /// Bytes arrive again after a [`Notice::LinkStalled`].
    LinkResumed {
        /// How long nothing was heard, ms.
        silent_ms: u64,
    },
}

/// What the experiment plan reported, published as an `"event"` or `"warning"` line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlanNote {
    /// Handshake done.
    Connected {
        /// The device's boot id.
        boot_id: u32,
    },
    /// ARM acknowledged.
    Armed,
    /// An operating point is reached and settled.
    LevelReached {
        /// Index in the configured list.
        index: usize,
        /// Throttle fraction.
        level: f64,
    },
    /// A pulse was acknowledged (not published: pulses are counted).
    PulseFired,
    /// The pulses at an operating point are done.
    LevelDone {
        /// Index in the configured list.
        index: usize,
        /// Throttle fraction.
        level: f64,
    },
    /// All operating points done, ramped down, disarmed.
    Finished,
    /// STOP acknowledged.
    Stopped,
    /// The device reset; the plan is over, or re-arms (`rearm_on_reset`).
    DeviceReset {
        /// The new boot id.
        new_boot_id: u32,
        /// The plan re-arms.
        rearm: bool,
    },
    /// The device's watchdog stopped the motor; the plan is over.
    WatchdogTripped,
    /// The device refused a command the plan needs; the plan is over.
    Refused {
        /// Protocol name of the command.
        command: &'static str,
    },
    /// A command went unanswered after its re-sends.
    LinkFailed {
        /// Protocol name of the command.
        command: &'static str,
    },
    /// The device reset or stalled once more after `max_rearms` re-arms; the plan is over.
    RearmLimit {
        /// Re-arms done.
        rearms: u32,
    },
    /// The applied throttle stayed outside what the plan commanded; the plan is over.
    ThrottleMismatch {
        /// Lowest commanded throttle, fraction.
        commanded_min: f64,
        /// Highest commanded throttle, fraction.
        commanded_max: f64,
        /// The throttle the device reported, fraction.
        applied: f64,
        /// How long, ms.
        for_ms: u64,
    },
    /// Commands acknowledged and never seen in the samples; the plan is over.
    CommandsNotExecuted {
        /// Protocol name of the command.
        command: &'static str,
        /// The level it commanded, fraction.
        level: f64,
    },
    /// The plan stopped on a sample rate other than the HELLO's (published from
    /// [`Item::RateMismatch`]).
    RateMismatch,
}

/// One item on the sampler → worker queue.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    /// A sample.
    Sample(SampleItem),
    /// `count` samples before index `before` were lost.
    Gap {
        /// The index of the first sample after the gap.
        before: u64,
        /// Samples lost.
        count: u64,
    },
    /// A new segment (device boot) starts with the next sample.
    Segment {
        /// The device's boot id (0 if the segment was inferred from the index going back).
        boot_id: u32,
    },
    /// The device clock jumped before the sample with this index (the window closes: no fit
    /// spans it).
    ClockJump {
        /// Device index of the sample after the jump.
        index: u64,
        /// The clock's step, µs (negative: backwards).
        step_us: i64,
        /// The step the index step said, µs.
        expected_us: f64,
    },
    /// The device's measured sample rate disagrees with its HELLO's.
    RateMismatch {
        /// The HELLO's rate, Hz.
        hello_hz: u16,
        /// The measured one, Hz.
        measured_hz: f64,
    },
    /// A device event.
    Event(EventItem),
    /// A link fact.
    Notice(Notice),
    /// An experiment-plan fact.
    Plan(PlanNote),
    /// A recording fact (a file opened, a write failure): rare, the one item that holds heap.
    Record(super::record_note::RecordNote),
}
