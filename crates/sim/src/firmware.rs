//! The stand's firmware as a sans-IO state machine (device side of TSP/1, docs/PROTOCOL.md §3–4).
//!
//! Host bytes go in with the device time they arrived ([`Firmware::feed`]); the device clock is
//! run forward with [`Firmware::advance`]; device bytes come out of [`Firmware::drain_output`].
//! Time is `now_us`, microseconds since boot (a `u64`); the wire's `t_us` is
//! `initial_t_us + now_us` modulo 2³², so a configured `initial_t_us` near 2³² makes it wrap.
//!
//! # Sample timing
//! Period `k` runs from boundary `b_k` to `b_{k+1}`, with `b_k = base + k·10⁶/rate` µs computed
//! from `k` (no accumulated rounding). At `b_k` the firmware commits the throttle `u_k` for
//! period `k` (watchdog, ramp and pulse are evaluated there, so a command takes effect at the
//! next boundary and its ACK carries that time), reads the sensors (the reading at `b_k` is the
//! end of period `k−1`) and sends `SAMPLE k−1 = {u_{k−1}, flags of period k−1, reading,
//! t_us = b_k}`: "the measured value is taken at the end of the period in which `throttle` was
//! applied" (§3). With the plant's `y_k = C x_k`, a SAMPLE therefore pairs `u_k` with
//! `C x_{k+1} = C A x_k + C B u_k`: records made from it have `Y_0 = C B`.
//!
//! # Pulses
//! IMPULSE holds the absolute `level` for `ceil(width_us · rate / 10⁶)` periods (at least one)
//! starting at the next boundary, then returns to the setpoint. EVENT IMPULSE_START carries the
//! index of the first SAMPLE at the pulse level, IMPULSE_END the index of the first SAMPLE
//! back at the setpoint; both carry the boundary time. A pulse cut short by STOP, DISARM or the
//! watchdog still gets its IMPULSE_END.

use super::config::{StandConfig, WireProtocol};
use super::csv::{CsvReader, CsvWriter};
use super::dedup::Dedup;
use super::dynamics::Dynamics;
use super::faults::{FaultInjector, FaultStats, FrameKind};
use super::plant::Measurement;
use super::rx::{CommandReader, Incoming, RxStats};
use propid_wire::protocol::message::caps;
use propid_wire::protocol::{
    encode_frame, EscProtocol, Event, EventCode, Hello, Log, Message, Sample, SampleFlags,
    MAX_FRAME_LEN,
};

/// Commands kept between two [`Firmware::take_commands`] (a runner takes them every turn).
pub const MAX_COMMAND_LOG: usize = 1 << 16;

/// Protocol minor version the firmware speaks.
pub const PROTO_MINOR: u8 = 0;

/// A ramp of the setpoint, linear in time.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ramp {
    pub(crate) from: u16,
    pub(crate) to: u16,
    pub(crate) start_us: u64,
    pub(crate) dur_us: u64,
}

impl Ramp {
    /// The level at time `t_us` (`to` once the ramp is over).
    pub(crate) fn at(&self, t_us: u64) -> u16 {
        let dt = t_us.saturating_sub(self.start_us);
        if dt >= self.dur_us {
            return self.to;
        }
        let (a, b) = (self.from as i64, self.to as i64);
        (a + (b - a) * dt as i64 / self.dur_us as i64) as u16
    }
}

/// A device-timed pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Pulse {
    /// No pulse.
    Idle,
    /// Accepted, starts at the next boundary.
    Pending { level: u16, periods: u32 },
    /// Running: `left` more periods at `level`.
    Active { level: u16, left: u32 },
}

/// What the firmware did, for tests and the runner's report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct FirmwareStats {
    /// SAMPLEs taken (including any a fault dropped).
    pub samples: u64,
    /// Frames (or CSV lines) produced, before faults.
    pub frames_out: u64,
    /// ACKs sent.
    pub acks: u64,
    /// Of those, answers to duplicates.
    pub duplicates: u64,
    /// Commands executed (not duplicates, not refused).
    pub executed: u64,
    /// Pulses started.
    pub pulses: u64,
    /// Watchdog trips.
    pub watchdog_trips: u64,
    /// Receive counters.
    pub rx: RxStats,
}

