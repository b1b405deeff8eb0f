//! `protocol = "auto"`: binary TSP/1 or the CSV fallback, decided from the first bytes.
//!
//! The rule (over the first [`DETECT_WINDOW`] bytes, after an optional UTF-8 BOM):
//! 1. A valid TSP/1 frame (COBS, CRC, version, known type) ends in the window → **binary**.
//! 2. No `0x00` in the window and a complete line that is CSV data by the dialect's line rules
//!    ([`classify`]: `*HH` checked, comments skipped) — numeric fields (at least two) or a
//!    header naming a known column — → **CSV**. Text never holds `0x00`, while a binary
//!    stream has a delimiter at least every 255 bytes; boot banners are text but neither
//!    numeric rows nor headers, so a banner before binary frames does not decide.
//! 3. The window is full (or the input has ended): a `0x00` seen → binary (a damaged binary
//!    stream; its decoder counts the drops), none → CSV.
//! 4. Otherwise: undecided, read more.

use super::csv::columns;
use super::csv::device::parse_comment;
use super::csv::line::{
    byte_lines, classify, fields, is_number, separator, strip_checksum_str, text_lines, LineKind,
};
use super::decoder::Decoder;

/// Bytes examined at most.
pub const DETECT_WINDOW: usize = 1024;

/// Which wire format a stream speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum WireFormat {
    /// COBS-framed binary TSP/1.
    Binary,
    /// The CSV text fallback.
    Csv,
}

/// Outcome of [`detect`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detection {
    /// Decided.
    Format(WireFormat),
    /// More bytes are needed.
    Undecided,
}

/// Decide the wire format from the first bytes of a stream; `at_end` says the input has no more
/// bytes (a short file). See the module documentation for the rule.
pub fn detect(prefix: &[u8], at_end: bool) -> Detection {
    let p = prefix.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(prefix);
    let window = &p[..p.len().min(DETECT_WINDOW)];
    let mut dec = Decoder::new();
    let mut binary = false;
    dec.push(window, |_| binary = true);
    if binary {
        return Detection::Format(WireFormat::Binary);
    }
    let has_zero = window.contains(&0);
    // The complete lines: all but the text after the last line end.
    let lines: Vec<&[u8]> = byte_lines(window).collect();
    let complete = &lines[..lines.len() - 1];
    if !has_zero && complete.iter().any(|l| is_csv_line(l)) {
        return Detection::Format(WireFormat::Csv);
    }
    if at_end || window.len() >= DETECT_WINDOW {
        let f = if has_zero {
            WireFormat::Binary
        } else {
            WireFormat::Csv
        };
        return Detection::Format(f);
    }
    Detection::Undecided
}

/// A complete line that is a CSV data row or header.
fn is_csv_line(line: &[u8]) -> bool {
    let LineKind::Data(text) = classify(line) else {
        return false;
    };
    let (mut numeric, mut blank, mut known, mut n) = (0, 0, false, 0);
    let sep = separator(text);
    for f in fields(text, sep) {
        let f = f.as_ref();
        n += 1;
        numeric += usize::from(is_number(f));
        blank += usize::from(f.is_empty());
        known |= columns::lookup(f).is_some();
    }
    (numeric >= 2 && numeric + blank == n) || known
}

/// Bytes of a file examined by [`is_csv_stream`].
pub const STREAM_LOOK: usize = 64 * 1024;

/// True when CSV text is a TSP/1 CSV *stream* as a bench sends it (docs/PROTOCOL.md §6; what
/// `propid run --record` writes of a CSV bench), not an exported log: among its first lines one
/// carries a `*HH` checksum that checks, or is a comment only a bench writes (`# HELLO`,
/// `#EVENT`, `#ACK`). A stream is placed by the stream placer ([`crate::stream`]) like a live
/// link; an exported log is read by its own time column.
pub fn is_csv_stream(bytes: &[u8]) -> bool {
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(STREAM_LOOK)]);
    let stream = text_lines(&text).take(1000).any(|line| {
        let t = line.trim_end();
        let checked = t.len() >= 3
            && t.as_bytes()[t.len() - 3] == b'*'
            && strip_checksum_str(t).is_some_and(|body| body.len() + 3 == t.len());
        let comment = t.trim_start().strip_prefix('#').map(str::trim_start);
        checked || comment.is_some_and(|c| c.starts_with("ACK ") || parse_comment(c).is_some())
    });
    stream
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{encode_frame, Message, MAX_FRAME_LEN};

    const CSV: Detection = Detection::Format(WireFormat::Csv);
    const BIN: Detection = Detection::Format(WireFormat::Binary);

    #[test]
    fn binary_after_a_banner() {
        let mut s = b"Booting stand fw 1.2\r\nready\r\n".to_vec();
        assert_eq!(detect(&s, false), Detection::Undecided);
        let mut f = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(1, &Message::Heartbeat, &mut f);
        // The banner runs into the first frame (no 0x00 between them): that frame is lost,
        // the next one decides.
        s.extend_from_slice(&f[..n]);
        assert_eq!(detect(&s, false), Detection::Undecided);
        s.extend_from_slice(&f[..n]);
        assert_eq!(detect(&s, false), BIN);
    }

    #[test]
    fn csv_rows_and_headers() {
        assert_eq!(detect(b"1000,3500,1.25\n", false), CSV);
        assert_eq!(detect(b"1000,3500,1.25*1F\n", false), CSV);
        assert_eq!(detect(b"1;3500;1.25\n", false), CSV);
        // a classic Mac text: lines end in CR alone
        assert_eq!(detect(b"1000,3500,1.25\r", false), CSV);
        assert_eq!(detect(b"\xEF\xBB\xBFTime (s),Thrust (N)\n", false), CSV);
        assert_eq!(detect(b"# banner\n1000,35", false), Detection::Undecided);
        assert_eq!(detect(b"# banner only", true), CSV);
    }

    #[test]
    fn garbage_with_zeros_is_binary_when_the_window_is_full() {
        let g: Vec<u8> = (0..2000u32).map(|i| (i * 7 % 251) as u8).collect();
        assert_eq!(detect(&g, false), BIN);
        assert_eq!(detect(&[0x05, 0x00, 0x07], false), Detection::Undecided);
        assert_eq!(detect(&[0x05, 0x00, 0x07], true), BIN);
        assert_eq!(detect(&[b'x'; 1024], false), CSV);
    }

    #[test]
    fn csv_streams_are_told_from_exported_logs() {
        let mut row = String::from("1000,3000,1.25");
        crate::protocol::csv::line::append_checksum(&mut row);
        assert!(is_csv_stream(format!("{row}\n").as_bytes()));
        assert!(is_csv_stream(
            b"# HELLO sim fw 3 boot_id 1 rate_hz 1000\n1000,3000,1.25\n"
        ));
        assert!(is_csv_stream(b"#ACK PING OK 1527156\n"));
        assert!(!is_csv_stream(b"Time (s),Thrust (N)\n0.0,1.2\n0.1,1.3\n"));
        // a wrong checksum or a plain comment makes no stream
        assert!(!is_csv_stream(
            b"1000,3000,1.25*00\n# exported by a stand\n"
        ));
    }
}
