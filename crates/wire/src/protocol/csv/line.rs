//! Lines and fields of the CSV dialect (PROTOCOL.md §6): the one rule for splitting text into
//! lines, checking a line's `*HH`, telling comments from data, choosing the separator and
//! splitting fields. The stream decoder, the simulated bench's command reader, format
//! detection and the file reader all use these.
//!
//! A line, in the order its rules apply:
//! 1. It ends in `\n`; `\r` is ignored. On a stream ([`LineSplitter`]) a line longer than the
//!    limit (255 characters by the protocol) is dropped whole; a file held in memory
//!    ([`text_lines`]) has no limit and keeps a `\r` inside a line (only one before the `\n`
//!    goes).
//! 2. Trailing white space is dropped; then an optional trailing `*HH` is the XOR of every byte
//!    before the `*`, in hex (as NMEA) — a wrong one drops the line ([`strip_checksum`]).
//! 3. What is left, without a UTF-8 byte-order mark and surrounding space, is empty (ignored),
//!    a `#` comment, or data ([`classify`]).
//! 4. Data fields are separated by `,`, else by tabs, else by `;` ([`separator`]); each field is
//!    trimmed and unquoted ([`fields`]). A line whose every `,` sits between two digits and that
//!    has a tab or a `;` is a decimal-comma line (the European spreadsheet export,
//!    `0,25;1503,2`): its separator is the tab or `;`.
//! 5. A number is what Rust's `f64` parser reads, or, in a line not separated by `,`, a decimal
//!    comma number (`-0,25`, `1503,2`: one `,` between digits, no `.`) ([`parse_number`]).
//!    A time-of-day or date-time stamp (`18:55:23.120`, `2024-08-13 18:55:23.120`,
//!    `2024-08-13T18:55:23Z`) is read as seconds by [`parse_clock`] where a column holds them.

/// Longest line the protocol allows, characters (without the newline).
pub const MAX_LINE: usize = 255;

/// The UTF-8 byte-order mark some exporters put before the first line.
const BOM: char = '\u{feff}';

/// A line as a [`LineSplitter`] hands it out.
#[derive(Debug, PartialEq, Eq)]
pub enum Line<'a> {
    /// A complete line (without `\n` and `\r`).
    Text(&'a [u8]),
    /// A line over the limit: dropped, only its end was seen.
    TooLong,
}

/// Splits a byte stream into lines into one buffer of fixed capacity (see the
/// [module documentation](self)).
#[derive(Debug, Clone)]
pub struct LineSplitter {
    line: Vec<u8>,
    max_line: usize,
    overflow: bool,
}

impl LineSplitter {
    /// A splitter for lines of at most `max_line` bytes; the buffer is allocated here, once.
    pub fn new(max_line: usize) -> Self {
        Self {
            line: Vec::with_capacity(max_line.min(1 << 16)),
            max_line,
            overflow: false,
        }
    }

    /// True when no part of a line is waiting for its `\n`.
    pub fn is_empty(&self) -> bool {
        self.line.is_empty() && !self.overflow
    }

