//! The device's answers and reports (docs/PROTOCOL.md §3): 0x43 ACK with its result codes, 0x44
//! EVENT with its event codes and names, 0x45 LOG; the layout, CSV line (§6: `#ACK <CMD> OK
//! <t_us>` or `#ACK <CMD> ERR <code>`, `#EVENT <NAME> <arg> <t_us> <sample_index>`, `# <text>`)
//! and vector of each.

use std::fmt::Write as _;

use super::super::payload::{u16_at, u32_at, Writer};
use super::wire_message::{Vector, WireMessage};
use super::{csv_keyword, floor_char_boundary, msg_type, utf8_prefix};

/// ACK result code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum AckResult {
    /// 0: done.
    Ok,
    /// 1: not allowed in this state.
    BadState,
    /// 2: an argument is out of range.
    OutOfRange,
    /// 3: unknown command type.
    UnknownType,
    /// 4: payload too short.
    BadLength,
    /// 5: wrong ARM key.
    BadKey,
    /// 6: a pulse or ramp is running.
    Busy,
    /// 7: a limit is active.
    LimitActive,
    /// 8: protocol version not supported.
    Version,
    /// A code this version does not know.
    Other(u8),
}

impl AckResult {
    /// From the wire code.
    pub fn from_u8(v: u8) -> Self {
        match v {
            0 => Self::Ok,
            1 => Self::BadState,
            2 => Self::OutOfRange,
            3 => Self::UnknownType,
            4 => Self::BadLength,
            5 => Self::BadKey,
            6 => Self::Busy,
            7 => Self::LimitActive,
            8 => Self::Version,
            o => Self::Other(o),
        }
    }

    /// The wire code.
    pub fn to_u8(self) -> u8 {
        match self {
            Self::Ok => 0,
            Self::BadState => 1,
            Self::OutOfRange => 2,
            Self::UnknownType => 3,
            Self::BadLength => 4,
            Self::BadKey => 5,
            Self::Busy => 6,
            Self::LimitActive => 7,
            Self::Version => 8,
            Self::Other(o) => o,
        }
    }
}

/// ACK flag bit0: a repeated command, answered from memory, not executed again.
pub const ACK_DUPLICATE: u8 = 1 << 0;

/// 0x43 ACK: answers every command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ack {
    /// `seq` of the command answered.
    pub cmd_seq: u16,
    /// Type of the command answered.
    pub cmd_type: u8,
    /// Outcome.
    pub result: AckResult,
    /// Flags, see [`ACK_DUPLICATE`].
    pub ack_flags: u8,
    /// When the command took effect or was refused (device clock, µs).
    pub t_us: u32,
}

impl Ack {
    /// True when this answers a repeated command.
    pub fn is_duplicate(&self) -> bool {
        self.ack_flags & ACK_DUPLICATE != 0
    }
}

/// EVENT code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum EventCode {
    /// 1: first sample of a device-timed pulse.
    ImpulseStart,
    /// 2: first sample after the pulse.
    ImpulseEnd,
    /// 3: the watchdog stopped the motor.
    WatchdogTrip,
    /// 4: a limit cut the motor off (`arg` = channel).
    LimitCutoff,
    /// 5: armed.
    Armed,
    /// 6: disarmed.
    Disarmed,
    /// 7: the device dropped samples (`arg` = how many).
    TxOverrun,
    /// 8: reset cause after boot.
    ResetCause,
    /// 9: tare finished.
    TareDone,
    /// A code this version does not know.
    Other(u8),
}

impl EventCode {
    /// From the wire code.
    pub fn from_u8(v: u8) -> Self {
        match v {
            1 => Self::ImpulseStart,
            2 => Self::ImpulseEnd,
            3 => Self::WatchdogTrip,
            4 => Self::LimitCutoff,
            5 => Self::Armed,
            6 => Self::Disarmed,
            7 => Self::TxOverrun,
            8 => Self::ResetCause,
            9 => Self::TareDone,
            o => Self::Other(o),
        }
    }

