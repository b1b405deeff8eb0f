//! The published lines, typed: what the daemon says, one [`Line`] per JSON line.
//!
//! - `{"type":"model", "t_s", "operating_point", "level", "first_sample", "samples", "reason",
//!   "path", ["outliers"], <the model fields of propid identify --json>}` ([`WindowModel`]): `t_s`
//!   is the device time of the window's last sample (unwrapped, s), `operating_point` the
//!   throttle level (fraction), `outliers` the isolated outlier samples left out (when > 0).
//! - `{"type":"event", "kind", ...}` ([`Event`]) and `{"type":"warning", "kind", ["message"],
//!   ...}` ([`Warning`]); a model that fails the quality checks is a `model_unreliable`
//!   warning with the model's fields and the `reasons`.
//! - At the end `{"type":"schedule", "models":[...]}` ([`ScheduleRow`]): the last model per
//!   operating point (the gain schedule a flight controller needs), ordered by operating point;
//!   then `{"type":"stats", ...}` ([`StatsLine`]).
//! - With `[experiment] kind` other than pulses (`propid_kinds`, docs/experiment-kinds.md):
//!   `{"type":"step", "kind", "index", "output", <step figures>}` as each staircase step's
//!   hold ends, `{"type":"static_map", "kind", "output", ["leg"], "unit", "levels", ...}`
//!   and `{"type":"frequency_response", "kind", "output", "level", "bins", "peak_hz",
//!   "bandwidth_hz", "phase_delay_s", "model", ...}` at the end, before the schedule, and
//!   the model fitted to it as a `{"type":"model", "kind", "output", "path":
//!   "frequency_response", "dead_time_s", "rms_rel_error", <the pulse model line's fields>}`
//!   ([`propid_kinds::ModelLine`]; not in the schedule).
//! - With `--http` only: `{"type":"event","kind":"http","url"}` first, and the lines only the
//!   web page's clients get ([`super::live`]: `samples`, `response`, `stabilization`,
//!   `live_stats`, and a `schedule` after every model).
//!
//! **Serialised once, keys sorted.** [`Publisher::publish_line`](super::publish::Publisher)
//! turns a line into its bytes in one place ([`Line::to_json`]): through a
//! [`serde_json::Value`], whose objects are sorted maps (the workspace does not enable
//! serde_json's `preserve_order`), so every object of every line has its keys in sorted order
//! whatever the declaration order of the fields here, and the model fields (declared by the
//! identification core's [`ModelReport`]) interleave with the window's exactly as they always
//! have. `worker/pinned_lines.jsonl` pins the bytes of every kind of line.

use serde::{Serialize, Serializer};
use std::fmt::Display;
use std::time::Instant;

use super::identify::IdentifyError;
use super::item::{EventItem, Notice, PlanNote};
use super::live::{ResponseLine, SamplesLine, StabilizationLine};
use super::quality::{Flaw, HINT};
use super::stats::StatsLine;
use super::window::{Reason, WindowView};
use propid_numerics::identify::PathTaken;
use propid_numerics::nullable;
use propid_numerics::report::{Gain, Uncertainty};
use propid_numerics::ModelReport;

/// What a model line says about the window the model comes from (no samples: copying it
/// allocates nothing).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WindowFacts {
    /// Device time of the window's last sample (unwrapped), s.
    pub t_s: f64,
    /// The operating point: the throttle level, fraction 0..1.
    pub operating_point: f64,
    /// The operating point's number (0-based, in the order they were reached).
    pub level: u32,
    /// Device sample index of the window's first sample.
    pub first_sample: u64,
    /// Samples in the window.
    pub samples: usize,
    /// Why the window was identified.
    pub reason: Reason,
    /// When the window's last sample was received (latency only; never published).
    #[serde(skip)]
    pub last_received: Option<Instant>,
}

impl From<&WindowView<'_>> for WindowFacts {
    fn from(v: &WindowView<'_>) -> Self {
        WindowFacts {
            t_s: v.last_t_us as f64 * 1e-6,
            operating_point: v.level,
            level: v.level_number,
            first_sample: v.first_index,
            samples: v.input.len(),
            reason: v.reason,
            last_received: v.last_received,
        }
    }
}

