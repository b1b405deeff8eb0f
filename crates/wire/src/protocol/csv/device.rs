//! What a CSV bench writes (docs/PROTOCOL.md §6 and the keyword lines of propid's simulated stand,
//! which benches may copy): written by [`device_line`] (the simulated stand) and read back by
//! [`parse_ack`] and [`parse_comment`] (the daemon, file ingest).
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

use std::fmt::Write as _;

use super::super::message::{AckResult, EscProtocol, Event, EventCode, Hello, Message, Sample};
use super::command::CsvCommandKind;
use super::line::append_checksum;

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

/// The event names of docs/PROTOCOL.md §3, one table both ways.
const EVENT_NAMES: [(EventCode, &str); 9] = [
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

/// The line (with its `\n`) a CSV bench writes for `msg`; `None` for messages the dialect has
/// no form for (host commands: see [`encode_csv_command`](super::encode_csv_command)).
pub fn device_line(msg: &Message) -> Option<String> {
    let mut s = String::new();
    match msg {
        Message::Sample(x) => write_row(x, &mut s),
        Message::Ack(a) => {
            let word = CsvCommandKind::of_type(a.cmd_type).keyword().unwrap_or("?");
            if a.result == AckResult::Ok {
                let _ = write!(s, "#ACK {word} OK {}", a.t_us);
            } else {
                let _ = write!(s, "#ACK {word} ERR {}", a.result.to_u8());
            }
        }
        Message::Event(e) => {
            let _ = write!(
                s,
                "#EVENT {} {} {} {}",
                event_name(e.code),
                e.arg,
                e.t_us,
                e.sample_index
            );
        }
        Message::Hello(h) => {
            let _ = write!(
                s,
                "# HELLO {} fw {} boot_id {:08x} rate_hz {}",
                h.name_str(),
                h.fw_version,
                h.boot_id,
                h.sample_rate_hz
            );
        }
        Message::Log(l) => {
            let _ = write!(s, "# {}", l.text().replace('\n', " "));
        }
        _ => return None,
    }
    s.push('\n');
    Some(s)
}

/// A SAMPLE as a header-less data row with its checksum (no newline).
fn write_row(x: &Sample, s: &mut String) {
    let _ = write!(
        s,
        "{},{},{:.4},{:.5},{:.1},{:.3},{:.3}",
        x.t_us, x.throttle, x.thrust_n, x.torque_nm, x.rpm, x.voltage_v, x.current_a
    );
    append_checksum(s);
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
    let mut words = text.split_whitespace();
    match words.next()? {
        "HELLO" => parse_hello(words).map(CommentFact::Hello),
        "EVENT" => parse_event(words).map(CommentFact::Event),
        _ => None,
    }
}

fn parse_hello<'a>(mut words: impl Iterator<Item = &'a str>) -> Option<Hello> {
    let mut hello = Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::None,
        fw_version: 0,
        boot_id: 0,
        t_us: 0,
        sample_rate_hz: 0,
        channels: 0,
        motor_poles: 0,
        caps: 0,
        name: [0; 16],
    };
    let mut first = true;
    while let Some(w) = words.next() {
        match w {
            "fw" => hello.fw_version = words.next()?.parse().ok()?,
            "boot_id" => hello.boot_id = u32::from_str_radix(words.next()?, 16).ok()?,
            "rate_hz" => hello.sample_rate_hz = words.next()?.parse().ok()?,
            name if first => hello.name = Hello::name_field(name),
            _ => {}
        }
        first = false;
    }
    Some(hello)
}

fn parse_event<'a>(mut words: impl Iterator<Item = &'a str>) -> Option<Event> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::csv::line::{checksum, classify, LineKind};
    use crate::protocol::message::{msg_type, Ack, SampleFlags};

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
