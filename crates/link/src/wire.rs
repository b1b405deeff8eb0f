//! The sampler's wire format: binary TSP/1, the CSV fallback, or not decided yet.
//!
//! `[device] protocol = "auto"` holds the first bytes (at most [`DETECT_WINDOW`]) until
//! [`detect`] decides, then hands them, and everything after, to the chosen decoder: nothing is
//! decoded twice or lost. `"tsp"` and `"csv"` decide before the first byte. Both decoders give
//! TSP/1 [`Frame`]s (the CSV one through [`CsvLink`]), and commands are encoded for the wire in
//! use, so the sampler, the experiment plan and the worker are the same for both.

use super::csv_link::{CsvLink, CsvLinkOptions};
use propid_wire::protocol::detect::{detect, Detection, WireFormat, DETECT_WINDOW};
use propid_wire::protocol::message::{Frame, Message};
use propid_wire::protocol::{encode_frame, Decoder};

/// `[device] protocol`: which wire format the daemon expects (docs/PROTOCOL.md §6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WireProtocol {
    /// Decide from the first bytes ([`propid_wire::protocol::detect`]).
    Auto,
    /// Binary TSP/1 only.
    Tsp,
    /// The CSV fallback (read through [`super::csv_link`]).
    Csv,
}

/// The decoder of a link.
pub enum Wire {
    /// `protocol = "auto"` before the first bytes decided.
    Undecided {
        /// The bytes so far (at most [`DETECT_WINDOW`]).
        prefix: Vec<u8>,
        /// How to read CSV if it is CSV.
        csv: CsvLinkOptions,
    },
    /// Binary TSP/1.
    Tsp(Box<Decoder>),
    /// The CSV fallback.
    Csv(Box<CsvLink>),
}

/// Names of the drop counters of both wire formats (`frames_dropped` always has them all).
pub const DROP_KINDS: [&str; 13] = [
    "cobs_error",
    "crc_error",
    "bad_version",
    "short_frame",
    "short_payload",
    "oversize",
    "unknown_type",
    "line_too_long",
    "bad_checksum",
    "bad_row",
    "row_out_of_order",
    "row_without_time",
    "hello_unconfirmed",
];

impl Wire {
    /// The wire for a configured protocol.
    pub fn new(protocol: WireProtocol, csv: CsvLinkOptions) -> Wire {
        match protocol {
            WireProtocol::Auto => Wire::Undecided {
                prefix: Vec::with_capacity(DETECT_WINDOW),
                csv,
            },
            WireProtocol::Tsp => Wire::Tsp(Box::default()),
            WireProtocol::Csv => Wire::Csv(Box::new(CsvLink::new(csv))),
        }
    }

    /// The format in use (`None` while undecided).
    pub fn format(&self) -> Option<WireFormat> {
        match self {
            Wire::Undecided { .. } => None,
            Wire::Tsp(_) => Some(WireFormat::Binary),
            Wire::Csv(_) => Some(WireFormat::Csv),
        }
    }