/// A model identified from one window: the window's facts and the core's report, flattened
/// into one object.
#[derive(Debug, Clone, Serialize)]
pub struct WindowModel {
    /// The window.
    #[serde(flatten)]
    pub window: WindowFacts,
    /// How the Markov parameters were obtained: always `"pulse"` (the daemon identifies
    /// windows of pulses; `propid identify` reports the same in `source.path`).
    pub path: PathTaken,
    /// Isolated outlier samples of the window's output left out (marked missing, counted in
    /// `missing_samples` too; `propid identify`'s `source.outliers`); absent when 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub outliers: usize,
    /// The model (the fields of `propid identify --json`'s `"model"`).
    #[serde(flatten)]
    pub report: ModelReport,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// One row of the gain schedule: an operating point and its last reliable model, in short.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScheduleRow {
    /// The operating point (as first published for its number), fraction.
    pub operating_point: f64,
    /// Model order.
    pub order: usize,
    /// Natural frequency, Hz.
    #[serde(with = "nullable::num")]
    pub fn_hz: f64,
    /// Damping ratio.
    #[serde(with = "nullable::num")]
    pub zeta: f64,
    /// DC gain, output units per unit throttle.
    pub dc_gain: Gain,
    /// Time constants of the real poles, s.
    #[serde(with = "nullable::vec")]
    pub time_constants_s: Vec<f64>,
    /// Pulses averaged.
    pub pulses: usize,
    /// Jackknife standard deviations.
    pub uncertainty: Uncertainty,
}

impl ScheduleRow {
    /// The row of `report` at `operating_point`.
    pub fn new(operating_point: f64, report: &ModelReport) -> ScheduleRow {
        ScheduleRow {
            operating_point,
            order: report.order,
            fn_hz: report.fn_hz,
            zeta: report.zeta,
            dc_gain: report.dc_gain.clone(),
            time_constants_s: report.time_constants_s.clone(),
            pulses: report.pulses,
            uncertainty: report.uncertainty.clone(),
        }
    }
}

/// A device EVENT as published (its kind is the [`Event`] or [`Warning`] variant).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DeviceEvent {
    /// Event code (docs/PROTOCOL.md §3, 0x44).
    pub code: u8,
    /// Code-specific argument.
    pub arg: u16,
    /// Device time (unwrapped), s.
    pub t_s: f64,
    /// Sample index (unwrapped).
    pub sample_index: u64,
}

/// An `"event"` line: something that happened, no action needed.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// `count` samples before index `before` were lost (masked, not bridged).
    Gap {
        /// The index of the first sample after the gap.
        before: u64,
        /// Samples lost.
        count: u64,
    },
    /// A new device segment (boot) starts.
    Segment {
        /// The device's boot id (0 when inferred from the index going back).
        boot_id: u32,
    },
    /// The plan's handshake is done.
    Connected {
        /// The device's boot id.
        boot_id: u32,
    },
    /// ARM acknowledged.
    ArmAcknowledged,
    /// An operating point is reached and settled.
    LevelReached {
        /// Index in the configured list.
        index: usize,
        /// Throttle fraction.
        operating_point: f64,
    },
    /// The pulses at an operating point are done.
    LevelDone {
        /// Index in the configured list.
        index: usize,
        /// Throttle fraction.
        operating_point: f64,
    },
    /// All operating points done, ramped down, disarmed.
    PlanFinished,
    /// STOP acknowledged (the plan's).
    StopAcknowledged,
    /// The link was reopened.
    Reconnected {
        /// The device node the configured path resolves to now (the udev symlink followed).
        #[serde(skip_serializing_if = "Option::is_none")]
        device_node: Option<String>,
    },
    /// Bytes arrive again after a `link_stalled` warning.
    LinkResumed {
        /// How long nothing was heard, ms.
        silent_ms: u64,
    },
    /// The shutdown STOP was acknowledged.
    ShutdownStopAcknowledged,
    /// The link speaks the CSV fallback (docs/PROTOCOL.md §6).
    CsvLink,
    /// The raw recording goes to this file from now on (the first, or the next after a
    /// rotation; never one that existed).
    Recording {
        /// The file's path.
        path: String,
    },
    /// The live web page is served at this URL (`--http`; its bound port when 0 was asked).
    Http {
        /// `http://ADDRESS:PORT/`.
        url: String,
    },
    /// A sample breached a `[limits]` limit: STOP sent, the plan is over for good (exit 8).
    LimitTripped {
        /// The limit's key (`max_current_a`, …).
        which: &'static str,
        /// What the sample showed (A, N, rev/min, V; throttle as a fraction).
        value: f64,
        /// The limit.
        limit: f64,
    },
    /// Device event ARMED.
    Armed(DeviceEvent),
    /// Device event DISARMED.
    Disarmed(DeviceEvent),
    /// Device event RESET_CAUSE.
    ResetCause(DeviceEvent),
    /// Device event TARE_DONE.
    TareDone(DeviceEvent),
}

