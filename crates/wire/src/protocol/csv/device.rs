//! What a CSV bench writes (docs/PROTOCOL.md §6 and the keyword lines of propid's simulated stand,
//! which benches may copy): written by [`device_line`] (the simulated stand) and read back by
//! [`parse_ack`] and [`parse_comment`] (the daemon, file ingest). Each message's line is its
//! [`WireMessage`](super::super::message::WireMessage) implementation's:
//!
//! | message | line                                                                   |
//! |---------|------------------------------------------------------------------------|
//! | SAMPLE  | `t_us,throttle,thrust_N,torque_Nm,rpm,voltage_V,current_A*HH` (§6's header-less order, with its checksum) |
//! | ACK     | `#ACK <CMD> OK <t_us>` or `#ACK <CMD> ERR <code>` (§6)                   |
//! | EVENT   | `#EVENT <NAME> <arg> <t_us> <sample_index>` (names as §3)               |
//! | HELLO   | `# HELLO <name> fw <version> boot_id <hex> rate_hz <rate>`              |
//! | LOG     | `# <text>` (newlines as spaces)                                          |
//!
//! Reading is lenient about order and extra words (a HELLO without `boot_id` is boot 0, without
//! `rate_hz` rate 0 = unknown), strict about numbers (a malformed number makes the line an
//! ordinary comment, never a wrong fact).

use super::super::message::{Event, Hello, Message, WireMessage};
use super::command::CsvCommandKind;

pub use super::super::message::{event_code, event_name};

/// A `#ACK` line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CsvAck {
    /// The command acknowledged.
    pub command: CsvCommandKind,
    /// `Ok(t_us)` for `OK <t_us>` (`None` when the time is absent), `Err(code)` for `ERR <code>`.
    pub result: Result<Option<u64>, i64>,
}

/// A device fact found in a comment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CommentFact {
    /// A HELLO line.
    Hello(Hello),
    /// An EVENT line.
    Event(Event),
}

/// The line (with its `\n`) a CSV bench writes for `msg`; `None` for messages the dialect has
/// no form for (host commands: see [`encode_csv_command`](super::encode_csv_command)).
pub fn device_line(msg: &Message) -> Option<String> {
    let mut s = String::new();
    if !msg.write_csv_line(&mut s) {
        return None;
    }
    s.push('\n');
    Some(s)
}

/// Parse `ACK <CMD> OK <t_us>` / `ACK <CMD> ERR <code>` (the text after `#`).
pub fn parse_ack(s: &str) -> Option<CsvAck> {
    let mut it = s.split_whitespace();
    if it.next()? != "ACK" {
        return None;
    }
    let command = CsvCommandKind::from_keyword(it.next()?);
    let result = match it.next()? {
        "OK" => Ok(match it.next() {
            Some(t) => Some(t.parse().ok()?),
            None => None,
        }),
        "ERR" => Err(it.next()?.parse().ok()?),
        _ => return None,
    };
    Some(CsvAck { command, result })
}

/// Reads a comment (the text after `#`): a HELLO or EVENT line, or `None` for anything else.
pub fn parse_comment(text: &str) -> Option<CommentFact> {
    match text.split_whitespace().next()? {
        "HELLO" => Hello::read_csv_line(text).map(CommentFact::Hello),
        "EVENT" => Event::read_csv_line(text).map(CommentFact::Event),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::csv::line::{checksum, classify, LineKind};
    use crate::protocol::message::{
        msg_type, Ack, AckResult, EventCode, Sample, SampleFlags, EVENT_NAMES,
    };

    fn comment(line: &str) -> &str {
        line.trim_end().strip_prefix('#').unwrap()
    }

    /// The lines the simulated stand writes read back as the facts it wrote.
    #[test]
    fn hello_and_event_lines_read_back() {
        let mut h = match parse_comment("HELLO x boot_id 1 rate_hz 1").unwrap() {
            CommentFact::Hello(h) => h,
            other => panic!("{other:?}"),
        };
        h.name = Hello::name_field("propid-sim");
        h.fw_version = 3;
        h.boot_id = 0xDEAD_BEEF;
        h.sample_rate_hz = 2000;
        let line = device_line(&Message::Hello(h)).unwrap();
        assert_eq!(
            line,
            "# HELLO propid-sim fw 3 boot_id deadbeef rate_hz 2000\n"
        );
        assert_eq!(parse_comment(comment(&line)), Some(CommentFact::Hello(h)));
        for (code, _) in EVENT_NAMES {
            let e = Event {
                code,
                arg: 7,
                t_us: 123_456,
                sample_index: 789,
            };
            let line = device_line(&Message::Event(e)).unwrap();
            assert_eq!(parse_comment(comment(&line)), Some(CommentFact::Event(e)));
        }
        assert_eq!(event_name(EventCode::Other(42)), "OTHER");
    }

    #[test]
    fn ordinary_and_malformed_comments_are_not_facts() {
        for text in [
            " booting stand v2",
            "HELLO x boot_id zz",
            "EVENT WATCHDOG_TRIP 0 12",
            "EVENT NOPE 0 1 2",
            "",
        ] {
            assert_eq!(parse_comment(text), None, "{text:?}");
        }
    }

    #[test]
    fn acks_read_back() {
        for (result, t_us, want) in [
            (AckResult::Ok, 527_000, Ok(Some(527_000))),
            (AckResult::OutOfRange, 0, Err(2)),
        ] {
            let a = Ack {
                cmd_seq: 1,
                cmd_type: msg_type::SET_THROTTLE,
                result,
                ack_flags: 0,
                t_us,
            };
            let line = device_line(&Message::Ack(a)).unwrap();
            let ack = parse_ack(comment(&line)).unwrap();
            assert_eq!(ack.command, CsvCommandKind::Thr);
            assert_eq!(ack.result, want);
        }
        assert_eq!(parse_ack("ACK PING OK").unwrap().result, Ok(None));
        assert_eq!(parse_ack("ACK PING MAYBE"), None);
    }

    #[test]
    fn sample_row_carries_a_valid_checksum() {
        let s = Sample {
            t_us: 1000,
            throttle: 3000,
            flags: SampleFlags::ARMED,
            thrust_n: 3.5,
            ..Sample::default()
        };
        let line = device_line(&Message::Sample(s)).unwrap();
        assert_eq!(line, "1000,3000,3.5000,0.00000,0.0,0.000,0.000*1A\n");
        let (body, rest) = line.trim_end().split_once('*').unwrap();
        assert_eq!(rest, format!("{:02X}", checksum(body.as_bytes())));
        assert_eq!(classify(line.trim_end().as_bytes()), LineKind::Data(body));
    }
}
