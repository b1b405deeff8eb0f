//! The experiment plan as a state machine. See the [module documentation](super).

use std::collections::VecDeque;

use super::config::{ExperimentConfig, ExperimentConfigError, Kind};
use super::program::{program, Setpoint};
use crate::protocol::message::throttle_level;
use crate::protocol::{Ack, AckResult, Arm, EventCode, Frame, Impulse, Message, SetThrottle};

/// Something the caller must know about.
#[derive(Debug, Clone, PartialEq)]
pub enum Notice {
    /// HELLO and ACK received: the device is there.
    Connected {
        /// Its boot id.
        boot_id: u32,
        /// Its nominal sample rate, Hz.
        sample_rate_hz: u16,
    },
    /// ARM acknowledged.
    Armed,
    /// The ramp to operating point `index` is done and the settling time has passed; pulses
    /// follow.
    LevelReached {
        /// Index in the configured list.
        index: usize,
        /// Throttle fraction.
        level: f64,
    },
    /// A pulse was acknowledged (it starts at the device time `t_us` of the ACK), or, when its
    /// ACK was lost, the device's EVENT IMPULSE_START said it fired (`t_us` of the event).
    PulseFired {
        /// Operating point index.
        index: usize,
        /// Pulse number at this operating point, from 0.
        pulse: u32,
        /// Signed amplitude, throttle fraction.
        delta: f64,
        /// Device time the pulse starts, µs (wire clock).
        t_us: u32,
    },
    /// K pulses are done at this operating point and the last response has decayed: identify.
    LevelDone {
        /// Operating point index.
        index: usize,
        /// Throttle fraction.
        level: f64,
        /// Pulses fired at this level.
        pulses: u32,
    },
    /// All operating points done, ramped down, disarmed.
    Finished,
    /// A STOP asked for by [`Experiment::abort`] was acknowledged.
    Stopped,
    /// The device reset (HELLO with a new boot id). It boots disarmed; the plan is over, or,
    /// with `rearm_on_reset`, hand-shakes and re-arms at the interrupted operating point.
    DeviceReset {
        /// Boot id at the handshake.
        old_boot_id: u32,
        /// The new one.
        new_boot_id: u32,
        /// The plan re-arms (`rearm_on_reset`); else it is over.
        rearm: bool,
    },
    /// The device reset or the link stalled once more after `max_rearms` re-arms
    /// (`rearm_on_reset`): the plan is over instead of re-arming again.
    RearmLimit {
        /// Re-arms done (= `max_rearms`).
        rearms: u32,
    },
    /// The device's watchdog stopped the motor. The plan is over.
    WatchdogTripped,
    /// The device refused a command the plan cannot do without. The plan is over (a STOP is
    /// sent).
    Refused {
        /// Protocol name of the command.
        command: &'static str,
        /// The device's answer.
        result: AckResult,
    },
    /// The throttle the device reports applying stayed outside what the plan commanded for
    /// longer than [`super::THROTTLE_MISMATCH_MS`] (a runaway ESC, a stand that lies). The plan
    /// is over (a STOP is sent).
    ThrottleMismatch {
        /// Lowest throttle the plan commanded at that moment (fraction).
        commanded_min: f64,
        /// Highest throttle the plan commanded at that moment (fraction).
        commanded_max: f64,
        /// The throttle the device reported (fraction), at the last sample.
        applied: f64,
        /// How long it has been outside, ms (host clock).
        for_ms: u64,
    },
    /// The device acknowledged commands its samples never show: a level that never appears,
    /// or [`super::PULSES_UNSEEN_LIMIT`] pulses in a row with no sign of them. The plan is
    /// over (a STOP is sent).
    CommandsNotExecuted {
        /// Protocol name of the command (`SET_THROTTLE` or `IMPULSE`).
        command: &'static str,
        /// The level it commanded (fraction; for a pulse `level + delta`).
        level: f64,
    },
    /// The device's measured sample rate disagrees with its HELLO's (see
    /// [`Experiment::sample_rate_disagrees`]): pulse widths are sized from the HELLO's. The
    /// plan is over (a STOP is sent).
    RateMismatch {
        /// The HELLO's rate, Hz.
        hello_hz: u16,
        /// The rate measured from the samples, Hz.
        measured_hz: f64,
    },
    /// A sample breached a safety limit (`[limits]`, [`super::Limits::breach`]). The plan is
    /// over for good (a STOP is sent; `rearm_on_reset` does not re-arm it).
    LimitTripped {
        /// The limit's key, e.g. `max_current_a`.
        which: &'static str,
        /// What the sample showed (SI units; throttle as a fraction).
        value: f64,
        /// The limit.
        limit: f64,
    },
    /// A limit on a quantity the stand's first samples never carried: it cannot be held (said
    /// once, after [`super::JUDGE_SAMPLES`] samples).
    LimitUnchecked {
        /// The limit's key.
        which: &'static str,
        /// Why.
        why: &'static str,
    },
    /// A command went unanswered after all re-sends. The plan is over.
    LinkFailed {
        /// Protocol name of the command.
        command: &'static str,
        /// Its seq.
        seq: u16,
    },
}