    /// `"tsp"`, `"csv"` or `"undecided"` (for the stats line).
    pub fn name(&self) -> &'static str {
        match self.format() {
            None => "undecided",
            Some(WireFormat::Binary) => "tsp",
            Some(WireFormat::Csv) => "csv",
        }
    }

    /// Bytes in, frames out, each with the wire it came on (a HELLO's rate of 0 means a
    /// different thing on each: [`SampleAssembler::hello`](propid_wire::stream::SampleAssembler::hello)).
    /// Returns the format when these bytes decided it.
    pub fn push(
        &mut self,
        bytes: &[u8],
        on_frame: &mut impl FnMut(Frame, WireFormat),
    ) -> Option<WireFormat> {
        match self {
            Wire::Tsp(d) => {
                d.push(bytes, |f| on_frame(f, WireFormat::Binary));
                None
            }
            Wire::Csv(c) => {
                c.push(bytes, &mut |f| on_frame(f, WireFormat::Csv));
                None
            }
            Wire::Undecided { prefix, .. } => {
                let take = (DETECT_WINDOW - prefix.len()).min(bytes.len());
                prefix.extend_from_slice(&bytes[..take]);
                let format = match detect(prefix, false) {
                    Detection::Undecided => return None,
                    Detection::Format(f) => f,
                };
                self.decide(format, on_frame);
                self.push(&bytes[take..], on_frame);
                Some(format)
            }
        }
    }

    /// End of input: an undecided prefix is decided on what there is, rows the CSV link holds
    /// are handed on. Returns the format when this decided it.
    pub fn finish(&mut self, on_frame: &mut impl FnMut(Frame, WireFormat)) -> Option<WireFormat> {
        let mut decided = None;
        if let Wire::Undecided { prefix, .. } = self {
            if prefix.is_empty() {
                return None;
            }
            if let Detection::Format(f) = detect(prefix, true) {
                self.decide(f, on_frame);
                decided = Some(f);
            }
        }
        if let Wire::Csv(c) = self {
            c.finish(&mut |f| on_frame(f, WireFormat::Csv));
        }
        decided
    }

    fn decide(&mut self, format: WireFormat, on_frame: &mut impl FnMut(Frame, WireFormat)) {
        let Wire::Undecided { prefix, csv } = self else {
            return;
        };
        let prefix = std::mem::take(prefix);
        *self = match format {
            WireFormat::Binary => Wire::Tsp(Box::default()),
            WireFormat::Csv => Wire::Csv(Box::new(CsvLink::new(*csv))),
        };
        self.push(&prefix, on_frame);
    }

    /// Writes a command for the wire in use into `out`; `None` when the CSV fallback has no form
    /// for it (only SET_RATE and TARE, which the plan does not send).
    pub fn encode(&mut self, seq: u16, msg: &Message, out: &mut [u8]) -> Option<usize> {
        match self {
            Wire::Csv(c) => c.encode_command(seq, msg, out).ok(),
            _ => Some(encode_frame(seq, msg, out)),
        }
    }

    /// ACK lines a CSV bench sent (0 for binary: there the plan sees every ACK itself).
    pub fn csv_acks(&self) -> u64 {
        match self {
            Wire::Csv(c) => c.stats().acks,
            _ => 0,
        }
    }

    /// Frames (binary) or lines (CSV) that decoded.
    pub fn frames_ok(&self) -> u64 {
        match self {
            Wire::Tsp(d) => d.stats().frames_ok,
            Wire::Csv(c) => c.lines_ok(),
            Wire::Undecided { .. } => 0,
        }
    }

    /// Empty binary frames (two 0x00 delimiters in a row): ignored by the protocol, counted so
    /// that a stream of zero bytes is never silent.
    pub fn empty_frames(&self) -> u64 {
        match self {
            Wire::Tsp(d) => d.stats().empty_frames,
            _ => 0,
        }
    }

    /// Every drop counter of [`DROP_KINDS`], in that order (zeros for the other format).
    pub fn dropped(&self) -> [(&'static str, u64); 13] {
        let mut out = DROP_KINDS.map(|k| (k, 0));
        let mut set = |k: &str, v: u64| {
            if let Some(slot) = out.iter_mut().find(|s| s.0 == k) {
                slot.1 = v;
            }
        };
        match self {
            Wire::Tsp(d) => {
                let dr = &d.stats().dropped;
                set("cobs_error", dr.cobs_error);
                set("crc_error", dr.crc_error);
                set("bad_version", dr.bad_version);
                set("short_frame", dr.short_frame);
                set("short_payload", dr.short_payload);
                set("oversize", dr.oversize);
                set("unknown_type", dr.unknown_type);
            }
            Wire::Csv(c) => {
                for (k, v) in c.dropped() {
                    set(k, v);
                }
            }
            Wire::Undecided { .. } => {}
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_wire::protocol::message::Message;

    fn push_in_chunks(wire: &mut Wire, bytes: &[u8], chunk: usize) -> (Vec<Frame>, usize) {
        let mut frames = Vec::new();
        let mut decisions = 0;
        for c in bytes.chunks(chunk) {
            decisions += wire.push(c, &mut |f, _| frames.push(f)).is_some() as usize;
        }
        decisions += wire.finish(&mut |f, _| frames.push(f)).is_some() as usize;
        (frames, decisions)
    }

    #[test]
    fn auto_loses_no_byte_while_deciding_in_any_chunking() {
        let mut tsp = Vec::new();
        let mut buf = [0u8; 300];
        for seq in 0..200u16 {
            let n = encode_frame(seq, &Message::Heartbeat, &mut buf);
            tsp.extend_from_slice(&buf[..n]);
        }
        let mut csv = String::from("t_us,throttle,thrust_N\n");
        for k in 0..300 {
            csv += &format!("{},3000,1.5\n", k * 1000);
        }
        for chunk in [1, 7, 1000, 5000] {
            let mut w = Wire::new(WireProtocol::Auto, CsvLinkOptions::default());
            let (frames, decisions) = push_in_chunks(&mut w, &tsp, chunk);
            assert_eq!((w.name(), decisions, frames.len()), ("tsp", 1, 200));
            assert_eq!(w.frames_ok(), 200);
            let mut w = Wire::new(WireProtocol::Auto, CsvLinkOptions::default());
            let (frames, decisions) = push_in_chunks(&mut w, csv.as_bytes(), chunk);
            assert_eq!((w.name(), decisions, frames.len()), ("csv", 1, 300));
            assert_eq!(w.frames_ok(), 301);
            assert!(w.dropped().iter().all(|d| d.1 == 0));
        }
    }

    #[test]
    fn commands_are_written_for_the_wire_in_use() {
        let mut out = [0u8; 300];
        let mut w = Wire::new(WireProtocol::Csv, CsvLinkOptions::default());
        let n = w.encode(3, &Message::Stop, &mut out).unwrap();
        assert_eq!(&out[..n], b"STOP\n");
        let mut w = Wire::new(WireProtocol::Tsp, CsvLinkOptions::default());
        let n = w.encode(3, &Message::Stop, &mut out).unwrap();
        assert_eq!(out[n - 1], 0, "a COBS frame ends in 0x00");
        let mut w = Wire::new(WireProtocol::Auto, CsvLinkOptions::default());
        assert!(w.encode(3, &Message::Stop, &mut out).is_some());
        assert_eq!(w.format(), None);
    }
}
