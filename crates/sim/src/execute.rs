//! The firmware's command semantics (docs/PROTOCOL.md §4): every command is answered with one ACK;
//! a repeat of one of the last 8 `(seq, type)` within a second gets the stored result with the
//! DUPLICATE flag and is not executed again (a pulse never fires twice).
//!
//! Result codes, checked in this order: BAD_KEY (ARM only), BAD_STATE (not allowed in this
//! armed/disarmed state), OUT_OF_RANGE, BUSY (a pulse is pending or running, or for IMPULSE also
//! a ramp). No limits are simulated, so LIMIT_ACTIVE never occurs. Any well-formed command,
//! refused or not, duplicate or not, resets the watchdog; a refused frame (UNKNOWN_TYPE,
//! BAD_LENGTH, VERSION) does not.

use super::dynamics::Dynamics;
use super::firmware::{Firmware, Pulse, Ramp};
use propid_wire::protocol::message::{ACK_DUPLICATE, ARM_KEY, THROTTLE_FULL_SCALE};
use propid_wire::protocol::{Ack, AckResult, Arm, EventCode, Impulse, Message, SetThrottle};

/// Longest IMPULSE accepted, µs (one second).
pub const MAX_IMPULSE_US: u32 = 1_000_000;
/// SET_RATE range, Hz.
pub const RATE_RANGE_HZ: (u16, u16) = (10, 20_000);
/// ARM watchdog range, ms.
pub const WATCHDOG_RANGE_MS: (u16, u16) = (100, 5000);

impl<D: Dynamics> Firmware<D> {
    /// Answers one well-formed command received at `self.now_us`.
    pub(crate) fn command(&mut self, seq: u16, msg: Message) {
        let t = msg.msg_type();
        let now = self.now_us;
        self.last_cmd_us = now;
        self.log_command(seq, msg);
        if let Some(stored) = self.dedup.lookup(seq, t, now) {
            self.stats.duplicates += 1;
            self.ack(seq, t, AckResult::from_u8(stored), true, now);
            return;
        }
        let (result, t_eff) = self.execute(&msg);
        if result == AckResult::Ok {
            self.stats.executed += 1;
        }
        self.dedup.remember(seq, t, result.to_u8(), now);
        self.ack(seq, t, result, false, t_eff);
    }

    /// Sends an ACK; `t` is when the command took effect or was refused (device time).
    pub(crate) fn ack(&mut self, seq: u16, cmd_type: u8, result: AckResult, dup: bool, t: u64) {
        self.stats.acks += 1;
        let ack = Ack {
            cmd_seq: seq,
            cmd_type,
            result,
            ack_flags: if dup { ACK_DUPLICATE } else { 0 },
            t_us: self.wire_t_us(t),
        };
        self.emit(Message::Ack(ack));
    }

    /// Executes a command: its result and the device time it took effect.
    fn execute(&mut self, msg: &Message) -> (AckResult, u64) {
        let now = self.now_us;
        let result = match *msg {
            Message::HelloReq => {
                self.emit(Message::Hello(self.hello()));
                AckResult::Ok
            }
            Message::Arm(a) => self.arm(a),
            Message::Disarm | Message::Stop => {
                let (b, idx) = (self.next_boundary_us, self.index.wrapping_add(1));
                self.stop_motor(now, b, idx);
                AckResult::Ok
            }
            Message::SetThrottle(s) => {
                let r = self.set_throttle(s);
                return (r, self.effective(r));
            }
            Message::Impulse(i) => {
                let r = self.impulse(i);
                return (r, self.effective(r));
            }
            Message::Heartbeat => AckResult::Ok,
            Message::SetRate(r) => self.set_rate(r.sample_rate_hz),
            Message::Tare => self.tare(),
            // Device → host types never reach here (the reader refuses them).
            _ => AckResult::UnknownType,
        };
        (result, now)
    }

    /// A throttle change takes effect at the next boundary; a refusal now.
    fn effective(&self, r: AckResult) -> u64 {
        if r == AckResult::Ok {
            self.next_boundary_us
        } else {
            self.now_us
        }
    }

    fn arm(&mut self, a: Arm) -> AckResult {
        if a.key != ARM_KEY {
            return AckResult::BadKey;
        }
        let busy = self.setpoint != 0 || self.ramp.is_some() || self.pulse != Pulse::Idle;
        if self.armed && busy {
            return AckResult::BadState;
        }
        if !(WATCHDOG_RANGE_MS.0..=WATCHDOG_RANGE_MS.1).contains(&a.watchdog_ms) {
            return AckResult::OutOfRange;
        }
        self.watchdog_us = a.watchdog_ms as u64 * 1000;
        self.watchdog_tripped = false;
        if !self.armed {
            self.armed = true;
            self.emit_event(EventCode::Armed, a.watchdog_ms, self.now_us, self.index);
        }
        AckResult::Ok
    }

    fn set_throttle(&mut self, s: SetThrottle) -> AckResult {
        if !self.armed {
            return AckResult::BadState;
        }
        if self.lies().ignore_commands {
            return AckResult::Ok;
        }
        if s.level > THROTTLE_FULL_SCALE {
            return AckResult::OutOfRange;
        }
        if self.pulse != Pulse::Idle {
            return AckResult::Busy;
        }
        let start = self.next_boundary_us;
        let from = self.ramp.map_or(self.setpoint, |r| r.at(start));
        self.setpoint = s.level;
        self.ramp = (s.ramp_ms > 0 && from != s.level).then_some(Ramp {
            from,
            to: s.level,
            start_us: start,
            dur_us: s.ramp_ms as u64 * 1000,
        });
        AckResult::Ok
    }

    fn impulse(&mut self, i: Impulse) -> AckResult {
        if !self.armed {
            return AckResult::BadState;
        }
        if self.lies().busy_impulses {
            return AckResult::Busy;
        }
        if self.lies().ignore_commands {
            return AckResult::Ok;
        }
        if i.level > THROTTLE_FULL_SCALE || i.width_us == 0 || i.width_us > MAX_IMPULSE_US {
            return AckResult::OutOfRange;
        }
        if self.pulse != Pulse::Idle || self.ramp.is_some() {
            return AckResult::Busy;
        }
        let periods = (i.width_us as u64 * self.rate_hz as u64).div_ceil(1_000_000);
        self.pulse = Pulse::Pending {
            level: i.level,
            periods: periods.max(1) as u32,
        };
        AckResult::Ok
    }

    fn set_rate(&mut self, hz: u16) -> AckResult {
        if self.armed {
            return AckResult::BadState;
        }
        if !(RATE_RANGE_HZ.0..=RATE_RANGE_HZ.1).contains(&hz) {
            return AckResult::OutOfRange;
        }
        if self.dynamics.set_sample_period(1.0 / hz as f64).is_err() {
            // The plant cannot be sampled that slowly (its mode is above Nyquist).
            return AckResult::OutOfRange;
        }
        self.reschedule(hz as u32);
        self.emit(Message::Hello(self.hello()));
        AckResult::Ok
    }

    fn tare(&mut self) -> AckResult {
        if self.armed {
            return AckResult::BadState;
        }
        self.tare = self.last_raw;
        self.emit_event(EventCode::TareDone, 0, self.now_us, self.index);
        AckResult::Ok
    }
}