    /// The wire code.
    pub fn to_u8(self) -> u8 {
        match self {
            Self::ImpulseStart => 1,
            Self::ImpulseEnd => 2,
            Self::WatchdogTrip => 3,
            Self::LimitCutoff => 4,
            Self::Armed => 5,
            Self::Disarmed => 6,
            Self::TxOverrun => 7,
            Self::ResetCause => 8,
            Self::TareDone => 9,
            Self::Other(o) => o,
        }
    }
}

/// The event names of docs/PROTOCOL.md §3, one table both ways.
pub(crate) const EVENT_NAMES: [(EventCode, &str); 9] = [
    (EventCode::ImpulseStart, "IMPULSE_START"),
    (EventCode::ImpulseEnd, "IMPULSE_END"),
    (EventCode::WatchdogTrip, "WATCHDOG_TRIP"),
    (EventCode::LimitCutoff, "LIMIT_CUTOFF"),
    (EventCode::Armed, "ARMED"),
    (EventCode::Disarmed, "DISARMED"),
    (EventCode::TxOverrun, "TX_OVERRUN"),
    (EventCode::ResetCause, "RESET_CAUSE"),
    (EventCode::TareDone, "TARE_DONE"),
];

/// Protocol name of an event code (`OTHER` for a code this version does not know).
pub fn event_name(c: EventCode) -> &'static str {
    EVENT_NAMES
        .iter()
        .find(|e| e.0 == c)
        .map_or("OTHER", |e| e.1)
}

/// The event code of a docs/PROTOCOL.md §3 event name.
pub fn event_code(name: &str) -> Option<EventCode> {
    EVENT_NAMES.iter().find(|e| e.1 == name).map(|e| e.0)
}

/// 0x44 EVENT.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Event {
    /// What happened.
    pub code: EventCode,
    /// Code-specific argument.
    pub arg: u16,
    /// Device clock, µs.
    pub t_us: u32,
    /// Exact sample index (impulse edges: the first sample inside / after the pulse).
    pub sample_index: u32,
}

/// Longest LOG text, bytes.
pub const LOG_TEXT_MAX: usize = 200;

/// 0x45 LOG: firmware debug text, fixed capacity (no allocation).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Log {
    /// Severity (firmware-defined; 0 = most severe by convention).
    pub severity: u8,
    len: u8,
    text: [u8; LOG_TEXT_MAX],
}

impl Log {
    /// A LOG message; text beyond 200 bytes is cut at a char boundary.
    pub fn new(severity: u8, text: &str) -> Self {
        let cut = floor_char_boundary(text, LOG_TEXT_MAX);
        Self::from_bytes(severity, &text.as_bytes()[..cut])
    }

    /// A LOG message from raw bytes (cut to 200 bytes).
    pub fn from_bytes(severity: u8, bytes: &[u8]) -> Self {
        let n = bytes.len().min(LOG_TEXT_MAX);
        let mut text = [0u8; LOG_TEXT_MAX];
        text[..n].copy_from_slice(&bytes[..n]);
        Self {
            severity,
            len: n as u8,
            text,
        }
    }

    /// The raw text bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.text[..self.len as usize]
    }

    /// The text, cut before the first invalid UTF-8 byte.
    pub fn text(&self) -> &str {
        utf8_prefix(self.bytes())
    }
}

impl std::fmt::Debug for Log {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Log")
            .field("severity", &self.severity)
            .field("text", &self.text())
            .finish()
    }
}

impl WireMessage for Ack {
    const TYPE: u8 = 0x43;
    const NAME: &'static str = "ACK";
    const MIN_LEN: usize = 9;

    fn parse(p: &[u8]) -> Self {
        Ack {
            cmd_seq: u16_at(p, 0),
            cmd_type: p[2],
            result: AckResult::from_u8(p[3]),
            ack_flags: p[4],
            t_us: u32_at(p, 5),
        }
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u16(self.cmd_seq);
        w.u8(self.cmd_type);
        w.u8(self.result.to_u8());
        w.u8(self.ack_flags);
        w.u32(self.t_us);
    }