/// What the plan wants done: a frame to send, or news.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// Encode `msg` with `seq` (e.g. `protocol::encode_frame`) and send it.
    Send {
        /// Link sequence number (the command id; a re-send keeps it).
        seq: u16,
        /// The command.
        msg: Message,
    },
    /// Something happened.
    Notice(Notice),
}

/// Where the plan is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Not started.
    Idle,
    /// HELLO_REQ sent, waiting for HELLO and ACK.
    Handshake,
    /// ARM sent.
    Arming,
    /// SET_THROTTLE to an operating point sent or its ramp running.
    Ramping,
    /// Waiting for the operating point to settle.
    Settling,
    /// Firing pulses and waiting between them.
    Pulsing,
    /// Sending the set-point program of a `staircase`, `ramp` or `chirp` (`program.rs`).
    Program,
    /// Ramping down at the end.
    RampDown,
    /// DISARM sent.
    Disarming,
    /// Finished normally.
    Done,
    /// STOP sent by [`Experiment::abort`].
    Stopping,
    /// Over because of a reset, a watchdog trip, a refusal, a failed link or an abort.
    Halted,
}

impl Phase {
    /// From ARM sent to DISARM sent: the device may be armed (a reconnect must ask whether it
    /// is the same boot; a stall must STOP it).
    pub fn mid_plan(self) -> bool {
        matches!(
            self,
            Phase::Arming
                | Phase::Ramping
                | Phase::Settling
                | Phase::Pulsing
                | Phase::Program
                | Phase::RampDown
                | Phase::Disarming
        )
    }
}

#[derive(Debug, Clone, Copy)]
pub(super) struct InFlight {
    pub(super) seq: u16,
    pub(super) msg: Message,
    pub(super) sent_us: u64,
    /// When it was first sent (re-sends keep it).
    pub(super) first_sent_us: u64,
    pub(super) resends: u32,
}

/// Wait before re-trying an IMPULSE the device answered BUSY, µs.
const BUSY_RETRY_US: u64 = 20_000;

/// The host-side experiment plan: a pure state machine (see the [module docs](super)).
#[derive(Debug, Clone)]
pub struct Experiment {
    pub(super) cfg: ExperimentConfig,
    pub(super) phase: Phase,
    seq: u16,
    pub(super) out: VecDeque<Output>,
    pub(super) in_flight: Option<InFlight>,
    pub(super) next_heartbeat_us: Option<u64>,
    pub(super) boot_id: Option<u32>,
    pub(super) rate_hz: Option<u16>,
    pub(super) handshake_acked: bool,
    pub(super) level_idx: usize,
    pub(super) pulses: u32,
    pub(super) wait_until_us: Option<u64>,
    /// After a reconnect: the HELLO_REQ that asks whether the device is the same boot is in
    /// flight; the command it displaced waits here (waits are paused meanwhile).
    pub(super) verifying: Option<Option<InFlight>>,
    /// Over after a stall, to re-arm at the next reconnect (`rearm_on_reset`).
    pub(super) rearm_pending: bool,
    /// The operating point the plan goes to after ARM (0, or the interrupted one on a re-arm).
    pub(super) resume_level: usize,
    /// Re-arms so far.
    pub(super) rearms: u32,
    /// When the last frame (of any kind) arrived.
    pub(super) last_frame_us: Option<u64>,
    /// The caller runs a stall watchdog ([`Experiment::set_stall_watchdog`]).
    stall_watchdog: bool,
    /// The throttle the plan commanded before the current operating point (the ramp's start).
    pub(super) from_level: f64,
    /// BUSY answers to the IMPULSE being fired, and when it was first sent.
    pub(super) busy: Option<(u32, u64)>,
    /// The device's samples checked against the commands (`verify.rs`).
    pub(super) check: super::stand_check::StandCheck,
    /// The safety limits (`limits.rs`).
    pub(super) limits: super::limits::LimitGuard,
    /// The set-point program (kinds other than pulses) and its end, ms from its start.
    pub(super) program: Vec<Setpoint>,
    program_end_ms: u64,
    /// Host time the program started (a resumed one: as if it had run from there).
    program_t0_us: u64,
}