/// Wire-format specific halves.
#[derive(Debug)]
enum Wire {
    Tsp(Box<CommandReader>),
    Csv(CsvReader, CsvWriter),
}

/// The simulated stand's firmware. See the [module documentation](self).
#[derive(Debug)]
pub struct Firmware<D: Dynamics> {
    pub(crate) cfg: StandConfig,
    pub(crate) dynamics: D,
    pub(crate) boot_id: u32,
    pub(crate) rate_hz: u32,
    sched_base_us: u64,
    sched_k: u64,
    running: bool,
    pub(crate) next_boundary_us: u64,
    pub(crate) now_us: u64,
    /// Index of the period now running.
    pub(crate) index: u32,
    cur_throttle: u16,
    cur_flags: SampleFlags,
    pub(crate) armed: bool,
    pub(crate) watchdog_us: u64,
    pub(crate) last_cmd_us: u64,
    pub(crate) watchdog_tripped: bool,
    pub(crate) setpoint: u16,
    pub(crate) ramp: Option<Ramp>,
    pub(crate) pulse: Pulse,
    pub(crate) tare: (f64, f64),
    pub(crate) last_raw: (f64, f64),
    next_hello_us: u64,
    pub(crate) dedup: Dedup,
    wire: Wire,
    tx_seq: u16,
    faults: FaultInjector,
    pub(crate) stats: FirmwareStats,
    /// Every well-formed command received, in order (`seq`, message), until taken.
    commands: Vec<(u16, Message)>,
    /// The clock's offset from its clock jumps so far, µs (`clock_jump_us`).
    clock_offset_us: i64,
}

impl<D: Dynamics> Firmware<D> {
    /// Boots the firmware at `now_us = 0`: HELLO, EVENT RESET_CAUSE (arg 0, power-on), a LOG
    /// line, and the first boundary. `cfg` must have passed validation.
    pub fn new(cfg: &StandConfig, dynamics: D, boot_id: u32, faults: FaultInjector) -> Self {
        let wire = match cfg.protocol {
            WireProtocol::Tsp => Wire::Tsp(Box::default()),
            WireProtocol::Csv => Wire::Csv(CsvReader::new(), CsvWriter::new()),
        };
        let faults = match cfg.protocol {
            WireProtocol::Tsp => faults,
            WireProtocol::Csv => faults.with_delimiter(b'\n'),
        };
        let mut fw = Firmware {
            cfg: cfg.clone(),
            dynamics,
            boot_id,
            rate_hz: cfg.sample_rate_hz,
            sched_base_us: 0,
            sched_k: 0,
            running: false,
            next_boundary_us: 0,
            now_us: 0,
            index: 0,
            cur_throttle: 0,
            cur_flags: SampleFlags::default(),
            armed: false,
            watchdog_us: 500_000,
            last_cmd_us: 0,
            watchdog_tripped: false,
            setpoint: 0,
            ramp: None,
            pulse: Pulse::Idle,
            tare: (0.0, 0.0),
            last_raw: (0.0, 0.0),
            next_hello_us: cfg.hello_period_ms as u64 * 1000,
            dedup: Dedup::new(),
            wire,
            tx_seq: 0,
            faults,
            stats: FirmwareStats::default(),
            commands: Vec::new(),
            clock_offset_us: 0,
        };
        fw.emit(Message::Hello(fw.hello()));
        fw.emit_event(EventCode::ResetCause, 0, 0, 0);
        let banner = format!("{} fw {} booted", cfg.name, cfg.fw_version);
        fw.emit(Message::Log(Log::new(2, &banner)));
        fw.boundary();
        fw
    }

    /// This boot's id.
    pub fn boot_id(&self) -> u32 {
        self.boot_id
    }

