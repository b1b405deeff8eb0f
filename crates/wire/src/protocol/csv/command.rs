//! Commands of the CSV fallback (docs/PROTOCOL.md §6), one per line:
//! `PING`, `ARM <watchdog_ms>`, `DISARM`, `THR <0..10000> [ramp_ms]`, `IMP <level> <width_us>`,
//! `STOP` (also the single byte `!`).
//!
//! [`encode_csv_command`] writes a [`Message`] as such a line (the host side: the daemon);
//! [`parse_csv_command`] reads one back (the bench side: the simulated CSV bench). Each
//! message's keyword and arguments are its [`WireMessage`](super::super::message::WireMessage)
//! implementation's; [`CsvCommandKind`] names the dialect's keywords for the `#ACK <CMD> …`
//! lines. HELLO_REQ and HEARTBEAT both become `PING` (any valid command resets the watchdog);
//! SET_RATE and TARE have no CSV form.
//!
//! Reading is lenient where a bench can afford it: keywords in any case, words after the
//! arguments a command takes ignored. An argument that is missing, not a whole number, or out
//! of its field's range is an error with a reason the bench can acknowledge
//! ([`CsvCommandError::ack_result`]).

use std::io::Write as _;

use super::super::message::{csv_keyword, csv_reader, AckResult, CsvArgError, CsvArgs, Message};

/// The command keyword of a CSV command or `#ACK` line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsvCommandKind {
    /// `PING`.
    Ping,
    /// `ARM`.
    Arm,
    /// `DISARM`.
    Disarm,
    /// `THR`.
    Thr,
    /// `IMP`.
    Imp,
    /// `STOP` or `!`.
    Stop,
    /// Anything else.
    Other,
}

/// The keyword table: kind and keyword (the messages say which keyword they are written as).
const KEYWORDS: [(CsvCommandKind, &str); 6] = [
    (CsvCommandKind::Ping, "PING"),
    (CsvCommandKind::Arm, "ARM"),
    (CsvCommandKind::Disarm, "DISARM"),
    (CsvCommandKind::Thr, "THR"),
    (CsvCommandKind::Imp, "IMP"),
    (CsvCommandKind::Stop, "STOP"),
];

impl CsvCommandKind {
    /// From the keyword (case-sensitive, as the protocol writes it; `!` is STOP).
    pub fn from_keyword(k: &str) -> Self {
        if k == "!" {
            return Self::Stop;
        }
        KEYWORDS
            .iter()
            .find(|e| e.1 == k)
            .map_or(Self::Other, |e| e.0)
    }

    /// The keyword as the protocol writes it (`None` for [`Other`](Self::Other)).
    pub fn keyword(self) -> Option<&'static str> {
        KEYWORDS.iter().find(|e| e.0 == self).map(|e| e.1)
    }

    /// The TSP/1 command type it stands for, the message that reads its keyword (`PING` is
    /// HELLO_REQ).
    pub fn msg_type(self) -> Option<u8> {
        csv_reader(self.keyword()?)
    }

    /// The kind a TSP/1 command type is written as (HELLO_REQ and HEARTBEAT are `PING`).
    pub fn of_type(t: u8) -> Self {
        csv_keyword(t).map_or(Self::Other, Self::from_keyword)
    }

    /// The kind a message is written as (`Other` for those without a CSV form).
    pub fn of(msg: &Message) -> Self {
        Self::of_type(msg.msg_type())
    }
}

/// Why a command cannot be written or read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum CsvCommandError {
    /// The message has no CSV form (device → host messages, SET_RATE, TARE).
    #[error("{0} has no CSV command form")]
    NoCsvForm(&'static str),
    /// The output buffer is too small (32 bytes always suffice).
    #[error("output buffer too small")]
    BufferTooSmall,
    /// Unknown keyword (or an empty line).
    #[error("unknown CSV command")]
    Unknown,
    /// A required argument is missing.
    #[error("{0:?}: missing argument")]
    MissingArgument(CsvCommandKind),
    /// An argument is not a whole number or out of its field's range.
    #[error("{0:?}: bad argument")]
    BadArgument(CsvCommandKind),
}

impl CsvCommandError {
    /// The refusal a bench acknowledges a line with (§4 result codes): UNKNOWN_TYPE,
    /// BAD_LENGTH for a missing argument, OUT_OF_RANGE for a bad one.
    pub fn ack_result(&self) -> AckResult {
        match self {
            Self::MissingArgument(_) => AckResult::BadLength,
            Self::BadArgument(_) => AckResult::OutOfRange,
            _ => AckResult::UnknownType,
        }
    }

    /// The command the line named, when its keyword was known.
    pub fn kind(&self) -> CsvCommandKind {
        match self {
            Self::MissingArgument(k) | Self::BadArgument(k) => *k,
            _ => CsvCommandKind::Other,
        }
    }
}

/// Longest command line written by [`encode_csv_command`], newline included.
pub const MAX_CSV_COMMAND: usize = 32;

/// Write `msg` as a CSV command line ending in `\n` into `out`; returns its length.
pub fn encode_csv_command(msg: &Message, out: &mut [u8]) -> Result<usize, CsvCommandError> {
    let kind = CsvCommandKind::of(msg);
    let Some(kw) = kind.keyword() else {
        return Err(CsvCommandError::NoCsvForm(msg.name()));
    };
    let mut cur = std::io::Cursor::new(out);
    let r = write!(cur, "{kw}")
        .and_then(|()| msg.write_csv_args(&mut cur))
        .and_then(|()| writeln!(cur));
    r.map_err(|_| CsvCommandError::BufferTooSmall)?;
    Ok(cur.position() as usize)
}