impl Experiment {
    /// A plan with `cfg` (validated here), starting with sequence number `first_seq`.
    pub fn new(cfg: ExperimentConfig, first_seq: u16) -> Result<Self, ExperimentConfigError> {
        cfg.validate()?;
        let (program, program_end_ms) = program(&cfg);
        Ok(Experiment {
            program,
            program_end_ms,
            program_t0_us: 0,
            cfg,
            phase: Phase::Idle,
            seq: first_seq,
            out: VecDeque::new(),
            in_flight: None,
            next_heartbeat_us: None,
            boot_id: None,
            rate_hz: None,
            handshake_acked: false,
            level_idx: 0,
            pulses: 0,
            wait_until_us: None,
            verifying: None,
            rearm_pending: false,
            resume_level: 0,
            rearms: 0,
            last_frame_us: None,
            stall_watchdog: false,
            from_level: 0.0,
            busy: None,
            check: Default::default(),
            limits: Default::default(),
        })
    }

    /// The caller runs a stall watchdog on the link (the daemon's `stall_timeout_ms`): a
    /// command still unanswered after its re-sends while *nothing at all* has been heard since
    /// its last re-send (after the device had spoken) is then not a link failure but a stall,
    /// left to the watchdog ([`Self::link_stalled`]): no more re-sends, the command stays in
    /// flight in case the device wakes. A device that goes on sending but does not acknowledge
    /// is a link failure ([`Notice::LinkFailed`]) either way. Off by default.
    pub fn set_stall_watchdog(&mut self, on: bool) {
        self.stall_watchdog = on;
    }

    /// The configuration.
    pub fn config(&self) -> &ExperimentConfig {
        &self.cfg
    }

    /// Where the plan is.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// True once the plan is over (finished, stopped or halted).
    pub fn is_over(&self) -> bool {
        matches!(self.phase, Phase::Done | Phase::Halted)
    }

    /// Boot id seen at the handshake.
    pub fn boot_id(&self) -> Option<u32> {
        self.boot_id
    }

    /// The operating point now being worked on (index, throttle fraction).
    pub fn current_level(&self) -> Option<(usize, f64)> {
        match self.phase {
            Phase::Ramping | Phase::Settling | Phase::Pulsing => {
                Some((self.level_idx, self.cfg.levels[self.level_idx]))
            }
            Phase::Program => {
                let i = self.level_idx.min(self.program.len()).checked_sub(1)?;
                Some((i, self.program[i].level))
            }
            _ => None,
        }
    }

    /// The next thing to do, if any. Call until `None` after every `start`, `poll`,
    /// `on_frame` and `abort`.
    pub fn next_output(&mut self) -> Option<Output> {
        self.out.pop_front()
    }

    /// Starts the plan at `now_us` (host clock, µs): HELLO_REQ.
    pub fn start(&mut self, now_us: u64) {
        if self.phase == Phase::Idle {
            self.phase = Phase::Handshake;
            self.send(Message::HelloReq, now_us);
        }
    }

    /// Asks the plan to stop the motor now (shutdown): STOP, re-sent until acknowledged or the
    /// link is declared failed. Heartbeats stop.
    pub fn abort(&mut self, now_us: u64) {
        if self.phase == Phase::Stopping {
            return;
        }
        self.phase = Phase::Stopping;
        self.next_heartbeat_us = None;
        self.wait_until_us = None;
        self.send(Message::Stop, now_us);
    }

    /// Timers: heartbeats, re-sends, waits. Call at least every few milliseconds.
    pub fn poll(&mut self, now_us: u64) {
        if let Some(t) = self.next_heartbeat_us.filter(|&t| t <= now_us) {
            let seq = self.next_seq();
            self.out.push_back(Output::Send {
                seq,
                msg: Message::Heartbeat,
            });
            let p = self.cfg.heartbeat_ms as u64 * 1000;
            self.next_heartbeat_us = Some((t + p).max(now_us));
        }
        self.check_retry(now_us);
        if self.verifying.is_some() {
            return; // waits resume once the device is known to be the same boot
        }
        if let Some(t) = self.wait_until_us.filter(|&t| t <= now_us) {
            self.wait_until_us = None;
            self.wait_over(t.max(now_us));
        }
    }

