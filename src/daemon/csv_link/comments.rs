//! `#` lines that carry device facts in the CSV dialect of propid's simulated stand and of
//! benches that copy it (PROTOCOL.md §6 leaves `#` lines free: comments, banners, ACKs):
//!
//! - `# HELLO <name> fw <version> boot_id <hex> rate_hz <rate>`: the device's HELLO;
//! - `#EVENT <NAME> <arg> <t_us> <sample_index>`: a device EVENT (names as PROTOCOL.md §3).
//!
//! Anything else is an ordinary comment. Parsing is lenient about order and extra words (a
//! HELLO without `boot_id` is boot 0, without `rate_hz` rate 0 = unknown), strict about
//! numbers (a malformed number makes the line an ordinary comment, never a wrong fact).

use propid_wire::protocol::message::{EscProtocol, Event, EventCode, Hello};

/// A device fact found in a comment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CommentFact {
    /// A HELLO line.
    Hello(Hello),
    /// An EVENT line.
    Event(Event),
}

/// Reads a comment (the text after `#`).
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

/// The event code of a PROTOCOL.md §3 event name.
fn event_code(name: &str) -> Option<EventCode> {
    Some(match name {
        "IMPULSE_START" => EventCode::ImpulseStart,
        "IMPULSE_END" => EventCode::ImpulseEnd,
        "WATCHDOG_TRIP" => EventCode::WatchdogTrip,
        "LIMIT_CUTOFF" => EventCode::LimitCutoff,
        "ARMED" => EventCode::Armed,
        "DISARMED" => EventCode::Disarmed,
        "TX_OVERRUN" => EventCode::TxOverrun,
        "RESET_CAUSE" => EventCode::ResetCause,
        "TARE_DONE" => EventCode::TareDone,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_sim::csv::CsvWriter;
    use propid_wire::protocol::message::Message;

    /// The simulated stand's own lines read back as the facts it wrote.
    #[test]
    fn reads_what_the_simulated_stand_writes() {
        let mut h = match parse_comment("HELLO x boot_id 1 rate_hz 1").unwrap() {
            CommentFact::Hello(h) => h,
            other => panic!("{other:?}"),
        };
        h.name = Hello::name_field("propid-sim");
        h.fw_version = 3;
        h.boot_id = 0xDEAD_BEEF;
        h.sample_rate_hz = 2000;
        let line = CsvWriter::new().format(&Message::Hello(h)).unwrap();
        let text = line.trim_end().strip_prefix('#').unwrap();
        assert_eq!(parse_comment(text), Some(CommentFact::Hello(h)));

        let e = Event {
            code: EventCode::WatchdogTrip,
            arg: 0,
            t_us: 123_456,
            sample_index: 789,
        };
        let line = CsvWriter::new().format(&Message::Event(e)).unwrap();
        let text = line.trim_end().strip_prefix('#').unwrap();
        assert_eq!(parse_comment(text), Some(CommentFact::Event(e)));
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
}