/// A `"warning"` line: something went wrong or needs the operator. Kinds with a fixed
/// explanation publish it as `"message"` ([`Warning::message`]).
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Warning<'a> {
    /// The link dropped.
    Disconnected,
    /// The shutdown STOP was not acknowledged within the stop timeout.
    ShutdownStopUnacknowledged,
    /// A CSV bench that never acknowledged a command: sampled only, no plan.
    PassiveBench,
    /// Nothing heard from a live link after it opened.
    NoData,
    /// The device reset; the plan is over.
    DeviceReset {
        /// The new boot id.
        boot_id: u32,
    },
    /// The device reset; the plan hand-shakes, re-arms and resumes (`rearm_on_reset`). The same
    /// kind as [`Warning::DeviceReset`], with `"rearm": true`.
    #[serde(rename = "device_reset")]
    DeviceResetRearm {
        /// The new boot id.
        boot_id: u32,
        /// Always true.
        rearm: bool,
    },
    /// The link stayed open but silent (no data, no ACK) for `device.stall_timeout_ms`: STOP
    /// was tried, the port is closed and reopened.
    LinkStalled {
        /// How long nothing was heard, ms.
        silent_ms: u64,
        /// Whether the device acknowledged the STOP.
        stop_acknowledged: bool,
    },
    /// The device reset or the link stalled once more after `experiment.max_rearms` re-arms;
    /// the plan is over (exit 8).
    RearmLimitReached {
        /// Re-arms done.
        rearms: u32,
    },
    /// The device watchdog stopped the motor; the plan is over.
    PlanHaltedWatchdog,
    /// The device refused a command the plan needs; the plan is over.
    CommandRefused {
        /// Protocol name of the command.
        command: &'static str,
    },
    /// A command went unanswered after its re-sends.
    LinkFailed {
        /// Protocol name of the command.
        command: &'static str,
    },
    /// The throttle the device reports applying stayed outside what the plan commanded for
    /// longer than `propid_wire::experiment::THROTTLE_MISMATCH_MS`: STOP sent, the plan is
    /// over (exit 8).
    ThrottleMismatch {
        /// Lowest commanded throttle then, fraction.
        commanded_min: f64,
        /// Highest commanded throttle then, fraction.
        commanded_max: f64,
        /// The throttle the device reported, fraction.
        applied: f64,
        /// How long it stayed outside, ms.
        for_ms: u64,
    },
    /// The device acknowledged commands its samples never show (a level never applied, or
    /// pulses in a row without a trace): STOP sent, the plan is over (exit 8).
    CommandsNotExecuted {
        /// Protocol name of the command (`SET_THROTTLE`, `IMPULSE`).
        command: &'static str,
        /// The throttle it commanded, fraction.
        level: f64,
    },
    /// The device's sample rate measured from its clock disagrees with its HELLO's; a plan
    /// (which sizes pulses from the HELLO's rate) is stopped (exit 8).
    HelloRateMismatch {
        /// The HELLO's rate, Hz.
        hello_hz: u16,
        /// The rate the samples' clock measures, Hz.
        measured_hz: f64,
    },
    /// The device clock stepped by `step_us` where the sample index said `expected_us`: the
    /// window there is closed (no fit spans it), the samples go on.
    ClockJump {
        /// Device index of the sample after the jump.
        sample_index: u64,
        /// The clock's step, µs (negative: backwards).
        step_us: i64,
        /// What the index step and the period expected, µs.
        #[serde(serialize_with = "nullable::num::serialize")]
        expected_us: f64,
    },
    /// A `[limits]` limit on a quantity the stand has not reported: it cannot hold.
    LimitUnchecked {
        /// The limit's key.
        which: &'static str,
        /// Why (published as the message).
        #[serde(rename = "message")]
        why: &'static str,
    },
    /// Device event WATCHDOG_TRIP.
    WatchdogTrip(DeviceEvent),
    /// Device event LIMIT_CUTOFF.
    LimitCutoff(DeviceEvent),
    /// Device event TX_OVERRUN.
    TxOverrun(DeviceEvent),
    /// A device event code this daemon does not know.
    UnknownEvent(DeviceEvent),
    /// Samples dropped by a full sampler queue (no gap announced them).
    OverflowGap {
        /// The index of the first sample after the hole.
        before: u64,
        /// Samples dropped.
        count: u64,
    },
    /// A window closed before its K pulses: not identified. `closed_by` says what closed it:
    /// `segment` (a device reset or a hang-up: a new boot, announced or seen as the sample
    /// index going back; the plan, re-armed, fires the operating point's pulses again),
    /// `level_end` (the operating point ended with pulses left over), `end` (the stream
    /// ended).
    WindowInterrupted {
        /// The window's operating point.
        operating_point: f64,
        /// Pulses it held (fewer than `identify.pulses_per_model`).
        pulses: usize,
        /// Device time of the window's last sample, s (the old segment's clock).
        t_s: f64,
        /// What closed it.
        closed_by: Reason,
    },
    /// The window filled before K pulses.
    WindowFull {
        /// The sample that found it full.
        sample_index: u64,
    },
    /// A complete window gave no model.
    IdentificationFailed {
        /// Why (published as its text).
        #[serde(rename = "message", serialize_with = "display")]
        error: &'a IdentifyError,
        /// The window's operating point.
        operating_point: f64,
        /// Device time of the window's last sample, s.
        t_s: f64,
    },
    /// An output failed and was disabled; the run goes on and exits 7 at the end.
    OutputFailed {
        /// Which output: `stdout` or `record`.
        sink: &'a str,
        /// The recording's file (`record` only).
        #[serde(skip_serializing_if = "Option::is_none")]
        path: Option<&'a str>,
        /// The OS error, as text.
        message: &'a str,
    },
    /// A model that fails the quality checks ([`super::quality`]): published for inspection,
    /// never as a model nor in the schedule.
    ModelUnreliable {
        /// The model, its fields flattened into the line.
        #[serde(flatten)]
        model: &'a WindowModel,
        /// Which checks it fails.
        reasons: &'a [Flaw],
    },
}