    /// A frame from the device arrived at `now_us`.
    pub fn on_frame(&mut self, frame: &Frame, now_us: u64) {
        self.last_frame_us = Some(now_us);
        match frame.msg {
            Message::Hello(h) => {
                match self.boot_id {
                    Some(old) if old != h.boot_id => {
                        return self.device_reset(old, h.boot_id, now_us);
                    }
                    _ => {}
                }
                if self.phase == Phase::Handshake && self.boot_id.is_none() {
                    self.boot_id = Some(h.boot_id);
                    self.rate_hz = Some(h.sample_rate_hz);
                    if self.handshake_acked {
                        self.connected(now_us);
                    }
                }
            }
            Message::Ack(a) => self.on_ack(a, now_us),
            Message::Sample(s) => {
                self.check_limits(&s, now_us);
                self.on_sample(&s, now_us)
            }
            Message::Event(e) if e.code == EventCode::ImpulseStart => {
                self.check.pulse_shown = true;
                self.on_impulse_start(e.t_us, now_us)
            }
            Message::Event(e) if e.code == EventCode::WatchdogTrip && !self.is_over() => {
                self.halt(Notice::WatchdogTripped);
            }
            _ => {}
        }
    }

    fn on_ack(&mut self, a: Ack, now_us: u64) {
        let Some(f) = self.in_flight.filter(|f| f.seq == a.cmd_seq) else {
            return; // heartbeats, late duplicates
        };
        self.in_flight = None;
        if let Some(displaced) = self.verifying.take() {
            return self.verified(displaced, now_us);
        }
        if a.result == AckResult::Busy && matches!(f.msg, Message::Impulse(_)) {
            // tried again 20 ms later, but not for ever: after `max_retries` more BUSYs or one
            // pulse spacing since it was first sent, a refusal
            let (n, since) = self.busy.get_or_insert((0, f.first_sent_us));
            *n += 1;
            let spacing = self.cfg.pulse_spacing_ms as u64 * 1000;
            if *n > self.cfg.max_retries || now_us >= *since + spacing {
                self.busy = None;
                return self.refused(f.msg.name(), a.result, now_us);
            }
            self.wait_until_us = Some(now_us + BUSY_RETRY_US);
            return;
        }
        if a.result != AckResult::Ok {
            if self.phase == Phase::Stopping {
                return self.halt(Notice::Stopped);
            }
            return self.refused(f.msg.name(), a.result, now_us);
        }
        match self.phase {
            Phase::Handshake => {
                self.handshake_acked = true;
                if self.boot_id.is_some() {
                    self.connected(now_us);
                }
            }
            Phase::Arming if matches!(f.msg, Message::Stop) => {
                // a re-arm: the motor is known to be stopped, now ARM
                self.send(Message::Arm(Arm::new(self.cfg.watchdog_ms)), now_us);
            }
            Phase::Arming => {
                self.notice(Notice::Armed);
                let p = self.cfg.heartbeat_ms as u64 * 1000;
                self.next_heartbeat_us = Some(now_us + p);
                if self.cfg.kind == Kind::Pulses {
                    self.go_to_level(self.resume_level, now_us);
                } else {
                    self.start_program(self.resume_level, now_us);
                }
            }
            Phase::Ramping => {
                self.phase = Phase::Settling;
                let wait = (self.cfg.ramp_ms as u64 + self.cfg.settle_ms as u64) * 1000;
                self.wait_until_us = Some(now_us + wait);
            }
            Phase::Pulsing => self.pulse_fired(a.t_us, now_us),
            Phase::Program => self.setpoint_acked(now_us),
            Phase::RampDown => {
                // Wait for the ramp (and one heartbeat period) before disarming.
                let wait = self.cfg.ramp_ms as u64 * 1000 + self.cfg.heartbeat_ms as u64 * 1000;
                self.wait_until_us = Some(now_us + wait);
            }
            Phase::Disarming => {
                self.phase = Phase::Done;
                self.next_heartbeat_us = None;
                self.notice(Notice::Finished);
            }
            Phase::Stopping => self.halt(Notice::Stopped),
            _ => {}
        }
    }

