//! The CSV dialect of the simulated stand (`protocol = "csv"`, PROTOCOL.md §6), for hosts
//! that speak the text fallback of simple Arduino benches.
//!
//! Out: data rows without a header in the default column order
//! `t_us,throttle,thrust_N,torque_Nm,rpm,voltage_V,current_A`, each with the `*HH` checksum
//! (XOR of every character before `*`, as NMEA); `#ACK <CMD> OK <t_us>` / `#ACK <CMD> ERR <code>`;
//! events as `#EVENT <NAME> <arg> <t_us> <sample_index>`, HELLO and LOG as `#` comments.
//! In: `PING`, `ARM <watchdog_ms>`, `DISARM`, `THR <0..10000> [ramp_ms]`, `IMP <level> <width_us>`,
//! `STOP` or the single byte `!`, one per line (`\r` ignored, lines over 255 characters dropped).
//! Lines carry no sequence number, so the reader numbers them itself and duplicates cannot
//! occur.

use std::fmt::Write as _;

use super::rx::{Incoming, RxStats};
use propid_wire::protocol::message::{msg_type, ARM_KEY};
use propid_wire::protocol::{AckResult, Arm, EventCode, Impulse, Message, SetThrottle};

/// Longest command line, characters.
pub const MAX_LINE: usize = 255;

/// Splits host text into command lines and parses them.
#[derive(Debug, Clone, Default)]
pub struct CsvReader {
    line: Vec<u8>,
    too_long: bool,
    seq: u16,
    stats: RxStats,
}

impl CsvReader {
    /// An empty reader.
    pub fn new() -> Self {
        Self::default()
    }

    /// Counters so far.
    pub fn stats(&self) -> RxStats {
        self.stats
    }

    /// Feeds host text; `on` gets every complete line, classified.
    pub fn push(&mut self, bytes: &[u8], mut on: impl FnMut(Incoming)) {
        for &b in bytes {
            match b {
                b'\r' => {}
                b'!' if self.line.is_empty() => self.finish_with(b"STOP", &mut on),
                b'\n' => {
                    let line = std::mem::take(&mut self.line);
                    if self.too_long {
                        self.too_long = false;
                        self.stats.garbage += 1;
                    } else if !line.is_empty() {
                        self.finish_with(&line, &mut on);
                    }
                }
                _ if self.line.len() >= MAX_LINE => self.too_long = true,
                _ => self.line.push(b),
            }
        }
    }

    fn finish_with(&mut self, line: &[u8], on: &mut impl FnMut(Incoming)) {
        self.seq = self.seq.wrapping_add(1);
        let inc = parse_line(self.seq, &String::from_utf8_lossy(line));
        match inc {
            Incoming::Command { .. } => self.stats.commands += 1,
            Incoming::Refused { .. } => self.stats.refused += 1,
            Incoming::Garbage => self.stats.garbage += 1,
        }
        on(inc);
    }
}