    /// The sample rate now in force, Hz.
    pub fn sample_rate_hz(&self) -> u32 {
        self.rate_hz
    }

    /// Device time of the next sample boundary, µs since boot: the runner sleeps until then.
    pub fn next_deadline_us(&self) -> u64 {
        self.next_boundary_us
    }

    /// True while armed.
    pub fn is_armed(&self) -> bool {
        self.armed
    }

    /// Counters so far.
    pub fn stats(&self) -> FirmwareStats {
        let mut s = self.stats;
        s.rx = match &self.wire {
            Wire::Tsp(r) => r.stats(),
            Wire::Csv(r, _) => r.stats(),
        };
        s
    }

    /// Injected faults so far.
    pub fn fault_stats(&self) -> FaultStats {
        self.faults.stats()
    }

    /// The fault injector, to carry its counts and generator into the next boot.
    pub fn into_faults(self) -> FaultInjector {
        self.faults
    }

    /// Mutable access to the fault injector (the runner counts hang-ups there).
    pub fn faults_mut(&mut self) -> &mut FaultInjector {
        &mut self.faults
    }

    /// The plant (or stand-in).
    pub fn dynamics(&self) -> &D {
        &self.dynamics
    }

    /// Device clock on the wire for device time `t` (µs since boot), wrapping at 2³² (shifted
    /// by the clock jumps so far, `clock_jump_us`).
    pub fn wire_t_us(&self, t: u64) -> u32 {
        self.cfg
            .initial_t_us
            .wrapping_add(t as u32)
            .wrapping_add(self.clock_offset_us as u32)
    }

    /// The commands received since the last call (`seq`, message): the host's every command,
    /// for tests that check them against the plan.
    pub fn take_commands(&mut self) -> Vec<(u16, Message)> {
        std::mem::take(&mut self.commands)
    }

    /// Logs a command received (see [`Self::take_commands`]).
    pub(crate) fn log_command(&mut self, seq: u16, msg: Message) {
        if self.commands.len() < MAX_COMMAND_LOG {
            self.commands.push((seq, msg));
        }
    }

    /// The configured misbehaviours (`[faults]`: runaway throttle, BUSY, ...).
    pub(crate) fn lies(&self) -> &super::config::FaultConfig {
        self.faults.config()
    }

    /// Runs the device clock to `now_us`: every boundary up to it (SAMPLEs, pulse edges,
    /// watchdog, periodic HELLO).
    pub fn advance(&mut self, now_us: u64) {
        while self.next_boundary_us <= now_us {
            self.now_us = self.next_boundary_us;
            self.boundary();
        }
        self.now_us = self.now_us.max(now_us);
    }

    /// Host bytes arrived at `now_us`: the clock is advanced first, then every complete
    /// command is executed (or refused) and answered.
    pub fn feed(&mut self, now_us: u64, bytes: &[u8]) {
        self.advance(now_us);
        let mut incoming = Vec::new();
        match &mut self.wire {
            Wire::Tsp(r) => r.push(bytes, |i| incoming.push(i)),
            Wire::Csv(r, _) => r.push(bytes, |i| incoming.push(i)),
        }
        for inc in incoming {
            match inc {
                Incoming::Command { seq, msg } => self.command(seq, msg),
                Incoming::Refused {
                    seq,
                    msg_type,
                    result,
                } => self.ack(seq, msg_type, result, false, self.now_us),
                Incoming::Garbage => {}
            }
        }
    }

    /// Moves the bytes that may go on the wire at `now_us` into `out` (faults applied).
    pub fn drain_output(&mut self, now_us: u64, out: &mut Vec<u8>) {
        self.faults.drain_ready(now_us, out);
    }