    /// The device's EVENT IMPULSE_START: while an IMPULSE is in flight (its ACK not yet
    /// received) this is the device saying it executed it. The pulse is counted and the IMPULSE
    /// is not re-sent: a re-send that comes after the device's repeat memory (docs/PROTOCOL.md §4:
    /// the last 8 commands, for one second; heartbeats count) is executed as a new command, a
    /// second pulse the plan never counted — the level then holds one pulse more than
    /// `pulses_per_level` and the host's last window at that level closes with a stray pulse
    /// (the soak's `window_interrupted` at `level_end` with 1 of 4 pulses, with `retry_ms =
    /// 1000`). An ACK that still comes is then a late one, ignored. (The EVENT of a pulse
    /// already acknowledged finds no IMPULSE in flight: the next one is sent only after
    /// `pulse_spacing_ms`.)
    fn on_impulse_start(&mut self, t_us: u32, now_us: u64) {
        let impulse_in_flight = self
            .in_flight
            .is_some_and(|f| matches!(f.msg, Message::Impulse(_)));
        if self.phase != Phase::Pulsing || self.verifying.is_some() || !impulse_in_flight {
            return;
        }
        self.in_flight = None;
        self.pulse_fired(t_us, now_us);
    }

    /// Pulse number `self.pulses` at the current level fired at device time `t_us`: noticed,
    /// counted, the next one after `pulse_spacing_ms`.
    fn pulse_fired(&mut self, t_us: u32, now_us: u64) {
        self.busy = None;
        self.check.pulse_fired();
        let delta = self.cfg.pulse_delta(self.pulses);
        self.notice(Notice::PulseFired {
            index: self.level_idx,
            pulse: self.pulses,
            delta,
            t_us,
        });
        self.pulses += 1;
        self.wait_until_us = Some(now_us + self.cfg.pulse_spacing_ms as u64 * 1000);
    }

    /// A timed wait ended.
    fn wait_over(&mut self, now_us: u64) {
        // a pulse's spacing ended: did the stand show the level and the pulses?
        if self.phase == Phase::Pulsing
            && self.busy.is_none()
            && self.stand_ignored_commands(now_us)
        {
            return;
        }
        match self.phase {
            Phase::Settling => {
                self.phase = Phase::Pulsing;
                let level = self.cfg.levels[self.level_idx];
                self.notice(Notice::LevelReached {
                    index: self.level_idx,
                    level,
                });
                self.fire(now_us);
            }
            Phase::Pulsing if self.pulses < self.cfg.pulses_per_level => self.fire(now_us),
            Phase::Pulsing => {
                self.notice(Notice::LevelDone {
                    index: self.level_idx,
                    level: self.cfg.levels[self.level_idx],
                    pulses: self.pulses,
                });
                if self.level_idx + 1 < self.cfg.levels.len() {
                    self.go_to_level(self.level_idx + 1, now_us);
                } else {
                    self.ramp_down(now_us);
                }
            }
            Phase::Program if self.level_idx < self.program.len() => {
                let s = self.program[self.level_idx];
                let msg = Message::SetThrottle(SetThrottle {
                    level: throttle_level(s.level),
                    ramp_ms: s.ramp_ms,
                });
                self.send(msg, now_us);
            }
            Phase::Program => self.ramp_down(now_us),
            Phase::RampDown => {
                self.phase = Phase::Disarming;
                self.send(Message::Disarm, now_us);
            }
            _ => {}
        }
    }

    /// The program from set-point `from` on (0, or the interrupted one on a re-arm), timed as
    /// if it had started `at_ms` of that set-point ago.
    fn start_program(&mut self, from: usize, now_us: u64) {
        self.check.new_level();
        self.phase = Phase::Program;
        let from = from.min(self.program.len().saturating_sub(1));
        self.level_idx = from;
        self.program_t0_us = now_us.saturating_sub(self.program[from].at_ms * 1000);
        self.wait_until_us = Some(now_us);
        self.poll(now_us);
    }

    /// The ACK of set-point `level_idx`: announced if a hold, then the next one's time (or
    /// the program's end).
    fn setpoint_acked(&mut self, now_us: u64) {
        let s = self.program[self.level_idx];
        if s.announce {
            self.notice(Notice::LevelReached {
                index: self.level_idx,
                level: s.level,
            });
        }
        self.level_idx += 1;
        let at_ms = match self.program.get(self.level_idx) {
            Some(next) => next.at_ms,
            None => self.program_end_ms,
        };
        self.wait_until_us = Some((self.program_t0_us + at_ms * 1000).max(now_us));
    }

