//! Lines and fields of the CSV dialect (docs/PROTOCOL.md §6): the one rule for splitting text into
//! lines, checking a line's `*HH`, telling comments from data, choosing the separator and
//! splitting fields. The stream decoder, the simulated bench's command reader, format
//! detection and the file reader all use these.
//!
//! A line, in the order its rules apply:
//! 1. It ends in `\n`, `\r\n` or a lone `\r` (a classic Mac text, Excel for Mac's "CSV
//!    (Macintosh)"): every `\r` ends a line, a `\n` right after it belongs to the same line
//!    end. On a stream ([`LineSplitter`]) a line longer than the limit (255 characters by the
//!    protocol) is dropped whole; a file held in memory ([`text_lines`], [`byte_lines`]) has
//!    no limit.
//! 2. Trailing white space is dropped; then an optional trailing `*HH` is the XOR of every byte
//!    before the `*`, in hex (as NMEA) — a wrong one drops the line ([`strip_checksum`]).
//! 3. What is left, without a UTF-8 byte-order mark and surrounding space, is empty (ignored),
//!    a `#` comment, or data ([`classify`]).
//! 4. Data fields are separated by `,`, else by tabs, else by `;` ([`separator`]), outside
//!    quoted fields; each field is trimmed and unquoted ([`fields`]). A line whose every `,`
//!    (outside quoted fields) sits between two digits and that has a tab or a `;` is a
//!    decimal-comma or thousands line (the European spreadsheet export `0,25;1503,2`, or
//!    `1,234.5\t0.45`): its separator is the tab or `;`.
//!
//!    Quoting is RFC 4180's, read leniently (one rule, [`split_field`]):
//!    - a `"` **opens** a quoted field only as the field's first character (after spaces);
//!      the quoted field keeps separators as they are (`"0,45"`, `"a;b"`), and `""` inside it
//!      is one `"` (`"Thrust ""gf"""` is `Thrust "gf"`);
//!    - the first lone `"` **closes** it; text after the closing quote up to the separator is
//!      kept, appended (`"5" prop` is `5 prop`);
//!    - a `"` anywhere else is an ordinary character: an inch mark (`Prop 5"x4.5`,
//!      `Torque (in-oz")`) stays in its field and never joins the fields after it;
//!    - a `"` that opens a field but is never closed on its line is an ordinary character too
//!      (`"10x4.5` is the field `"10x4.5`, ending at the next separator): a stray quote cannot
//!      swallow the rest of the line into one field. A field never continues on the next line.
//! 5. A number is written with a decimal mark, `.` or `,`, and may group thousands with the
//!    other mark (`1,234.5`, `1.234,5`, `12,345`): [`DecimalMark`] reads a field both ways. A
//!    field only one mark reads (`0,45`, `1.234,5`, `12,3`; `0.45`, `1,234.5`) shows the
//!    file's mark; `1,234` and `1.234` (one mark, then exactly three digits) are read with the
//!    mark the file's other fields show ([`DecimalMark::of_fields`]); where they show none, as
//!    a decimal (`1,234` is 1.234): thousands are read only where the file shows the other
//!    mark, and a plain `,`-separated file, whose fields hold no `,`, never reads a `.` as
//!    thousands ([`parse_number`]).
//!    A time-of-day or date-time stamp (`18:55:23.120`, `2024-08-13 18:55:23.120`,
//!    `2024-08-13T18:55:23Z`) is read as seconds by [`parse_clock`] where a column holds them;
//!    read in order ([`ClockColumn`]), a time of day that falls back by more than 12 h has
//!    passed midnight (23:59:59.9 then 00:00:00.1 is 0.2 s later).

use std::borrow::Cow;

mod clock;
mod number;
pub use clock::{parse_clock, ClockColumn};
pub use number::{
    is_cell_number, is_missing_marker, is_number, parse_cell, parse_number, DecimalMark,
    MISSING_MARKERS,
};

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
    /// The last byte pushed was a `\r` that ended a line: a `\n` next is part of its end.
    after_cr: bool,
}