impl Warning<'_> {
    /// The fixed explanation published with this kind, if it has one.
    pub fn message(&self) -> Option<&'static str> {
        Some(match self {
            Warning::DeviceReset { .. } => {
                "the device reset and is disarmed; the plan is over and will not re-arm"
            }
            Warning::DeviceResetRearm { .. } => {
                "the device reset and is disarmed; the plan hand-shakes, re-arms and resumes at \
                 the interrupted operating point (experiment.rearm_on_reset)"
            }
            Warning::LinkStalled { .. } => {
                "nothing from the device (no data, no ACK) for device.stall_timeout_ms: STOP \
                 sent, the port closed and reopened; the plan re-arms only with \
                 experiment.rearm_on_reset"
            }
            Warning::RearmLimitReached { .. } => {
                "the device reset or stalled again after experiment.max_rearms re-arms; the plan \
                 is over and will not re-arm"
            }
            Warning::PlanHaltedWatchdog => {
                "the device watchdog stopped the motor; the plan is over"
            }
            Warning::CommandRefused { .. } => "the device refused a command; the plan is over",
            Warning::LinkFailed { .. } => "a command went unanswered after its re-sends",
            Warning::ThrottleMismatch { .. } => {
                "the throttle the device reports is not the one commanded: STOP sent, the plan \
                 is over"
            }
            Warning::CommandsNotExecuted { .. } => {
                "the device acknowledged commands its samples never show: STOP sent, the plan \
                 is over"
            }
            Warning::HelloRateMismatch { .. } => {
                "the sample rate measured from the device clock is not the HELLO's (pulse \
                 widths are sized from it): a plan is stopped"
            }
            Warning::ClockJump { .. } => {
                "the device clock jumped while the sample index ran on: the window there is \
                 closed, no model spans the jump"
            }
            Warning::WindowInterrupted {
                closed_by: Reason::ClockJump,
                ..
            } => "a device clock jump closed the window before its K pulses: not identified",
            Warning::OverflowGap { .. } => {
                "samples dropped by a full sampler queue; masked as missing"
            }
            Warning::WindowInterrupted {
                closed_by: Reason::Segment,
                ..
            } => {
                "a device reset or hang-up interrupted the window before its K pulses: not \
                 identified"
            }
            Warning::WindowInterrupted {
                closed_by: Reason::LevelEnd,
                ..
            } => {
                "the operating point ended with pulses left over after its last model (the \
                 pulses seen at the level are not a multiple of K): not identified"
            }
            Warning::WindowInterrupted { .. } => {
                "the window closed before its K pulses (closed_by): not identified"
            }
            Warning::WindowFull { .. } => {
                "window filled before K pulses; its samples were discarded"
            }
            Warning::ModelUnreliable { .. } => HINT,
            _ => return None,
        })
    }
}

