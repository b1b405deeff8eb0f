//! The simulated stand speaking the CSV dialect (`protocol = "csv"`, docs/PROTOCOL.md §6), for hosts
//! that speak the text fallback of simple Arduino benches. The dialect itself — lines, commands,
//! the bench's rows and `#` lines — is the protocol's
//! ([`propid_wire::protocol::csv`]); this is the bench's side of it:
//!
//! - in: host text split into lines by the dialect's [`LineSplitter`] (`\r` ignored, lines over
//!   255 characters dropped), each read by [`parse_csv_command`] — plus the single byte `!`,
//!   which stops the motor at once, without waiting for a newline. Lines carry no sequence
//!   number, so the reader numbers them itself and duplicates cannot occur; a line that is not
//!   a command is refused with the reason the dialect gives it;
//! - out: what the dialect's [`device_line`] writes for each device message (rows with their
//!   `*HH`, `#ACK`, `#EVENT`, `# HELLO`, `# <log>`).

use super::rx::{Incoming, RxStats};
use propid_wire::protocol::csv::line::{Line, LineSplitter, MAX_LINE};
use propid_wire::protocol::csv::{device_line, parse_csv_command, CsvCommandError};
use propid_wire::protocol::Message;

/// Splits host text into command lines and parses them.
#[derive(Debug, Clone)]
pub struct CsvReader {
    lines: LineSplitter,
    seq: u16,
    stats: RxStats,
}

impl Default for CsvReader {
    fn default() -> Self {
        Self::new()
    }
}

impl CsvReader {
    /// An empty reader.
    pub fn new() -> Self {
        Self {
            lines: LineSplitter::new(MAX_LINE),
            seq: 0,
            stats: RxStats::default(),
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> RxStats {
        self.stats
    }

    /// Feeds host text; `on` gets every complete line, classified.
    pub fn push(&mut self, bytes: &[u8], mut on: impl FnMut(Incoming)) {
        let Self { lines, seq, stats } = self;
        let mut line = |l: Line<'_>| {
            let inc = match l {
                Line::TooLong => Incoming::Garbage,
                Line::Text([]) => return,
                Line::Text(text) => {
                    *seq = seq.wrapping_add(1);
                    parse_line(*seq, &String::from_utf8_lossy(text))
                }
            };
            stats.count(&inc);
            on(inc);
        };
        let mut rest = bytes;
        while !rest.is_empty() {
            // `!` at the start of a line (`\r` ignored) is STOP, now.
            if lines.is_empty() && matches!(rest[0], b'!' | b'\r') {
                if rest[0] == b'!' {
                    line(Line::Text(b"STOP"));
                }
                rest = &rest[1..];
                continue;
            }
            // up to and including the next newline (after which `!` may start a line)
            let n = rest
                .iter()
                .position(|&b| b == b'\n')
                .map_or(rest.len(), |i| i + 1);
            lines.push(&rest[..n], &mut line);
            rest = &rest[n..];
        }
    }
}

/// Reads one command line (numbered `seq`): a command, or a refusal with the reason the
/// dialect gives; a line of only white space is garbage.
pub fn parse_line(seq: u16, line: &str) -> Incoming {
    match parse_csv_command(line) {
        Ok(msg) => Incoming::Command { seq, msg },
        Err(CsvCommandError::Unknown) if line.trim().is_empty() => Incoming::Garbage,
        Err(e) => Incoming::Refused {
            seq,
            msg_type: e.kind().msg_type().unwrap_or(0),
            result: e.ack_result(),
        },
    }
}

/// Formats device messages as CSV lines.
#[derive(Debug, Clone, Default)]
pub struct CsvWriter;

impl CsvWriter {
    /// A writer.
    pub fn new() -> Self {
        CsvWriter
    }

    /// The line (with its `\n`) for `msg`, `None` for messages the dialect has no form for.
    pub fn format(&self, msg: &Message) -> Option<String> {
        device_line(msg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_wire::protocol::{AckResult, Arm, Impulse, SetThrottle};

    fn read(text: &str) -> Vec<Incoming> {
        let mut r = CsvReader::new();
        let mut v = Vec::new();
        r.push(text.as_bytes(), |i| v.push(i));
        v
    }

    #[test]
    fn commands_parse() {
        let got = read("PING\r\nARM 500\nTHR 3500 200\nIMP 4000 1000\n!DISARM\r\n\r!stop\n");
        let msgs: Vec<Message> = got
            .iter()
            .map(|i| match i {
                Incoming::Command { msg, .. } => *msg,
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(
            msgs,
            vec![
                Message::HelloReq,
                Message::Arm(Arm::new(500)),
                Message::SetThrottle(SetThrottle {
                    level: 3500,
                    ramp_ms: 200
                }),
                Message::Impulse(Impulse {
                    level: 4000,
                    width_us: 1000
                }),
                Message::Stop,
                Message::Disarm,
                Message::Stop,
                Message::Stop,
            ]
        );
    }

    #[test]
    fn bad_lines_are_refused_with_a_reason() {
        let got = read("FLY\nIMP 4000\nTHR abc\n   \n");
        let results: Vec<Option<(u8, AckResult)>> = got
            .iter()
            .map(|i| match i {
                Incoming::Refused {
                    msg_type, result, ..
                } => Some((*msg_type, *result)),
                Incoming::Garbage => None,
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(
            results,
            vec![
                Some((0, AckResult::UnknownType)),
                Some((0x05, AckResult::BadLength)),
                Some((0x04, AckResult::OutOfRange)),
                None,
            ]
        );
    }

    #[test]
    fn overlong_lines_are_garbage_and_stop_needs_no_newline() {
        let mut text = "x".repeat(300);
        text.push('\n');
        let mut r = CsvReader::new();
        let mut v = Vec::new();
        r.push(text.as_bytes(), |i| v.push(i));
        r.push(b"!", |i| v.push(i));
        assert_eq!(v[0], Incoming::Garbage);
        assert!(matches!(
            v[1],
            Incoming::Command {
                msg: Message::Stop,
                ..
            }
        ));
        assert_eq!((r.stats().garbage, r.stats().commands), (1, 1));
    }
}
