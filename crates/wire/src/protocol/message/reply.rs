//! The device's answers and reports (docs/PROTOCOL.md §3): 0x43 ACK with its result codes, 0x44
//! EVENT with its event codes, 0x45 LOG.

use super::{floor_char_boundary, utf8_prefix};

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
