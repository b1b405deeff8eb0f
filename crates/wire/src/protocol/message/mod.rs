//! TSP/1 messages, both directions (docs/PROTOCOL.md §3, §4), as typed payload structs.
//!
//! Everything here is `Copy` and fixed-size (a LOG text lives in a 200-byte array), so decoding
//! a frame never allocates. Wire layouts (offsets, little-endian) live in
//! [`payload`](super::payload); this module holds the types, codes and helpers: [`Message`] and
//! [`Frame`] here, HELLO in [`hello`], SAMPLE in [`sample`], ACK / EVENT / LOG in [`reply`], the
//! command payloads in [`command`].

mod command;
mod hello;
mod reply;
mod sample;

pub use command::{Arm, Impulse, SetRate, SetThrottle, ARM_KEY};
pub use hello::{caps, EscProtocol, Hello};
pub use reply::{Ack, AckResult, Event, EventCode, Log, ACK_DUPLICATE, LOG_TEXT_MAX};
pub use sample::{throttle_fraction, throttle_level, Sample, SampleFlags, THROTTLE_FULL_SCALE};

/// Message type codes (`type` byte of the frame body).
pub mod msg_type {
    /// Host → device: ask for a HELLO.
    pub const HELLO_REQ: u8 = 0x01;
    /// Host → device: arm with a watchdog.
    pub const ARM: u8 = 0x02;
    /// Host → device: disarm.
    pub const DISARM: u8 = 0x03;
    /// Host → device: set the throttle (step or ramp).
    pub const SET_THROTTLE: u8 = 0x04;
    /// Host → device: device-timed pulse.
    pub const IMPULSE: u8 = 0x05;
    /// Host → device: stop everything.
    pub const STOP: u8 = 0x06;
    /// Host → device: reset the watchdog.
    pub const HEARTBEAT: u8 = 0x07;
    /// Host → device: change the sample rate.
    pub const SET_RATE: u8 = 0x08;
    /// Host → device: tare the load cell.
    pub const TARE: u8 = 0x09;
    /// Device → host: identity and state.
    pub const HELLO: u8 = 0x41;
    /// Device → host: one measurement.
    pub const SAMPLE: u8 = 0x42;
    /// Device → host: answer to a command.
    pub const ACK: u8 = 0x43;
    /// Device → host: something happened.
    pub const EVENT: u8 = 0x44;
    /// Device → host: debug text.
    pub const LOG: u8 = 0x45;
}

/// Any TSP/1 message, device → host or host → device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message {
    /// 0x41.
    Hello(Hello),
    /// 0x42.
    Sample(Sample),
    /// 0x43.
    Ack(Ack),
    /// 0x44.
    Event(Event),
    /// 0x45.
    Log(Log),
    /// 0x01.
    HelloReq,
    /// 0x02.
    Arm(Arm),
    /// 0x03.
    Disarm,
    /// 0x04.
    SetThrottle(SetThrottle),
    /// 0x05.
    Impulse(Impulse),
    /// 0x06.
    Stop,
    /// 0x07.
    Heartbeat,
    /// 0x08.
    SetRate(SetRate),
    /// 0x09.
    Tare,
}

impl Message {
    /// The wire type code.
    pub fn msg_type(&self) -> u8 {
        use msg_type as t;
        match self {
            Self::Hello(_) => t::HELLO,
            Self::Sample(_) => t::SAMPLE,
            Self::Ack(_) => t::ACK,
            Self::Event(_) => t::EVENT,
            Self::Log(_) => t::LOG,
            Self::HelloReq => t::HELLO_REQ,
            Self::Arm(_) => t::ARM,
            Self::Disarm => t::DISARM,
            Self::SetThrottle(_) => t::SET_THROTTLE,
            Self::Impulse(_) => t::IMPULSE,
            Self::Stop => t::STOP,
            Self::Heartbeat => t::HEARTBEAT,
            Self::SetRate(_) => t::SET_RATE,
            Self::Tare => t::TARE,
        }
    }

    /// True for host → device messages (type 0x01..=0x3F).
    pub fn is_command(&self) -> bool {
        is_command_type(self.msg_type())
    }

    /// Protocol name of the message type (`"SAMPLE"`, `"SET_THROTTLE"`, …).
    pub fn name(&self) -> &'static str {
        type_name(self.msg_type()).unwrap_or("?")
    }
}

/// True for the host → device type range 0x01..=0x3F.
pub fn is_command_type(t: u8) -> bool {
    (0x01..=0x3F).contains(&t)
}

/// Protocol name of a known type code.
pub fn type_name(t: u8) -> Option<&'static str> {
    use msg_type as m;
    Some(match t {
        m::HELLO_REQ => "HELLO_REQ",
        m::ARM => "ARM",
        m::DISARM => "DISARM",
        m::SET_THROTTLE => "SET_THROTTLE",
        m::IMPULSE => "IMPULSE",
        m::STOP => "STOP",
        m::HEARTBEAT => "HEARTBEAT",
        m::SET_RATE => "SET_RATE",
        m::TARE => "TARE",
        m::HELLO => "HELLO",
        m::SAMPLE => "SAMPLE",
        m::ACK => "ACK",
        m::EVENT => "EVENT",
        m::LOG => "LOG",
        _ => return None,
    })
}

/// A decoded frame: the sender's link sequence number and the message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Per-sender counter (for commands also the command id).
    pub seq: u16,
    /// The message.
    pub msg: Message,
}

/// The longest prefix of `b` that is valid UTF-8.
fn utf8_prefix(b: &[u8]) -> &str {
    match std::str::from_utf8(b) {
        Ok(s) => s,
        // `valid_up_to` is a char boundary, so this inner conversion cannot fail.
        Err(e) => std::str::from_utf8(&b[..e.valid_up_to()]).unwrap_or(""),
    }
}

/// Largest index `<= max` that is a char boundary of `s`.
fn floor_char_boundary(s: &str, max: usize) -> usize {
    if s.len() <= max {
        return s.len();
    }
    (0..=max)
        .rev()
        .find(|&i| s.is_char_boundary(i))
        .unwrap_or(0)
}