/// Parse one command line (without its newline; surrounding space and `\r` ignored).
/// `PING` reads as HELLO_REQ; `THR` without a ramp is a step.
pub fn parse_csv_command(line: &str) -> Result<Message, CsvCommandError> {
    let mut it = line.split_whitespace();
    let kw = it.next().ok_or(CsvCommandError::Unknown)?;
    let kind = CsvCommandKind::from_keyword(&kw.to_ascii_uppercase());
    let keyword = kind.keyword().ok_or(CsvCommandError::Unknown)?;
    // Arity first, then the numbers: a line with too few words is BAD_LENGTH whatever they are.
    match Message::parse_csv_args(keyword, &mut CsvArgs::new(it)) {
        None => Err(CsvCommandError::Unknown),
        Some(Ok(msg)) => Ok(msg),
        Some(Err(CsvArgError::Missing)) => Err(CsvCommandError::MissingArgument(kind)),
        Some(Err(CsvArgError::Bad)) => Err(CsvCommandError::BadArgument(kind)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::message::{msg_type, Arm, Impulse, SetRate, SetThrottle};

    fn line(msg: &Message) -> String {
        let mut buf = [0u8; MAX_CSV_COMMAND];
        let n = encode_csv_command(msg, &mut buf).unwrap();
        String::from_utf8(buf[..n].to_vec()).unwrap()
    }

    #[test]
    fn commands_are_written_as_the_protocol_shows() {
        let thr = Message::SetThrottle(SetThrottle {
            level: 3500,
            ramp_ms: 0,
        });
        assert_eq!(line(&thr), "THR 3500 0\n");
        let imp = Message::Impulse(Impulse {
            level: 6000,
            width_us: 20000,
        });
        assert_eq!(line(&imp), "IMP 6000 20000\n");
        assert_eq!(line(&Message::Arm(Arm::new(500))), "ARM 500\n");
        assert_eq!(line(&Message::Stop), "STOP\n");
        assert_eq!(line(&Message::Disarm), "DISARM\n");
        assert_eq!(line(&Message::Heartbeat), "PING\n");
        assert_eq!(line(&Message::HelloReq), "PING\n");
        let rate = Message::SetRate(SetRate { sample_rate_hz: 1 });
        let mut buf = [0u8; 32];
        assert_eq!(
            encode_csv_command(&rate, &mut buf),
            Err(CsvCommandError::NoCsvForm("SET_RATE"))
        );
        assert_eq!(
            encode_csv_command(&imp, &mut buf[..4]),
            Err(CsvCommandError::BufferTooSmall)
        );
    }

    #[test]
    fn commands_parse_back() {
        for m in [
            Message::Arm(Arm::new(500)),
            Message::SetThrottle(SetThrottle {
                level: 10000,
                ramp_ms: 250,
            }),
            Message::Impulse(Impulse {
                level: 1,
                width_us: 4_000_000,
            }),
            Message::Stop,
            Message::Disarm,
            Message::HelloReq,
        ] {
            assert_eq!(parse_csv_command(line(&m).trim_end()), Ok(m));
        }
        assert_eq!(parse_csv_command("!"), Ok(Message::Stop));
        assert_eq!(parse_csv_command("stop now"), Ok(Message::Stop));
        assert_eq!(
            parse_csv_command("thr 3500"),
            Ok(Message::SetThrottle(SetThrottle {
                level: 3500,
                ramp_ms: 0
            }))
        );
    }

    #[test]
    fn bad_lines_have_a_reason_a_bench_can_acknowledge() {
        use CsvCommandKind::*;
        let cases = [
            (
                "THR",
                CsvCommandError::MissingArgument(Thr),
                AckResult::BadLength,
            ),
            (
                "IMP 4000",
                CsvCommandError::MissingArgument(Imp),
                AckResult::BadLength,
            ),
            (
                "IMP x",
                CsvCommandError::MissingArgument(Imp),
                AckResult::BadLength,
            ),
            (
                "THR 70000",
                CsvCommandError::BadArgument(Thr),
                AckResult::OutOfRange,
            ),
            (
                "THR abc",
                CsvCommandError::BadArgument(Thr),
                AckResult::OutOfRange,
            ),
            (
                "IMP 5 x",
                CsvCommandError::BadArgument(Imp),
                AckResult::OutOfRange,
            ),
            (
                "ARM -1",
                CsvCommandError::BadArgument(Arm),
                AckResult::OutOfRange,
            ),
            ("FLY", CsvCommandError::Unknown, AckResult::UnknownType),
            ("", CsvCommandError::Unknown, AckResult::UnknownType),
        ];
        for (text, err, ack) in cases {
            assert_eq!(parse_csv_command(text), Err(err), "{text}");
            assert_eq!(err.ack_result(), ack, "{text}");
        }
        assert_eq!(
            CsvCommandError::BadArgument(Imp).kind().msg_type(),
            Some(msg_type::IMPULSE)
        );
    }

    #[test]
    fn one_keyword_table_both_ways() {
        for t in [
            msg_type::HELLO_REQ,
            msg_type::ARM,
            msg_type::DISARM,
            msg_type::SET_THROTTLE,
            msg_type::IMPULSE,
            msg_type::STOP,
        ] {
            let k = CsvCommandKind::of_type(t);
            assert_eq!(k.msg_type(), Some(t));
            assert_eq!(CsvCommandKind::from_keyword(k.keyword().unwrap()), k);
        }
        assert_eq!(
            CsvCommandKind::of_type(msg_type::HEARTBEAT),
            CsvCommandKind::Ping
        );
        assert_eq!(
            CsvCommandKind::of_type(msg_type::TARE),
            CsvCommandKind::Other
        );
        assert_eq!(CsvCommandKind::Other.keyword(), None);
    }
}
