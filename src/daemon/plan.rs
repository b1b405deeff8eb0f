//! The experiment plan as the sampler drives it: the pure [`Experiment`] state machine
//! (`propid_wire::experiment`) behind the sampler's [`Plan`] trait.
//!
//! The sampler gives it the host clock and every device frame, sends what it asks for, and
//! turns its notices into published lines. After a reconnect the plan asks the device whether
//! it is the same boot before it goes on. After a device reset or a link stall the plan is over
//! unless `[experiment] rearm_on_reset` lets it hand-shake, ARM and resume at the interrupted
//! operating point; after a watchdog trip or a refused command it is over, and so it is when the
//! stand's samples contradict its ACKs (a throttle other than the commanded one, commands never
//! executed, a sample rate other than the HELLO's: `propid_wire::experiment`'s `verify.rs`,
//! a STOP sent; the rate measured by the tracker's assembler), and when a sample breaches a
//! `[limits]` safety limit (`limits.rs` there: checked here, on the sampler's thread, as each
//! SAMPLE arrives; never re-armed). A plan over on a
//! fault ends the run with exit 8 (the sampler reads the link 500 ms more first). A failed link
//! (a command unanswered after its re-sends) ends the run (exit 6).

use propid_wire::experiment::{Experiment, ExperimentConfig, Notice, Output};
use propid_wire::protocol::message::{Frame, Message};

use super::config::{Config, ConfigError};
use super::item::PlanNote;
use super::sampler::{Plan, PlanStatus};
use super::DaemonError;

/// The experiment plan with the bookkeeping the sampler needs.
pub struct ExperimentPlan {
    exp: Experiment,
    started: bool,
    link_failed: bool,
}

/// Builds the plan from the config's `[experiment]` table (its keys are the plan's own); with
/// `[device] stall_timeout_ms` set, a command unanswered on a silent link is left to the stall
/// watchdog ([`Experiment::set_stall_watchdog`]).
pub fn from_config(cfg: &Config) -> Result<Box<dyn Plan>, DaemonError> {
    let ecfg: ExperimentConfig = cfg.experiment.clone().try_into().map_err(|source| {
        DaemonError::Config(ConfigError::Parse {
            origin: "[experiment]".into(),
            source,
        })
    })?;
    from_experiment(ecfg, cfg)
}

/// Builds the plan from an experiment configuration (validated here) for a run of the daemon
/// with `cfg` (`propid demo`, whose stand brings its own plan): as [`from_config`], the stall
/// watchdog of `cfg` decides what an unanswered command on a silent link is.
pub fn from_experiment(ecfg: ExperimentConfig, cfg: &Config) -> Result<Box<dyn Plan>, DaemonError> {
    let mut plan = ExperimentPlan::new(ecfg)?;
    plan.exp
        .set_stall_watchdog(cfg.device.stall_timeout.is_some());
    plan.exp
        .set_limits(cfg.limits)
        .map_err(|e| DaemonError::Config(ConfigError::Limits(e)))?;
    Ok(Box::new(plan))
}

impl ExperimentPlan {
    fn new(ecfg: ExperimentConfig) -> Result<ExperimentPlan, DaemonError> {
        let exp = Experiment::new(ecfg, 1)
            .map_err(|e| DaemonError::Config(ConfigError::Experiment(e)))?;
        Ok(ExperimentPlan {
            exp,
            started: false,
            link_failed: false,
        })
    }
}

/// Translates the plan's notice into what the worker publishes.
fn note(n: &Notice) -> PlanNote {
    match *n {
        Notice::Connected { boot_id, .. } => PlanNote::Connected { boot_id },
        Notice::Armed => PlanNote::Armed,
        Notice::LevelReached { index, level } => PlanNote::LevelReached { index, level },
        Notice::PulseFired { .. } => PlanNote::PulseFired,
        Notice::LevelDone { index, level, .. } => PlanNote::LevelDone { index, level },
        Notice::Finished => PlanNote::Finished,
        Notice::Stopped => PlanNote::Stopped,
        Notice::DeviceReset {
            new_boot_id, rearm, ..
        } => PlanNote::DeviceReset { new_boot_id, rearm },
        Notice::WatchdogTripped => PlanNote::WatchdogTripped,
        Notice::Refused { command, .. } => PlanNote::Refused { command },
        Notice::LinkFailed { command, .. } => PlanNote::LinkFailed { command },
        Notice::RearmLimit { rearms } => PlanNote::RearmLimit { rearms },
        Notice::ThrottleMismatch {
            commanded_min,
            commanded_max,
            applied,
            for_ms,
        } => PlanNote::ThrottleMismatch {
            commanded_min,
            commanded_max,
            applied,
            for_ms,
        },
        Notice::CommandsNotExecuted { command, level } => {
            PlanNote::CommandsNotExecuted { command, level }
        }
        Notice::RateMismatch { .. } => PlanNote::RateMismatch,
        Notice::LimitTripped {
            which,
            value,
            limit,
        } => PlanNote::LimitTripped {
            which,
            value,
            limit,
        },
        Notice::LimitUnchecked { which, why } => PlanNote::LimitUnchecked { which, why },
    }
}

impl Plan for ExperimentPlan {
    fn on_connect(&mut self, now_us: u64) {
        // The plan's handshake runs once; after a reconnect a HELLO_REQ asks whether the
        // device is the same boot (the plan goes on) or reset (the plan halts, or re-arms with
        // `rearm_on_reset`).
        if !self.started {
            self.started = true;
            self.exp.start(now_us);
        } else {
            self.exp.reconnected(now_us);
        }
    }

    fn on_stall(&mut self, now_us: u64) {
        self.exp.link_stalled(now_us);
    }

    fn on_frame(&mut self, now_us: u64, frame: &Frame) {
        self.exp.on_frame(frame, now_us);
    }

    fn poll(&mut self, now_us: u64) {
        self.exp.poll(now_us);
    }

    fn on_rate_mismatch(&mut self, now_us: u64, hello_hz: u16, measured_hz: f64) {
        self.exp
            .sample_rate_disagrees(hello_hz, measured_hz, now_us);
    }

    fn abort(&mut self, now_us: u64) {
        if !self.exp.is_over() {
            self.exp.abort(now_us);
        }
    }

    fn next(&mut self, send: &mut dyn FnMut(u16, &Message), notes: &mut dyn FnMut(PlanNote)) {
        while let Some(o) = self.exp.next_output() {
            match o {
                Output::Send { seq, msg } => send(seq, &msg),
                Output::Notice(n) => {
                    if matches!(n, Notice::LinkFailed { .. }) {
                        self.link_failed = true;
                    }
                    notes(note(&n));
                }
            }
        }
    }

    fn status(&self) -> PlanStatus {
        if self.link_failed {
            PlanStatus::LinkFailed
        } else if self.exp.phase() == propid_wire::experiment::Phase::Done {
            PlanStatus::Done
        } else if self.exp.is_over() && !self.exp.rearm_pending() {
            PlanStatus::Halted
        } else {
            PlanStatus::Running
        }
    }
}