/// Parses one command line (numbered `seq`).
pub fn parse_line(seq: u16, line: &str) -> Incoming {
    let mut words = line.split_whitespace();
    let Some(cmd) = words.next() else {
        return Incoming::Garbage;
    };
    let args: Vec<&str> = words.collect();
    let (t, need) = match cmd.to_ascii_uppercase().as_str() {
        "PING" => (msg_type::HELLO_REQ, 0),
        "ARM" => (msg_type::ARM, 1),
        "DISARM" => (msg_type::DISARM, 0),
        "THR" => (msg_type::SET_THROTTLE, 1),
        "IMP" => (msg_type::IMPULSE, 2),
        "STOP" => (msg_type::STOP, 0),
        _ => {
            return Incoming::Refused {
                seq,
                msg_type: 0,
                result: AckResult::UnknownType,
            }
        }
    };
    let refuse = |result| Incoming::Refused {
        seq,
        msg_type: t,
        result,
    };
    if args.len() < need {
        return refuse(AckResult::BadLength);
    }
    let num = |i: usize| -> Option<u64> { args.get(i).map_or(Some(0), |a| a.parse().ok()) };
    let (Some(a0), Some(a1)) = (num(0), num(1)) else {
        return refuse(AckResult::OutOfRange);
    };
    let u16v = |v: u64| u16::try_from(v).ok();
    let msg = match t {
        msg_type::HELLO_REQ => Some(Message::HelloReq),
        msg_type::ARM => u16v(a0).map(|w| {
            Message::Arm(Arm {
                watchdog_ms: w,
                key: ARM_KEY,
            })
        }),
        msg_type::DISARM => Some(Message::Disarm),
        msg_type::SET_THROTTLE => u16v(a0)
            .zip(u16v(a1))
            .map(|(level, ramp_ms)| Message::SetThrottle(SetThrottle { level, ramp_ms })),
        msg_type::IMPULSE => u16v(a0)
            .zip(u32::try_from(a1).ok())
            .map(|(level, width_us)| Message::Impulse(Impulse { level, width_us })),
        _ => Some(Message::Stop),
    };
    match msg {
        Some(msg) => Incoming::Command { seq, msg },
        None => refuse(AckResult::OutOfRange),
    }
}

/// The CSV command word of a command type (for `#ACK` lines).
pub fn command_word(t: u8) -> &'static str {
    match t {
        msg_type::HELLO_REQ => "PING",
        msg_type::ARM => "ARM",
        msg_type::DISARM => "DISARM",
        msg_type::SET_THROTTLE => "THR",
        msg_type::IMPULSE => "IMP",
        msg_type::STOP => "STOP",
        _ => "?",
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
        let mut s = String::new();
        match msg {
            Message::Sample(x) => {
                let _ = write!(
                    s,
                    "{},{},{:.4},{:.5},{:.1},{:.3},{:.3}",
                    x.t_us, x.throttle, x.thrust_n, x.torque_nm, x.rpm, x.voltage_v, x.current_a
                );
                let sum = s.bytes().fold(0u8, |a, b| a ^ b);
                let _ = write!(s, "*{sum:02X}");
            }
            Message::Ack(a) => {
                let word = command_word(a.cmd_type);
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
}

/// Protocol name of an event code.
pub fn event_name(c: EventCode) -> &'static str {
    match c {
        EventCode::ImpulseStart => "IMPULSE_START",
        EventCode::ImpulseEnd => "IMPULSE_END",
        EventCode::WatchdogTrip => "WATCHDOG_TRIP",
        EventCode::LimitCutoff => "LIMIT_CUTOFF",
        EventCode::Armed => "ARMED",
        EventCode::Disarmed => "DISARMED",
        EventCode::TxOverrun => "TX_OVERRUN",
        EventCode::ResetCause => "RESET_CAUSE",
        EventCode::TareDone => "TARE_DONE",
        EventCode::Other(_) => "OTHER",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_wire::protocol::{Sample, SampleFlags};

    fn read(text: &str) -> Vec<Incoming> {
        let mut r = CsvReader::new();
        let mut v = Vec::new();
        r.push(text.as_bytes(), |i| v.push(i));
        v
    }

    #[test]
    fn commands_parse() {
        let got = read("PING\r\nARM 500\nTHR 3500 200\nIMP 4000 1000\n!DISARM\n");
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
            ]
        );
    }

    #[test]
    fn bad_lines_are_refused_with_a_reason() {
        let got = read("FLY\nIMP 4000\nTHR abc\n");
        let results: Vec<AckResult> = got
            .iter()
            .map(|i| match i {
                Incoming::Refused { result, .. } => *result,
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(
            results,
            vec![
                AckResult::UnknownType,
                AckResult::BadLength,
                AckResult::OutOfRange
            ]
        );
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
        let line = CsvWriter::new().format(&Message::Sample(s)).unwrap();
        let (body, rest) = line.trim_end().split_once('*').unwrap();
        assert!(body.starts_with("1000,3000,3.5000,"));
        let sum = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(rest, format!("{sum:02X}"));
    }
}
