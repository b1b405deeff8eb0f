//! Payload layouts of every TSP/1 message (docs/PROTOCOL.md §3, §4): little-endian integers,
//! IEEE-754 binary32 floats, fixed offsets. Parsing checks the type's minimum length and ignores
//! trailing bytes (fields may only be appended in later minor versions).

use super::error::DecodeError;
use super::message::{
    msg_type as t, Ack, AckResult, Arm, EscProtocol, Event, EventCode, Hello, Impulse, Log,
    Message, Sample, SampleFlags, SetRate, SetThrottle, LOG_TEXT_MAX,
};

/// Largest payload that fits a 253-byte body: 253 − 4 (ver, type, seq) − 2 (crc).
pub const MAX_PAYLOAD: usize = 247;

/// Minimum payload length of a known type, `None` for an unknown type.
pub fn min_payload_len(msg_type: u8) -> Option<usize> {
    Some(match msg_type {
        t::HELLO => 34,
        t::SAMPLE => 32,
        t::ACK => 9,
        t::EVENT => 12,
        t::LOG => 1,
        t::ARM => 6,
        t::SET_THROTTLE => 4,
        t::IMPULSE => 6,
        t::SET_RATE => 2,
        t::HELLO_REQ | t::DISARM | t::STOP | t::HEARTBEAT | t::TARE => 0,
        _ => return None,
    })
}

fn u16_at(p: &[u8], o: usize) -> u16 {
    u16::from_le_bytes([p[o], p[o + 1]])
}

fn u32_at(p: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([p[o], p[o + 1], p[o + 2], p[o + 3]])
}

fn f32_at(p: &[u8], o: usize) -> f32 {
    f32::from_bits(u32_at(p, o))
}

/// Parse the payload of a message of type `msg_type`.
pub fn parse(msg_type: u8, p: &[u8]) -> Result<Message, DecodeError> {
    let min = min_payload_len(msg_type).ok_or(DecodeError::UnknownType(msg_type))?;
    if p.len() < min {
        return Err(DecodeError::ShortPayload {
            msg_type,
            len: p.len(),
            min,
        });
    }
    // Every index below is within `min`, checked above.
    Ok(match msg_type {
        t::HELLO => Message::Hello(parse_hello(p)),
        t::SAMPLE => Message::Sample(Sample {
            sample_index: u32_at(p, 0),
            t_us: u32_at(p, 4),
            throttle: u16_at(p, 8),
            flags: SampleFlags(u16_at(p, 10)),
            thrust_n: f32_at(p, 12),
            torque_nm: f32_at(p, 16),
            rpm: f32_at(p, 20),
            voltage_v: f32_at(p, 24),
            current_a: f32_at(p, 28),
        }),
        t::ACK => Message::Ack(Ack {
            cmd_seq: u16_at(p, 0),
            cmd_type: p[2],
            result: AckResult::from_u8(p[3]),
            ack_flags: p[4],
            t_us: u32_at(p, 5),
        }),
        t::EVENT => Message::Event(Event {
            code: EventCode::from_u8(p[0]),
            arg: u16_at(p, 2),
            t_us: u32_at(p, 4),
            sample_index: u32_at(p, 8),
        }),
        t::LOG => Message::Log(Log::from_bytes(p[0], &p[1..])),
        t::ARM => Message::Arm(Arm {
            watchdog_ms: u16_at(p, 0),
            key: u32_at(p, 2),
        }),
        t::SET_THROTTLE => Message::SetThrottle(SetThrottle {
            level: u16_at(p, 0),
            ramp_ms: u16_at(p, 2),
        }),
        t::IMPULSE => Message::Impulse(Impulse {
            level: u16_at(p, 0),
            width_us: u32_at(p, 2),
        }),
        t::SET_RATE => Message::SetRate(SetRate {
            sample_rate_hz: u16_at(p, 0),
        }),
        t::HELLO_REQ => Message::HelloReq,
        t::DISARM => Message::Disarm,
        t::STOP => Message::Stop,
        t::HEARTBEAT => Message::Heartbeat,
        t::TARE => Message::Tare,
        other => return Err(DecodeError::UnknownType(other)),
    })
}

fn parse_hello(p: &[u8]) -> Hello {
    let mut name = [0u8; 16];
    name.copy_from_slice(&p[18..34]);
    Hello {
        proto_minor: p[0],
        esc_protocol: EscProtocol::from_u8(p[1]),
        fw_version: u16_at(p, 2),
        boot_id: u32_at(p, 4),
        t_us: u32_at(p, 8),
        sample_rate_hz: u16_at(p, 12),
        channels: u16_at(p, 14),
        motor_poles: p[16],
        caps: p[17],
        name,
    }
}

/// A bounded little-endian writer over a payload buffer.
struct Writer<'a> {
    out: &'a mut [u8],
    n: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) {
        self.out[self.n..self.n + b.len()].copy_from_slice(b);
        self.n += b.len();
    }
    fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.bytes(&v.to_le_bytes());
    }
}

/// Write the payload of `msg` into `out` (at least [`MAX_PAYLOAD`] bytes); returns its length.
/// A LOG payload is at most 1 + 200 bytes, so every message fits.
pub fn write(msg: &Message, out: &mut [u8; MAX_PAYLOAD]) -> usize {
    let mut w = Writer { out, n: 0 };
    match msg {
        Message::Hello(h) => {
            w.u8(h.proto_minor);
            w.u8(h.esc_protocol.to_u8());
            w.u16(h.fw_version);
            w.u32(h.boot_id);
            w.u32(h.t_us);
            w.u16(h.sample_rate_hz);
            w.u16(h.channels);
            w.u8(h.motor_poles);
            w.u8(h.caps);
            w.bytes(&h.name);
        }
        Message::Sample(s) => {
            w.u32(s.sample_index);
            w.u32(s.t_us);
            w.u16(s.throttle);
            w.u16(s.flags.0);
            w.f32(s.thrust_n);
            w.f32(s.torque_nm);
            w.f32(s.rpm);
            w.f32(s.voltage_v);
            w.f32(s.current_a);
        }
        Message::Ack(a) => {
            w.u16(a.cmd_seq);
            w.u8(a.cmd_type);
            w.u8(a.result.to_u8());
            w.u8(a.ack_flags);
            w.u32(a.t_us);
        }
        Message::Event(e) => {
            w.u8(e.code.to_u8());
            w.u8(0);
            w.u16(e.arg);
            w.u32(e.t_us);
            w.u32(e.sample_index);
        }
        Message::Log(l) => {
            w.u8(l.severity);
            let b = l.bytes();
            w.bytes(&b[..b.len().min(LOG_TEXT_MAX)]);
        }
        Message::Arm(a) => {
            w.u16(a.watchdog_ms);
            w.u32(a.key);
        }
        Message::SetThrottle(s) => {
            w.u16(s.level);
            w.u16(s.ramp_ms);
        }
        Message::Impulse(i) => {
            w.u16(i.level);
            w.u32(i.width_us);
        }
        Message::SetRate(r) => w.u16(r.sample_rate_hz),
        Message::HelloReq
        | Message::Disarm
        | Message::Stop
        | Message::Heartbeat
        | Message::Tare => {}
    }
    w.n
}
