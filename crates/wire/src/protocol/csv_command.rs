//! Commands of the CSV fallback (PROTOCOL.md §6), one per line:
//! `PING`, `ARM <watchdog_ms>`, `DISARM`, `THR <0..10000> [ramp_ms]`, `IMP <level> <width_us>`,
//! `STOP` (also the single byte `!`).
//!
//! [`encode_csv_command`] writes a [`Message`] as such a line (the host side);
//! [`parse_csv_command`] reads one back (the bench side, for a simulated CSV bench).
//! HELLO_REQ and HEARTBEAT both become `PING` (any valid command resets the watchdog);
//! SET_RATE and TARE have no CSV form.

use std::io::Write as _;

use super::message::{Arm, Impulse, Message, SetThrottle};

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

impl CsvCommandKind {
    /// From the keyword (case-sensitive, as the protocol writes it).
    pub fn from_keyword(k: &str) -> Self {
        match k {
            "PING" => Self::Ping,
            "ARM" => Self::Arm,
            "DISARM" => Self::Disarm,
            "THR" => Self::Thr,
            "IMP" => Self::Imp,
            "STOP" | "!" => Self::Stop,
            _ => Self::Other,
        }
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
    /// Unknown keyword.
    #[error("unknown CSV command")]
    Unknown,
    /// Missing or unparsable argument.
    #[error("bad or missing argument")]
    BadArgument,
}

/// Longest command line written by [`encode_csv_command`], newline included.
pub const MAX_CSV_COMMAND: usize = 32;

/// Write `msg` as a CSV command line ending in `\n` into `out`; returns its length.
pub fn encode_csv_command(msg: &Message, out: &mut [u8]) -> Result<usize, CsvCommandError> {
    let mut cur = std::io::Cursor::new(out);
    let r = match msg {
        Message::HelloReq | Message::Heartbeat => writeln!(cur, "PING"),
        Message::Arm(a) => writeln!(cur, "ARM {}", a.watchdog_ms),
        Message::Disarm => writeln!(cur, "DISARM"),
        Message::SetThrottle(s) => writeln!(cur, "THR {} {}", s.level, s.ramp_ms),
        Message::Impulse(i) => writeln!(cur, "IMP {} {}", i.level, i.width_us),
        Message::Stop => writeln!(cur, "STOP"),
        other => return Err(CsvCommandError::NoCsvForm(other.name())),
    };
    r.map_err(|_| CsvCommandError::BufferTooSmall)?;
    Ok(cur.position() as usize)
}

/// Parse one command line (without its newline; surrounding space and `\r` ignored).
/// `PING` reads as HELLO_REQ; `THR` without a ramp is a step.
pub fn parse_csv_command(line: &str) -> Result<Message, CsvCommandError> {
    let mut it = line.split_whitespace();
    let kw = it.next().ok_or(CsvCommandError::Unknown)?;
    let mut arg = || -> Result<Option<u64>, CsvCommandError> {
        it.next()
            .map(|a| a.parse().map_err(|_| CsvCommandError::BadArgument))
            .transpose()
    };
    let need = |v: Option<u64>| v.ok_or(CsvCommandError::BadArgument);
    let narrow = |v: u64| u16::try_from(v).map_err(|_| CsvCommandError::BadArgument);
    Ok(match CsvCommandKind::from_keyword(kw) {
        CsvCommandKind::Ping => Message::HelloReq,
        CsvCommandKind::Arm => Message::Arm(Arm::new(narrow(need(arg()?)?)?)),
        CsvCommandKind::Disarm => Message::Disarm,
        CsvCommandKind::Thr => {
            let level = narrow(need(arg()?)?)?;
            let ramp_ms = narrow(arg()?.unwrap_or(0))?;
            Message::SetThrottle(SetThrottle { level, ramp_ms })
        }
        CsvCommandKind::Imp => {
            let level = narrow(need(arg()?)?)?;
            let w = need(arg()?)?;
            let width_us = u32::try_from(w).map_err(|_| CsvCommandError::BadArgument)?;
            Message::Impulse(Impulse { level, width_us })
        }
        CsvCommandKind::Stop => Message::Stop,
        CsvCommandKind::Other => return Err(CsvCommandError::Unknown),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::message::SetRate;

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
        ] {
            assert_eq!(parse_csv_command(line(&m).trim_end()), Ok(m));
        }
        assert_eq!(parse_csv_command("!"), Ok(Message::Stop));
        assert_eq!(
            parse_csv_command("THR 3500"),
            Ok(Message::SetThrottle(SetThrottle {
                level: 3500,
                ramp_ms: 0
            }))
        );
        assert_eq!(parse_csv_command("THR"), Err(CsvCommandError::BadArgument));
        assert_eq!(
            parse_csv_command("THR 70000"),
            Err(CsvCommandError::BadArgument)
        );
        assert_eq!(
            parse_csv_command("IMP 5 x"),
            Err(CsvCommandError::BadArgument)
        );
        assert_eq!(parse_csv_command("FLY"), Err(CsvCommandError::Unknown));
        assert_eq!(parse_csv_command(""), Err(CsvCommandError::Unknown));
    }
}