/// One published line.
#[derive(Debug, Clone)]
pub enum Line<'a> {
    /// `"model"`: a model that passed the quality checks.
    Model(&'a WindowModel),
    /// `"event"`.
    Event(Event),
    /// `"warning"`.
    Warning(Warning<'a>),
    /// `"schedule"`: the gain schedule, ordered by operating point.
    Schedule(&'a [ScheduleRow]),
    /// `"stats"`: the run's counters, last.
    Stats(&'a StatsLine<'a>),
    /// `"samples"` (the web page's only, [`super::live`]).
    Samples(&'a SamplesLine),
    /// `"response"` (the web page's only).
    Response(&'a ResponseLine),
    /// `"stabilization"` (the web page's only).
    Stabilization(&'a StabilizationLine),
    /// `"live_stats"`: the counters so far (the web page's only).
    LiveStats(&'a StatsLine<'a>),
    /// `"step"`, `"static_map"`, `"frequency_response"`, `"model"`: an experiment kind's
    /// results.
    Kind(&'a propid_kinds::Published),
}

impl Line<'_> {
    /// The line for a link fact.
    pub fn notice(n: Notice) -> Line<'static> {
        match n {
            Notice::Disconnected => Line::Warning(Warning::Disconnected),
            Notice::Reconnected { device_node } => Line::Event(Event::Reconnected { device_node }),
            Notice::Stopped => Line::Event(Event::ShutdownStopAcknowledged),
            Notice::StopUnacknowledged => Line::Warning(Warning::ShutdownStopUnacknowledged),
            Notice::CsvLink => Line::Event(Event::CsvLink),
            Notice::PassiveBench => Line::Warning(Warning::PassiveBench),
            Notice::NoData => Line::Warning(Warning::NoData),
            Notice::LinkStalled {
                silent_ms,
                stop_acknowledged,
            } => Line::Warning(Warning::LinkStalled {
                silent_ms,
                stop_acknowledged,
            }),
            Notice::LinkResumed { silent_ms } => Line::Event(Event::LinkResumed { silent_ms }),
        }
    }

    /// The line for an experiment-plan fact (`None`: not published; pulses are counted).
    pub fn plan(n: PlanNote) -> Option<Line<'static>> {
        Some(match n {
            PlanNote::PulseFired => return None,
            PlanNote::Connected { boot_id } => Line::Event(Event::Connected { boot_id }),
            PlanNote::Armed => Line::Event(Event::ArmAcknowledged),
            PlanNote::LevelReached { index, level } => Line::Event(Event::LevelReached {
                index,
                operating_point: level,
            }),
            PlanNote::LevelDone { index, level } => Line::Event(Event::LevelDone {
                index,
                operating_point: level,
            }),
            PlanNote::Finished => Line::Event(Event::PlanFinished),
            PlanNote::Stopped => Line::Event(Event::StopAcknowledged),
            PlanNote::DeviceReset {
                new_boot_id,
                rearm: false,
            } => Line::Warning(Warning::DeviceReset {
                boot_id: new_boot_id,
            }),
            PlanNote::DeviceReset {
                new_boot_id,
                rearm: true,
            } => Line::Warning(Warning::DeviceResetRearm {
                boot_id: new_boot_id,
                rearm: true,
            }),
            PlanNote::WatchdogTripped => Line::Warning(Warning::PlanHaltedWatchdog),
            PlanNote::Refused { command } => Line::Warning(Warning::CommandRefused { command }),
            PlanNote::LinkFailed { command } => Line::Warning(Warning::LinkFailed { command }),
            PlanNote::RearmLimit { rearms } => Line::Warning(Warning::RearmLimitReached { rearms }),
            PlanNote::ThrottleMismatch {
                commanded_min,
                commanded_max,
                applied,
                for_ms,
            } => Line::Warning(Warning::ThrottleMismatch {
                commanded_min,
                commanded_max,
                applied,
                for_ms,
            }),
            PlanNote::CommandsNotExecuted { command, level } => {
                Line::Warning(Warning::CommandsNotExecuted { command, level })
            }
            // published from the tracker's item (replays too): `hello_rate_mismatch`
            PlanNote::RateMismatch => return None,
            PlanNote::LimitTripped {
                which,
                value,
                limit,
            } => Line::Event(Event::LimitTripped {
                which,
                value,
                limit,
            }),
            PlanNote::LimitUnchecked { which, why } => {
                Line::Warning(Warning::LimitUnchecked { which, why })
            }
        })
    }

    /// The line for a device EVENT (`None` for the impulse edges, counted through the samples'
    /// flags).
    pub fn device_event(e: &EventItem) -> Option<Line<'static>> {
        let d = DeviceEvent {
            code: e.code,
            arg: e.arg,
            t_s: e.t_us as f64 * 1e-6,
            sample_index: e.sample_index,
        };
        Some(match e.code {
            1 | 2 => return None,
            3 => Line::Warning(Warning::WatchdogTrip(d)),
            4 => Line::Warning(Warning::LimitCutoff(d)),
            5 => Line::Event(Event::Armed(d)),
            6 => Line::Event(Event::Disarmed(d)),
            7 => Line::Warning(Warning::TxOverrun(d)),
            8 => Line::Event(Event::ResetCause(d)),
            9 => Line::Event(Event::TareDone(d)),
            _ => Line::Warning(Warning::UnknownEvent(d)),
        })
    }

    /// The line's bytes (without the newline): the one serialisation of every published line,
    /// keys sorted at every level (see the module documentation).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string(&serde_json::to_value(self)?)
    }
}

impl Serialize for Line<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        /// The wire shape: the `"type"` tag, and a warning's fixed message beside its fields.
        #[derive(Serialize)]
        #[serde(tag = "type", rename_all = "snake_case")]
        enum Shape<'l> {
            Model(&'l WindowModel),
            Event(&'l Event),
            Warning {
                #[serde(flatten)]
                warning: &'l Warning<'l>,
                #[serde(skip_serializing_if = "Option::is_none")]
                message: Option<&'static str>,
            },
            Schedule {
                models: &'l [ScheduleRow],
            },
            Stats(&'l StatsLine<'l>),
            Samples(&'l SamplesLine),
            Response(&'l ResponseLine),
            Stabilization(&'l StabilizationLine),
            LiveStats(&'l StatsLine<'l>),
            Step(&'l propid_kinds::StepLine),
            StaticMap(&'l propid_kinds::StaticMapLine),
            FrequencyResponse(&'l propid_kinds::FrequencyResponseLine),
            #[serde(rename = "model")]
            KindModel(&'l propid_kinds::ModelLine),
        }
        match self {
            Line::Model(m) => Shape::Model(m),
            Line::Event(e) => Shape::Event(e),
            Line::Warning(w) => Shape::Warning {
                warning: w,
                message: w.message(),
            },
            Line::Schedule(models) => Shape::Schedule { models },
            Line::Stats(st) => Shape::Stats(st),
            Line::Samples(l) => Shape::Samples(l),
            Line::Response(l) => Shape::Response(l),
            Line::Stabilization(l) => Shape::Stabilization(l),
            Line::LiveStats(st) => Shape::LiveStats(st),
            Line::Kind(propid_kinds::Published::Step(l)) => Shape::Step(l),
            Line::Kind(propid_kinds::Published::StaticMap(l)) => Shape::StaticMap(l),
            Line::Kind(propid_kinds::Published::FrequencyResponse(l)) => {
                Shape::FrequencyResponse(l)
            }
            Line::Kind(propid_kinds::Published::Model(l)) => Shape::KindModel(l),
        }
        .serialize(s)
    }
}

/// Serialises a value as its `Display` text.
fn display<T: Display, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::report;
    use serde_json::json;

    #[test]
    fn every_notice_has_its_line() {
        let kinds: Vec<String> = [
            Notice::Disconnected,
            Notice::Reconnected { device_node: None },
            Notice::Reconnected {
                device_node: Some("/dev/ttyACM1".into()),
            },
            Notice::Stopped,
            Notice::StopUnacknowledged,
            Notice::CsvLink,
            Notice::PassiveBench,
            Notice::NoData,
            Notice::LinkStalled {
                silent_ms: 1200,
                stop_acknowledged: false,
            },
            Notice::LinkResumed { silent_ms: 2500 },
        ]
        .into_iter()
        .map(|n| Line::notice(n).to_json().unwrap())
        .collect();
        assert_eq!(
            kinds,
            [
                r#"{"kind":"disconnected","type":"warning"}"#,
                r#"{"kind":"reconnected","type":"event"}"#,
                r#"{"device_node":"/dev/ttyACM1","kind":"reconnected","type":"event"}"#,
                r#"{"kind":"shutdown_stop_acknowledged","type":"event"}"#,
                r#"{"kind":"shutdown_stop_unacknowledged","type":"warning"}"#,
                r#"{"kind":"csv_link","type":"event"}"#,
                r#"{"kind":"passive_bench","type":"warning"}"#,
                r#"{"kind":"no_data","type":"warning"}"#,
                concat!(
                    r#"{"kind":"link_stalled","message":"nothing from the device (no data, no ACK) for "#,
                    r#"device.stall_timeout_ms: STOP sent, the port closed and reopened; the plan "#,
                    r#"re-arms only with experiment.rearm_on_reset","silent_ms":1200,"#,
                    r#""stop_acknowledged":false,"type":"warning"}"#
                ),
                r#"{"kind":"link_resumed","silent_ms":2500,"type":"event"}"#,
            ]
        );
    }

    #[test]
    fn a_failed_identification_publishes_the_error_text() {
        let error = IdentifyError::NoModel;
        let line = Line::Warning(Warning::IdentificationFailed {
            error: &error,
            operating_point: 0.5,
            t_s: 2.0,
        });
        assert_eq!(
            line.to_json().unwrap(),
            r#"{"kind":"identification_failed","message":"no model identified","operating_point":0.5,"t_s":2.0,"type":"warning"}"#
        );
    }

    #[test]
    fn non_finite_model_numbers_are_null_and_keys_stay_sorted() {
        let model = WindowModel {
            window: WindowFacts {
                t_s: 1.5,
                operating_point: 0.45,
                level: 1,
                first_sample: 10,
                samples: 20,
                reason: Reason::Full,
                last_received: None,
            },
            path: PathTaken::Pulse,
            outliers: 0,
            report: report(json!({"fn_hz": null, "zeta": null, "dc_gain": null})),
        };
        let text = Line::Model(&model).to_json().unwrap();
        assert!(text.contains(r#""fn_hz":null"#), "{text}");
        assert!(!text.contains("outliers"), "absent when 0: {text}");
        let with = WindowModel {
            outliers: 2,
            ..model.clone()
        };
        let with = Line::Model(&with).to_json().unwrap();
        assert!(with.contains(r#""outliers":2,"#), "{with}");
        assert!(text.contains(r#""reason":"window_full""#), "{text}");
        assert!(!text.contains("last_received"), "{text}");
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
        let mut sorted = keys.clone();
        sorted.sort();
        assert_eq!(keys, sorted);
        assert!(text.starts_with(r#"{"a":"#) && text.ends_with(r#""zeta":null}"#));
        let row = ScheduleRow::new(0.45, &model.report);
        assert_eq!(
            Line::Schedule(&[row]).to_json().unwrap(),
            r#"{"models":[{"dc_gain":null,"fn_hz":null,"operating_point":0.45,"order":2,"pulses":1,"time_constants_s":[],"uncertainty":{"dc_gain":0.5,"fn_hz":0.25,"zeta":null},"zeta":null}],"type":"schedule"}"#
        );
    }
}