    /// Read back as the dialect's `CsvAck` (a keyword, not a type code), by `csv::parse_ack`.
    fn write_csv_line(&self, s: &mut String) -> bool {
        let word = csv_keyword(self.cmd_type).unwrap_or("?");
        if self.result == AckResult::Ok {
            let _ = write!(s, "#ACK {word} OK {}", self.t_us);
        } else {
            let _ = write!(s, "#ACK {word} ERR {}", self.result.to_u8());
        }
        true
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 0x1235,
            msg: Ack {
                cmd_seq: 9,
                cmd_type: msg_type::IMPULSE,
                result: AckResult::Ok,
                ack_flags: 0,
                t_us: 4_000_010_000,
            },
            wire: "06 01 43 35 12 09 02 05 01 07 10 4f 6b ee 29 35 00",
            csv: Some("#ACK IMP OK 4000010000"),
        }
    }
}

impl WireMessage for Event {
    const TYPE: u8 = 0x44;
    const NAME: &'static str = "EVENT";
    const MIN_LEN: usize = 12;

    fn parse(p: &[u8]) -> Self {
        Event {
            code: EventCode::from_u8(p[0]),
            arg: u16_at(p, 2),
            t_us: u32_at(p, 4),
            sample_index: u32_at(p, 8),
        }
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u8(self.code.to_u8());
        w.u8(0);
        w.u16(self.arg);
        w.u32(self.t_us);
        w.u32(self.sample_index);
    }

    fn write_csv_line(&self, s: &mut String) -> bool {
        let _ = write!(
            s,
            "#EVENT {} {} {} {}",
            event_name(self.code),
            self.arg,
            self.t_us,
            self.sample_index
        );
        true
    }

    /// Strict: a known name and three numbers, else not an EVENT.
    fn read_csv_line(text: &str) -> Option<Self> {
        let mut words = text.split_whitespace();
        if words.next()? != "EVENT" {
            return None;
        }
        let code = event_code(words.next()?)?;
        let arg = words.next()?.parse().ok()?;
        let t_us = words.next()?.parse().ok()?;
        let sample_index = words.next()?.parse().ok()?;
        Some(Event {
            code,
            arg,
            t_us,
            sample_index,
        })
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 1,
            msg: Event {
                code: EventCode::TxOverrun,
                arg: 3,
                t_us: 1,
                sample_index: 77,
            },
            wire: "04 01 44 01 02 07 02 03 02 01 01 01 02 4d 01 01 03 d1 f9 00",
            csv: Some("#EVENT TX_OVERRUN 3 1 77"),
        }
    }
}

impl WireMessage for Log {
    const TYPE: u8 = 0x45;
    const NAME: &'static str = "LOG";
    const MIN_LEN: usize = 1;

    fn parse(p: &[u8]) -> Self {
        Log::from_bytes(p[0], &p[1..])
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u8(self.severity);
        let b = self.bytes();
        w.bytes(&b[..b.len().min(LOG_TEXT_MAX)]);
    }

    /// An ordinary comment (newlines as spaces), read back as one.
    fn write_csv_line(&self, s: &mut String) -> bool {
        let _ = write!(s, "# {}", self.text().replace('\n', " "));
        true
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 2,
            msg: Log::new(3, "boot ok"),
            wire: "04 01 45 02 0b 03 62 6f 6f 74 20 6f 6b b8 fc 00",
            csv: Some("# boot ok"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::message::EscProtocol;
    #[test]
    fn codes_round_trip() {
        for v in 0..=255u8 {
            assert_eq!(AckResult::from_u8(v).to_u8(), v);
            assert_eq!(EventCode::from_u8(v).to_u8(), v);
            assert_eq!(EscProtocol::from_u8(v).to_u8(), v);
        }
        assert_eq!(AckResult::from_u8(6), AckResult::Busy);
        assert_eq!(EventCode::from_u8(2), EventCode::ImpulseEnd);
    }

    #[test]
    fn log_text_is_cut_at_char_boundary() {
        let long = "é".repeat(150); // 300 bytes
        let log = Log::new(2, &long);
        assert_eq!(log.bytes().len(), 200);
        assert_eq!(log.text().chars().count(), 100);
        let bad = Log::from_bytes(1, &[b'o', b'k', 0xFF, b'x']);
        assert_eq!(bad.text(), "ok");
    }
}