impl LineSplitter {
    /// A splitter for lines of at most `max_line` bytes; the buffer is allocated here, once.
    pub fn new(max_line: usize) -> Self {
        Self {
            line: Vec::with_capacity(max_line.min(1 << 16)),
            max_line,
            overflow: false,
            after_cr: false,
        }
    }

    /// True when no part of a line is waiting for its `\n`.
    pub fn is_empty(&self) -> bool {
        self.line.is_empty() && !self.overflow
    }

    /// Feed bytes; `on_line` gets every line completed by a `\n`, `\r\n` or `\r`, in order
    /// (a `\r\n` split between two pushes is one line end).
    pub fn push(&mut self, bytes: &[u8], mut on_line: impl FnMut(Line<'_>)) {
        let mut rest = bytes;
        if self.after_cr && !rest.is_empty() {
            rest = rest.strip_prefix(b"\n").unwrap_or(rest);
            self.after_cr = false;
        }
        while let Some(i) = rest.iter().position(|&b| b == b'\n' || b == b'\r') {
            self.append(&rest[..i]);
            let cr = rest[i] == b'\r';
            rest = &rest[i + 1..];
            self.end_line(&mut on_line);
            if cr {
                match rest.strip_prefix(b"\n") {
                    Some(r) => rest = r,
                    None => self.after_cr = rest.is_empty(),
                }
            }
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
        if self.line.len() + chunk.len() > self.max_line {
            self.overflow = true;
            return;
        }
        self.line.extend_from_slice(chunk);
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

/// The lines of a text held in memory, by the rule of [`LineSplitter`] without a length limit:
/// ended by `\n`, `\r\n` or `\r`; the text after the last line end is a last line (empty
/// when the text ends in a line end).
pub fn text_lines(text: &str) -> impl Iterator<Item = &str> {
    let mut rest = Some(text);
    std::iter::from_fn(move || {
        let r = rest?;
        // Line ends are ASCII: both indices are character boundaries.
        let (line, next) = line_end(r.as_bytes());
        rest = next.map(|n| &r[n..]);
        Some(&r[..line])
    })
}

/// [`text_lines`] on bytes (a text not decoded yet: the line ends are the same bytes in UTF-8
/// and in Windows-1252).
pub fn byte_lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut rest = Some(bytes);
    std::iter::from_fn(move || {
        let r = rest?;
        let (line, next) = line_end(r);
        rest = next.map(|n| &r[n..]);
        Some(&r[..line])
    })
}

/// The length of the first line of `b`, and where the next starts (`None`: no line end).
fn line_end(b: &[u8]) -> (usize, Option<usize>) {
    match b.iter().position(|&c| c == b'\n' || c == b'\r') {
        Some(i) if b[i..].starts_with(b"\r\n") => (i, Some(i + 2)),
        Some(i) => (i, Some(i + 1)),
        None => (b.len(), None),
    }
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

/// Field separator of a data line: `,`, else tab, else `;`, counting only those outside quoted
/// fields — unless every such `,` has a digit on both sides (a decimal comma or a thousands
/// separator) and the line has a tab or a `;` (rule 4 of the [module documentation](self)).
/// While the separator is not known, a field may start after any of the three.
pub fn separator(text: &str) -> char {
    let b = text.as_bytes();
    let (mut comma, mut tab, mut semicolon, mut digit_commas) = (false, false, false, true);
    let mut start = 0;
    while let (_, Some(i)) = split_field(&text[start..], is_candidate) {
        let i = start + i;
        match b[i] {
            b',' => {
                comma = true;
                digit_commas &= between_digits(b, i);
            }
            b'\t' => tab = true,
            _ => semicolon = true,
        }
        start = i + 1;
    }
    if comma && !((tab || semicolon) && digit_commas) {
        ','
    } else if tab {
        '\t'
    } else {
        ';'
    }
}

/// A character [`separator`] may choose.
fn is_candidate(c: char) -> bool {
    matches!(c, ',' | '\t' | ';')
}

/// True when byte `i` of `b` has an ASCII digit on both sides.
pub(crate) fn between_digits(b: &[u8], i: usize) -> bool {
    i > 0 && b[i - 1].is_ascii_digit() && b.get(i + 1).is_some_and(u8::is_ascii_digit)
}

/// How the first field of a line's rest is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Span {
    /// Unquoted: every `"` in it is an ordinary character.
    Plain,
    /// Quoted: the content is `rest[open + 1..close]` (`""` still doubled), the text after the
    /// closing quote `rest[close + 1..]` up to the separator.
    Quoted { open: usize, close: usize },
}

/// The first field of `rest` by the quoting of rule 4 of the [module documentation](self):
/// how it is written, and the byte index of the separator that ends it (`None`: it is the
/// line's last field). A `"` opens a quoted field only as the field's first character after
/// spaces, and only when a lone `"` closes it on the line; `""` inside is an escaped quote.
///
/// Linear in the line: a search for the closing quote that fails leaves only runs of an even
/// number of `"` after the opening one, so any later field's opening quote (the first of its
/// run) is closed within its run.
fn split_field(rest: &str, is_sep: impl Fn(char) -> bool) -> (Span, Option<usize>) {
    let b = rest.as_bytes();
    // Spaces before the quote; a tab too unless it is the separator.
    let blank = |c: char| (c == ' ' || c == '\t') && !is_sep(c);
    let open = rest.len() - rest.trim_start_matches(blank).len();
    let mut span = Span::Plain;
    let mut from = 0;
    if b.get(open) == Some(&b'"') {
        let mut i = open + 1;
        while i < b.len() {
            match (b[i], b.get(i + 1)) {
                (b'"', Some(b'"')) => i += 2,
                (b'"', _) => {
                    span = Span::Quoted { open, close: i };
                    from = i + 1;
                    break;
                }
                _ => i += 1,
            }
        }
    }
    let end = rest[from..]
        .char_indices()
        .find(|&(_, c)| is_sep(c))
        .map(|(i, _)| from + i);
    (span, end)
}

/// The fields of a data line, split at `sep` outside quoted fields, trimmed and unquoted (rule
/// 4 of the [module documentation](self)). A field is borrowed from the line unless it holds an
/// escaped quote (`""`) or text after its closing quote.
pub fn fields(text: &str, sep: char) -> Fields<'_> {
    Fields {
        rest: Some(text),
        sep,
    }
}

/// The iterator of [`fields`] (no allocation for plain and simply quoted fields: the stream
/// decoder splits every row with it).
#[derive(Debug, Clone)]
pub struct Fields<'a> {
    rest: Option<&'a str>,
    sep: char,
}

impl<'a> Iterator for Fields<'a> {
    type Item = Cow<'a, str>;

