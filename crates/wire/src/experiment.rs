//! The host-side experiment plan (issue 3, item 4): a pure state machine, no I/O and no clock of
//! its own. It is handed the host's `now_us` and the frames the device sent; it says which
//! commands to send ([`Output::Send`], encode them with
//! [`encode_frame`](crate::protocol::encode_frame)) and tells the caller what happened
//! ([`Output::Notice`]).
//!
//! The plan (docs/PROTOCOL.md §4):
//! 1. handshake: HELLO_REQ, then wait for HELLO (boot id, sample rate) and its ACK;
//! 2. ARM with the configured watchdog; from its ACK on, HEARTBEAT every `heartbeat_ms`
//!    (fire-and-forget: their ACKs are not tracked, the next one follows anyway);
//! 3. for each operating point: SET_THROTTLE with `ramp_ms`, wait `ramp_ms + settle_ms`
//!    ([`Notice::LevelReached`]), then `pulses_per_level` IMPULSEs to `level ± amplitude` for
//!    `pulse_width_samples` periods, `pulse_spacing_ms` apart ([`Notice::PulseFired`]); one
//!    spacing after the last, [`Notice::LevelDone`] — the moment to identify;
//! 4. SET_THROTTLE 0 with the ramp, wait, DISARM ([`Notice::Finished`]).
//!
//! That is `kind = "pulses"`; the other kinds (`staircase`, `ramp`, `chirp`) replace step 3 by
//! a timed set-point program ([`program`]): each SET_THROTTLE at its time from the ARM's ACK
//! (a hold announced by [`Notice::LevelReached`] at its ACK), then step 4.
//!
//! Reliability: one acknowledged command is in flight at a time; without its ACK after
//! `retry_ms` it is re-sent with the **same seq** (the device answers a repeat as a DUPLICATE and
//! does not execute it twice — but only for one second and its last 8 commands, heartbeats
//! included: a later re-send is a new command), at most `max_retries` times, then
//! [`Notice::LinkFailed`]. An IMPULSE whose ACK is lost is not re-sent once the device's EVENT
//! IMPULSE_START says it fired (the pulse is counted then): with `retry_ms` near a second a
//! re-send would fire it a second time, one pulse more at the level than the plan counted. An
//! IMPULSE answered BUSY is tried again 20 ms later with a new seq, at most `max_retries` times
//! and for one `pulse_spacing_ms`, then it is a refusal; any other refusal ends the plan with
//! [`Notice::Refused`] and a STOP. The device's samples are held against the commands
//! (`verify.rs`): a throttle outside what was commanded, levels or pulses acknowledged and
//! never seen, a sample rate other than the HELLO's end the plan with a STOP too, and so does a
//! sample over a safety limit (`limits.rs`, [`Limits`]: never re-armed). A HELLO with a new
//! boot id means the device reset:
//! [`Notice::DeviceReset`], and the plan is over unless `rearm_on_reset` says to hand-shake, ARM
//! and resume at the interrupted operating point (`recover.rs`: also what a reconnect and a
//! stall of the link do). A watchdog trip ends it too. [`Experiment::abort`] sends STOP (re-sent until acknowledged) for shutdown.
//!
//! ```
//! use propid_wire::experiment::{Experiment, ExperimentConfig, Output};
//! let mut plan = Experiment::new(ExperimentConfig::default(), 0).unwrap();
//! plan.start(0);
//! while let Some(out) = plan.next_output() {
//!     if let Output::Send { seq, msg } = out {
//!         assert_eq!((seq, msg.name()), (0, "HELLO_REQ"));
//!     }
//! }
//! ```

mod config;
mod limits;
mod plan;
pub mod program;
mod recover;
mod stand_check;
mod verify;

pub use config::{Commanded, ExperimentConfig, ExperimentConfigError, Kind};
pub use limits::{LimitGuard, LimitTrip, Limits, LimitsError, JUDGE_SAMPLES};
pub use plan::{Experiment, Notice, Output, Phase};
pub use stand_check::{
    MIN_SAMPLES_TO_JUDGE, PULSES_UNSEEN_LIMIT, THROTTLE_MISMATCH_MS, THROTTLE_TOLERANCE,
};