    /// Feed bytes; `on_line` gets every line completed by a `\n`, in order.
    pub fn push(&mut self, bytes: &[u8], mut on_line: impl FnMut(Line<'_>)) {
        let mut rest = bytes;
        while let Some(i) = rest.iter().position(|&b| b == b'\n') {
            self.append(&rest[..i]);
            rest = &rest[i + 1..];
            self.end_line(&mut on_line);
        }
        self.append(rest);
    }

    /// End of input: a last line without `\n` is handed out.
    pub fn finish(&mut self, mut on_line: impl FnMut(Line<'_>)) {
        if !self.is_empty() {
            self.end_line(&mut on_line);
        }
    }

    fn append(&mut self, chunk: &[u8]) {
        if self.overflow {
            return;
        }
        for &b in chunk {
            if b == b'\r' {
                continue;
            }
            if self.line.len() >= self.max_line {
                self.overflow = true;
                return;
            }
            self.line.push(b);
        }
    }

    fn end_line(&mut self, on_line: &mut impl FnMut(Line<'_>)) {
        if self.overflow {
            on_line(Line::TooLong);
        } else {
            on_line(Line::Text(&self.line));
        }
        self.line.clear();
        self.overflow = false;
    }
}

/// The lines of a text held in memory, by the rule of [`LineSplitter`] without a length limit
/// (borrowed, so a `\r` is only dropped before the `\n`).
pub fn text_lines(text: &str) -> impl Iterator<Item = &str> {
    text.split('\n').map(|l| l.strip_suffix('\r').unwrap_or(l))
}

/// The `*HH` checksum of a line: XOR of its bytes.
pub fn checksum(line: &[u8]) -> u8 {
    line.iter().fold(0, |a, b| a ^ b)
}

/// `line` with the checksum `*HH` appended (`HH` upper-case hex), as a bench writes rows.
pub fn append_checksum(line: &mut String) {
    use std::fmt::Write as _;
    let sum = checksum(line.as_bytes());
    let _ = write!(line, "*{sum:02X}");
}

/// Checks and removes a trailing `*HH` (after trailing white space); `None` when it is present
/// and wrong. Lines without one pass unchanged.
pub fn strip_checksum(line: &[u8]) -> Option<&[u8]> {
    let line = line.trim_ascii_end();
    let n = line.len();
    if n >= 3 && line[n - 3] == b'*' {
        let hex = std::str::from_utf8(&line[n - 2..]).ok();
        if let Some(want) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
            return (checksum(&line[..n - 3]) == want).then_some(&line[..n - 3]);
        }
    }
    Some(line)
}

/// [`strip_checksum`] on text.
pub fn strip_checksum_str(line: &str) -> Option<&str> {
    // `*HH` is ASCII, so the kept bytes end on a character boundary.
    strip_checksum(line.as_bytes()).map(|b| &line[..b.len()])
}

/// What a line is (rules 2 and 3 of the [module documentation](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineKind<'a> {
    /// Nothing but space (or a BOM).
    Empty,
    /// A `#` line: the text after the `#`.
    Comment(&'a str),
    /// A header or data row, trimmed.
    Data(&'a str),
    /// A wrong `*HH`: dropped.
    BadChecksum,
    /// Not UTF-8 (binary noise): dropped.
    NotText,
}

/// Classifies one line (without its newline).
pub fn classify(raw: &[u8]) -> LineKind<'_> {
    let Some(body) = strip_checksum(raw) else {
        return LineKind::BadChecksum;
    };
    let Ok(text) = std::str::from_utf8(body) else {
        return LineKind::NotText;
    };
    classify_text(text)
}

/// [`classify`] for a line that is already text.
pub fn classify_str(raw: &str) -> LineKind<'_> {
    match strip_checksum_str(raw) {
        Some(text) => classify_text(text),
        None => LineKind::BadChecksum,
    }
}

fn classify_text(text: &str) -> LineKind<'_> {
    let text = text.trim_start_matches(BOM).trim();
    if text.is_empty() {
        LineKind::Empty
    } else if let Some(c) = text.strip_prefix('#') {
        LineKind::Comment(c)
    } else {
        LineKind::Data(text)
    }
}

/// Field separator of a data line: `,`, else tab, else `;` — unless every `,` of the line is a
/// decimal comma (between two digits) and it has a tab or a `;` (rule 4 of the
/// [module documentation](self)).
pub fn separator(text: &str) -> char {
    let other = text.contains('\t') || text.contains(';');
    if text.contains(',') && !(other && all_commas_decimal(text)) {
        ','
    } else if text.contains('\t') {
        '\t'
    } else {
        ';'
    }
}

/// True when every `,` of `text` has an ASCII digit on both sides.
fn all_commas_decimal(text: &str) -> bool {
    let b = text.as_bytes();
    b.iter()
        .enumerate()
        .filter(|(_, &c)| c == b',')
        .all(|(i, _)| {
            i > 0 && b[i - 1].is_ascii_digit() && b.get(i + 1).is_some_and(u8::is_ascii_digit)
        })
}