    /// Boundary `b = next_boundary_us`: commit the next period, read, send the last SAMPLE.
    fn boundary(&mut self) {
        let b = self.next_boundary_us;
        let first = !self.running;
        self.running = true;
        let prev = (self.cur_throttle, self.cur_flags);
        if !first {
            self.index = self.index.wrapping_add(1);
        }
        if self.armed && b.saturating_sub(self.last_cmd_us) >= self.watchdog_us {
            self.watchdog_trip(b);
        }
        let (mut u, flags) = self.commit(b);
        if self.lies().runaway_throttle && self.armed && u > 0 {
            u = propid_wire::protocol::message::THROTTLE_FULL_SCALE;
        }
        self.cur_throttle = u;
        self.cur_flags = flags;
        let m = self
            .dynamics
            .step(propid_wire::protocol::message::throttle_fraction(u));
        self.last_raw = (m.thrust_n, m.torque_nm);
        if !first {
            self.send_sample(b, prev.0, prev.1, &m);
        }
        if b >= self.next_hello_us {
            self.emit(Message::Hello(self.hello_at(b)));
            let p = self.cfg.hello_period_ms as u64 * 1000;
            while self.next_hello_us <= b {
                self.next_hello_us += p;
            }
        }
        self.sched_k += 1;
        self.next_boundary_us = self.sched_base_us + self.sched_k * 1_000_000 / self.rate_hz as u64;
    }

    /// The throttle and flags of the period starting at `b` (index `self.index`).
    fn commit(&mut self, b: u64) -> (u16, SampleFlags) {
        let mut flags = SampleFlags::default();
        if self.watchdog_tripped {
            flags.insert(SampleFlags::WATCHDOG_TRIPPED);
        }
        if !self.armed {
            return (0, flags);
        }
        flags.insert(SampleFlags::ARMED);
        let mut base = self.setpoint;
        if let Some(r) = self.ramp {
            base = r.at(b);
            if b >= r.start_us + r.dur_us {
                self.ramp = None;
            } else {
                flags.insert(SampleFlags::RAMP_ACTIVE);
            }
        }
        if let Pulse::Pending { level, periods } = self.pulse {
            self.stats.pulses += 1;
            self.emit_event(EventCode::ImpulseStart, level, b, self.index);
            self.pulse = Pulse::Active {
                level,
                left: periods,
            };
        }
        match self.pulse {
            Pulse::Active { level, left } if left > 0 => {
                self.pulse = Pulse::Active {
                    level,
                    left: left - 1,
                };
                flags.insert(SampleFlags::IMPULSE_ACTIVE);
                (level, flags)
            }
            Pulse::Active { level, .. } => {
                self.emit_event(EventCode::ImpulseEnd, level, b, self.index);
                self.pulse = Pulse::Idle;
                (base, flags)
            }
            _ => (base, flags),
        }
    }

    fn send_sample(&mut self, b: u64, throttle: u16, mut flags: SampleFlags, m: &Measurement) {
        self.stats.samples += 1;
        let mut thrust = m.thrust_n - self.tare.0;
        let torque = m.torque_nm - self.tare.1;
        let index = self.index.wrapping_sub(1);
        let every = self.lies().clock_jump_every_samples;
        if every > 0 && index > 0 && index % every == 0 {
            self.clock_offset_us += self.lies().clock_jump_us;
        }
        let every = self.lies().absurd_thrust_every_samples;
        if every > 0 && index % every < 4 {
            const ABSURD: [f64; 4] = [3e38, f64::NEG_INFINITY, -3e38, f64::INFINITY];
            thrust = ABSURD[(index % every) as usize];
            flags.insert(SampleFlags::THRUST_VALID);
        }
        let channels = [
            (SampleFlags::THRUST_VALID, thrust),
            (SampleFlags::TORQUE_VALID, torque),
            (SampleFlags::RPM_VALID, m.rpm),
            (SampleFlags::VOLTAGE_VALID, m.voltage_v),
            (SampleFlags::CURRENT_VALID, m.current_a),
        ];
        for (f, v) in channels {
            if v.is_finite() {
                flags.insert(f);
            }
        }
        flags.insert(SampleFlags::THRUST_FRESH | SampleFlags::RPM_FRESH);
        if m.adc_saturated {
            flags.insert(SampleFlags::ADC_SATURATED);
        }
        let sample = Sample {
            sample_index: self.index.wrapping_sub(1),
            t_us: self.wire_t_us(b),
            throttle,
            flags,
            thrust_n: thrust as f32,
            torque_nm: torque as f32,
            rpm: m.rpm as f32,
            voltage_v: m.voltage_v as f32,
            current_a: m.current_a as f32,
        };
        if self.faults.before_sample(sample.sample_index) {
            return;
        }
        self.emit(Message::Sample(sample));
    }