    /// The last operating point or set-point is over: SET_THROTTLE 0 with the ramp, then
    /// DISARM.
    fn ramp_down(&mut self, now_us: u64) {
        self.phase = Phase::RampDown;
        let msg = Message::SetThrottle(SetThrottle {
            level: 0,
            ramp_ms: self.cfg.ramp_ms,
        });
        self.send(msg, now_us);
    }

    pub(super) fn connected(&mut self, now_us: u64) {
        self.notice(Notice::Connected {
            boot_id: self.boot_id.unwrap_or(0),
            sample_rate_hz: self.rate_hz.unwrap_or(0),
        });
        self.phase = Phase::Arming;
        if self.rearms > 0 {
            // a device back in the same boot may still be armed and busy (it refuses ARM
            // then): STOP first, ARM on its ACK
            self.send(Message::Stop, now_us);
        } else {
            self.send(Message::Arm(Arm::new(self.cfg.watchdog_ms)), now_us);
        }
    }

    fn go_to_level(&mut self, idx: usize, now_us: u64) {
        self.from_level = match self.phase {
            Phase::Pulsing => self.cfg.levels[self.level_idx],
            _ => 0.0,
        };
        self.check.new_level();
        self.level_idx = idx;
        self.pulses = 0;
        self.phase = Phase::Ramping;
        let msg = Message::SetThrottle(SetThrottle {
            level: throttle_level(self.cfg.levels[idx]),
            ramp_ms: self.cfg.ramp_ms,
        });
        self.send(msg, now_us);
    }

    /// Pulse number `self.pulses` at the current level: the absolute level `u + delta` for
    /// `pulse_width_samples` sample periods (width from the HELLO's rate).
    fn fire(&mut self, now_us: u64) {
        let level = self.cfg.levels[self.level_idx] + self.cfg.pulse_delta(self.pulses);
        let rate = self.rate_hz.filter(|&r| r > 0).unwrap_or(1000) as u64;
        let width_us = (self.cfg.pulse_width_samples as u64 * 1_000_000 / rate).max(1);
        let msg = Message::Impulse(Impulse {
            level: throttle_level(level),
            width_us: width_us.min(u32::MAX as u64) as u32,
        });
        self.send(msg, now_us);
    }

    fn refused(&mut self, command: &'static str, result: AckResult, now_us: u64) {
        self.notice(Notice::Refused { command, result });
        let armed_phase = !matches!(self.phase, Phase::Idle | Phase::Handshake);
        self.phase = Phase::Halted;
        self.next_heartbeat_us = None;
        self.wait_until_us = None;
        if armed_phase {
            self.send(Message::Stop, now_us);
        }
    }

    pub(super) fn halt(&mut self, n: Notice) {
        self.busy = None;
        self.phase = Phase::Halted;
        self.verifying = None;
        self.rearm_pending = false;
        self.in_flight = None;
        self.next_heartbeat_us = None;
        self.wait_until_us = None;
        self.notice(n);
    }

    fn check_retry(&mut self, now_us: u64) {
        let Some(mut f) = self.in_flight else { return };
        if now_us < f.sent_us + self.cfg.retry_ms as u64 * 1000 {
            return;
        }
        if f.resends >= self.cfg.max_retries {
            // Silent since the last re-send: a frame already on its way when the command was
            // first sent (the device froze just then; a loaded host reads it late) does not
            // make a frozen device a deaf one.
            let silent = self.last_frame_us.is_some_and(|t| t < f.sent_us);
            if self.stall_watchdog && silent {
                return; // a stall: the caller's watchdog acts
            }
            let n = Notice::LinkFailed {
                command: f.msg.name(),
                seq: f.seq,
            };
            return self.halt(n);
        }
        f.resends += 1;
        f.sent_us = now_us;
        self.in_flight = Some(f);
        self.out.push_back(Output::Send {
            seq: f.seq,
            msg: f.msg,
        });
    }

    /// Sends a command that must be acknowledged (one at a time).
    pub(super) fn send(&mut self, msg: Message, now_us: u64) {
        let seq = self.next_seq();
        self.in_flight = Some(InFlight {
            seq,
            msg,
            sent_us: now_us,
            first_sent_us: now_us,
            resends: 0,
        });
        self.out.push_back(Output::Send { seq, msg });
    }

    pub(super) fn next_seq(&mut self) -> u16 {
        let s = self.seq;
        self.seq = self.seq.wrapping_add(1);
        s
    }

    pub(super) fn notice(&mut self, n: Notice) {
        self.out.push_back(Output::Notice(n));
    }
}