/// A field as a number (rule 5 of the [module documentation](self)): Rust's `f64` syntax, or,
/// when the line's separator `sep` is not `,`, a decimal comma (`-0,25`: one `,` between two
/// digits, no `.`). `None` for anything else (text, a thousands separator `1.234,5`).
pub fn parse_number(field: &str, sep: char) -> Option<f64> {
    if let Ok(v) = field.parse() {
        return Some(v);
    }
    if sep == ',' || field.contains('.') || field.matches(',').count() != 1 {
        return None;
    }
    if !all_commas_decimal(field) {
        return None;
    }
    field.replacen(',', ".", 1).parse().ok()
}

/// A time stamp as seconds: `HH:MM:SS[.fff]` (seconds of the day) or
/// `YYYY-MM-DD[T| ]HH:MM:SS[.fff][Z]` (seconds since 1970-01-01, UTC as written: no time zone
/// is applied). A decimal comma is accepted in the seconds. `None` for anything else.
pub fn parse_clock(field: &str) -> Option<f64> {
    let field = field.strip_suffix('Z').unwrap_or(field);
    let (date, time) = match field.split_once(['T', ' ']) {
        Some((d, t)) => (Some(d), t.trim()),
        None => (None, field),
    };
    let mut hms = time.split(':');
    let h: u32 = hms.next()?.parse().ok()?;
    let m: u32 = hms.next()?.parse().ok()?;
    let sec = hms.next()?.replacen(',', ".", 1);
    let sec: f64 = sec.parse().ok()?;
    if hms.next().is_some() || h > 23 || m > 59 || !(0.0..61.0).contains(&sec) {
        return None;
    }
    let day_s = f64::from(h * 3600 + m * 60) + sec;
    let Some(date) = date else {
        return Some(day_s);
    };
    let mut ymd = date.split('-');
    let y: i64 = ymd.next()?.parse().ok()?;
    let mo: u32 = ymd.next()?.parse().ok()?;
    let d: u32 = ymd.next()?.parse().ok()?;
    if ymd.next().is_some() || !(1..=12).contains(&mo) || !(1..=31).contains(&d) {
        return None;
    }
    Some(days_from_civil(y, mo, d) as f64 * 86_400.0 + day_s)
}

/// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant, "chrono-Compatible
/// Low-Level Date Algorithms", `days_from_civil`).
fn days_from_civil(y: i64, m: u32, d: u32) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = i64::from((m + 9) % 12);
    let doy = (153 * mp + 2) / 5 + i64::from(d) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The fields of a data line, trimmed and unquoted.
pub fn fields(text: &str, sep: char) -> impl Iterator<Item = &str> {
    text.split(sep).map(|f| f.trim().trim_matches('"').trim())
}