    /// The watchdog fired at boundary `b`: motor stop, disarm, EVENT WATCHDOG_TRIP.
    fn watchdog_trip(&mut self, b: u64) {
        self.stats.watchdog_trips += 1;
        self.watchdog_tripped = true;
        self.emit_event(EventCode::WatchdogTrip, 0, b, self.index);
        self.stop_motor(b, b, self.index);
    }

    /// Motor stop, disarm, cancel ramp and pulse; EVENT DISARMED when it was armed (and
    /// IMPULSE_END for a pulse that was running). `t` is the device time of the stop, the
    /// throttle is zero from boundary `b_end` (sample `idx_end`) on.
    pub(crate) fn stop_motor(&mut self, t: u64, b_end: u64, idx_end: u32) {
        if let Pulse::Active { level, .. } = self.pulse {
            self.emit_event(EventCode::ImpulseEnd, level, b_end, idx_end);
        }
        self.pulse = Pulse::Idle;
        self.ramp = None;
        self.setpoint = 0;
        if self.armed {
            self.armed = false;
            self.emit_event(EventCode::Disarmed, 0, t, self.index);
        }
    }

    /// HELLO as of now.
    pub(crate) fn hello(&self) -> Hello {
        self.hello_at(self.now_us)
    }

    fn hello_at(&self, t: u64) -> Hello {
        Hello {
            proto_minor: PROTO_MINOR,
            esc_protocol: EscProtocol::from_u8(self.cfg.esc_protocol),
            fw_version: self.cfg.fw_version,
            boot_id: self.boot_id,
            t_us: self.wire_t_us(t),
            sample_rate_hz: self
                .lies()
                .hello_rate_hz
                .unwrap_or(self.rate_hz.min(u16::MAX as u32) as u16),
            channels: 0b1_1111,
            motor_poles: self.cfg.motor_poles,
            caps: caps::IMPULSE | caps::RAMP | caps::TARE | caps::SET_RATE,
            name: Hello::name_field(&self.cfg.name),
        }
    }

    /// Re-bases the sample schedule at the next boundary with a new rate.
    pub(crate) fn reschedule(&mut self, rate_hz: u32) {
        self.sched_base_us = self.next_boundary_us;
        self.sched_k = 0;
        self.rate_hz = rate_hz;
    }

    pub(crate) fn emit_event(&mut self, code: EventCode, arg: u16, t: u64, index: u32) {
        let ev = Event {
            code,
            arg,
            t_us: self.wire_t_us(t),
            sample_index: index,
        };
        self.emit(Message::Event(ev));
    }

    /// Encodes one device message (next link `seq`) into the fault stage.
    pub(crate) fn emit(&mut self, msg: Message) {
        let kind = if matches!(msg, Message::Sample(_)) {
            FrameKind::Sample
        } else {
            FrameKind::Other
        };
        self.stats.frames_out += 1;
        match &mut self.wire {
            Wire::Tsp(_) => {
                let mut buf = [0u8; MAX_FRAME_LEN];
                let n = encode_frame(self.tx_seq, &msg, &mut buf);
                self.faults.push_frame(&buf[..n], kind);
            }
            Wire::Csv(_, w) => {
                if let Some(line) = w.format(&msg) {
                    self.faults.push_frame(line.as_bytes(), kind);
                }
            }
        }
        self.tx_seq = self.tx_seq.wrapping_add(1);
    }
}

#[cfg(test)]
#[path = "firmware_tests.rs"]
mod tests;