    fn next(&mut self) -> Option<Cow<'a, str>> {
        let rest = self.rest?;
        let sep = self.sep;
        let (span, end) = split_field(rest, |c| c == sep);
        let field = match end {
            Some(i) => {
                self.rest = Some(&rest[i + sep.len_utf8()..]);
                &rest[..i]
            }
            None => {
                self.rest = None;
                rest
            }
        };
        Some(match span {
            Span::Plain => Cow::Borrowed(field.trim()),
            Span::Quoted { open, close } => {
                let content = &field[open + 1..close];
                let after = field[close + 1..].trim_end();
                if !content.contains("\"\"") && after.is_empty() {
                    Cow::Borrowed(content.trim())
                } else {
                    let text = content.replace("\"\"", "\"") + after;
                    Cow::Owned(text.trim().to_string())
                }
            }
        })
    }
}

/// True when every field is empty or a number ([`is_number`]): a data row, not a header.
pub fn is_numeric(text: &str, sep: char) -> bool {
    fields(text, sep).all(|f| f.is_empty() || is_number(&f))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split(line: &str, sep: char) -> Vec<String> {
        fields(line, sep).map(Cow::into_owned).collect()
    }

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
    fn lines_split_across_chunks_and_overlong_ones() {
        assert_eq!(
            lines(5, &[b"ab", b"c\n12345\n123456\nx\r\ny"]),
            ["abc", "12345", "<too long>", "x", "y"]
        );
        assert_eq!(lines(5, &[b"", b"\n"]), [""]);
        let t: Vec<&str> = text_lines("a\r\nb\rc\n\nd").collect();
        assert_eq!(t, ["a", "b", "c", "", "d"]);
    }

    #[test]
    fn cr_lf_and_crlf_each_end_a_line() {
        // Classic Mac (CR only), Unix (LF), Windows (CRLF): the same lines.
        let want = ["t_s,thrust_N", "0.0,1.5", "0.1,1.6"];
        for end in ["\r", "\n", "\r\n"] {
            let text = want.join(end) + end;
            assert_eq!(lines(255, &[text.as_bytes()]), want, "{end:?}");
            // one byte at a time: a CRLF split between two pushes is one line end
            let bytes: Vec<&[u8]> = text.as_bytes().chunks(1).collect();
            assert_eq!(lines(255, &bytes), want, "{end:?}");
            let t: Vec<&str> = text_lines(&text).collect();
            assert_eq!(t, [&want[..], &[""]].concat(), "{end:?}");
            let b: Vec<&[u8]> = byte_lines(text.as_bytes()).collect();
            assert_eq!(b.len(), 4);
            assert_eq!(b[1], b"0.0,1.5");
        }
        // an empty line between two CRs, and between CRLF and CR
        assert_eq!(lines(255, &[b"a\r\rb\r\n\rc"]), ["a", "", "b", "", "c"]);
        let t: Vec<&str> = text_lines("a\r\rb\r\n\rc").collect();
        assert_eq!(t, ["a", "", "b", "", "c"]);
        // a CR that ends a push, then a lone LF: the LF belongs to the CR's line end
        assert_eq!(lines(255, &[b"a\r", b"", b"\nb\n"]), ["a", "b"]);
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
        let f = split(" \"Time (s)\" , 2 ,", ',');
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
        let comma = DecimalMark::Comma;
        assert_eq!(parse_number("-0,25", comma), Some(-0.25));
        assert_eq!(parse_number("1503,2", comma), Some(1503.2));
        // A point number where the file's mark is the comma: read with its own mark.
        assert_eq!(parse_number("2.5", comma), Some(2.5));
        // Not two commas, not a lone comma.
        assert_eq!(parse_number("1,2,3", comma), None);
        assert_eq!(parse_number(",5", comma), None);
        assert!(is_numeric("0,010;30,5;", ';'));
        assert!(!is_numeric("0,010;x", ';'));
    }

    #[test]
    fn quoted_fields_keep_their_separators() {
        let line = "\"0,45\",\"12,3\",\"1,234.5\", 7 ,";
        assert_eq!(separator(line), ',');
        let f = split(line, ',');
        assert_eq!(f, ["0,45", "12,3", "1,234.5", "7", ""]);
        let f = split("\"a;b\";\"1,5\"", ';');
        assert_eq!(f, ["a;b", "1,5"]);
        assert_eq!(separator("\"1,5\";\"2,5\""), ';');
        assert_eq!(split("", ','), [""]);
        // Quoted decimal commas in a `,` file: the comma is the file's mark.
        let rows = [
            "\"0,000\",\"30,0\",\"3,0129\"",
            "\"1,500\",\"50,0\",\"4,9911\"",
        ];
        let mark = DecimalMark::of_fields(rows.iter().flat_map(|r| fields(r, ',')));
        assert_eq!(mark, DecimalMark::Comma);
        assert_eq!(parse_number("1,500", mark), Some(1.5));
    }
}

#[cfg(test)]
mod quote_tests;