/// True when every field is empty or a number ([`parse_number`]): a data row, not a header.
pub fn is_numeric(text: &str, sep: char) -> bool {
    fields(text, sep).all(|f| f.is_empty() || parse_number(f, sep).is_some())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(max: usize, chunks: &[&[u8]]) -> Vec<String> {
        let mut s = LineSplitter::new(max);
        let mut out = Vec::new();
        let mut on = |l: Line<'_>| {
            out.push(match l {
                Line::Text(t) => String::from_utf8_lossy(t).into_owned(),
                Line::TooLong => "<too long>".into(),
            })
        };
        for c in chunks {
            s.push(c, &mut on);
        }
        s.finish(&mut on);
        out
    }

    #[test]
    fn lines_split_across_chunks_drop_cr_and_overlong_ones() {
        assert_eq!(
            lines(5, &[b"ab\r", b"c\n12345\n123456\nx\r\ny"]),
            ["abc", "12345", "<too long>", "x", "y"]
        );
        assert_eq!(lines(5, &[b"", b"\n"]), [""]);
        let t: Vec<&str> = text_lines("a\r\nb\rc\n\nd").collect();
        assert_eq!(t, ["a", "b\rc", "", "d"]);
    }

    #[test]
    fn checksums_comments_and_data() {
        let mut row = "1000,3500,1.25".to_string();
        append_checksum(&mut row);
        assert_eq!(
            row,
            format!("1000,3500,1.25*{:02X}", checksum(b"1000,3500,1.25"))
        );
        assert_eq!(classify(row.as_bytes()), LineKind::Data("1000,3500,1.25"));
        assert_eq!(
            classify(format!("{row}  ").as_bytes()),
            LineKind::Data("1000,3500,1.25")
        );
        let bad = format!("{}0", &row[..row.len() - 1]);
        assert_eq!(classify(bad.as_bytes()), LineKind::BadChecksum);
        assert_eq!(
            classify(b"#ACK PING OK 1"),
            LineKind::Comment("ACK PING OK 1")
        );
        assert_eq!(
            classify_str("\u{feff} t_s,thrust_N "),
            LineKind::Data("t_s,thrust_N")
        );
        assert_eq!(classify(b"  "), LineKind::Empty);
        assert_eq!(classify(&[0xff, 0x31]), LineKind::NotText);
        // not hex: no checksum, the text stays
        assert_eq!(classify(b"a*zz"), LineKind::Data("a*zz"));
    }

    #[test]
    fn separators_and_fields() {
        assert_eq!(separator("a;b,c"), ',');
        // Decimal commas in a `;` line (see `decimal_commas_in_semicolon_and_tab_lines`).
        assert_eq!(separator("1;2,3"), ';');
        assert_eq!(separator("1;2\t3"), '\t');
        assert_eq!(separator("1;2"), ';');
        let f: Vec<&str> = fields(" \"Time (s)\" , 2 ,", ',').collect();
        assert_eq!(f, ["Time (s)", "2", ""]);
        assert!(is_numeric("1,,2.5", ','));
        assert!(!is_numeric("1,x", ','));
    }

    #[test]
    fn decimal_commas_in_semicolon_and_tab_lines() {
        // Every comma between digits, with a `;` or a tab: the commas are decimal.
        assert_eq!(separator("0,010;30,5;-1,25"), ';');
        assert_eq!(separator("0,010\t30,5"), '\t');
        assert_eq!(separator("Time (s);Thrust (g)"), ';');
        // A comma that is not between digits, or no other separator: a comma file.
        assert_eq!(separator("a, b;c"), ',');
        assert_eq!(separator("1,5"), ',');
        assert_eq!(parse_number("-0,25", ';'), Some(-0.25));
        assert_eq!(parse_number("1503,2", '\t'), Some(1503.2));
        assert_eq!(parse_number("2.5", ';'), Some(2.5));
        // Not in a comma file, not a thousands separator, not two commas, not a lone comma.
        assert_eq!(parse_number("0,25", ','), None);
        assert_eq!(parse_number("1.234,5", ';'), None);
        assert_eq!(parse_number("1,2,3", ';'), None);
        assert_eq!(parse_number(",5", ';'), None);
        assert!(is_numeric("0,010;30,5;", ';'));
        assert!(!is_numeric("0,010;x", ';'));
    }

    #[test]
    fn clock_stamps_as_seconds() {
        assert_eq!(parse_clock("18:55:23.5"), Some(68_123.5));
        assert_eq!(parse_clock("1970-01-02 00:00:01"), Some(86_401.0));
        assert_eq!(parse_clock("2000-03-01T00:00:00Z"), Some(951_868_800.0));
        let a = parse_clock("2024-08-13 18:55:23,120").unwrap();
        let b = parse_clock("2024-08-13T18:55:24.130").unwrap();
        assert!((b - a - 1.01).abs() < 1e-6, "{}", b - a);
        for bad in ["18:55", "25:00:00", "2024-13-01 00:00:00", "12.5", "a:b:c"] {
            assert_eq!(parse_clock(bad), None, "{bad}");
        }
    }
}
