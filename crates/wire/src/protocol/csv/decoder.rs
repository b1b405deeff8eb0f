//! The CSV stream decoder, sans-IO: bytes in, headers / rows / ACKs / comments out.
//!
//! Lines are split, checked and classified by the rules of [`line`](super::line); then:
//! - a `#` line is an acknowledgement ([`CsvAck`], `#ACK <CMD> OK <t_us>` /
//!   `#ACK <CMD> ERR <code>`) or any other comment (banners, the bench's HELLO and EVENT lines,
//!   read by [`device`](super::device));
//! - the header is the first non-comment line with a non-numeric field; its names are looked up
//!   in the alias table ([`HeaderMap`]). Later, a line whose known-name columns are numbers is a
//!   row; a non-numeric line that names at least one known column replaces the header (a
//!   rebooted bench prints it again); any other non-numeric line is a bad row;
//! - without a header, rows follow `t_us,throttle,thrust_N[,torque_Nm,rpm,voltage_V,current_A]`;
//! - values are converted to canonical units (throttle fraction, s, N, N·m, rev/min, V, A). An
//!   empty field is "not measured" (`None`); text in a mapped field drops the row (`bad_row`).
//!
//! The decoder keeps one line buffer of fixed capacity; only a header allocates (once).

use serde::{Deserialize, Serialize};

use super::columns::ConvOptions;
use super::device::{parse_ack, CsvAck};
use super::header::{CsvRow, HeaderMap};
use super::line::{classify, fields, is_numeric, separator, Line, LineKind, LineSplitter};
use super::MAX_LINE;

/// Decoder options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CsvOptions {
    /// Unit conversion options (ESC range, motor poles).
    pub conv: ConvOptions,
    /// Longest accepted line, bytes (default [`MAX_LINE`]; exported logs have longer headers).
    pub max_line: usize,
}

impl Default for CsvOptions {
    fn default() -> Self {
        Self {
            conv: ConvOptions::default(),
            max_line: MAX_LINE,
        }
    }
}

/// What the decoder found in a line.
#[derive(Debug, Clone, PartialEq)]
pub enum CsvItem<'a> {
    /// A (new) header; rows that follow use it.
    Header(&'a HeaderMap),
    /// A data row.
    Row(CsvRow),
    /// An acknowledgement.
    Ack(CsvAck),
    /// Any other `#` line (without the `#`).
    Comment(&'a str),
}

/// Decoder counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CsvStats {
    /// Complete lines seen.
    pub lines: u64,
    /// Rows handed out.
    pub rows: u64,
    /// Headers recognised.
    pub headers: u64,
    /// Comment lines (ACKs included).
    pub comments: u64,
    /// ACK lines.
    pub acks: u64,
    /// Lines over the length limit, dropped.
    pub too_long: u64,
    /// Lines with a wrong `*HH`, dropped.
    pub bad_checksum: u64,
    /// Lines that are neither header nor row (text in a number field, binary noise), dropped.
    pub bad_row: u64,
    /// Empty lines, ignored.
    pub empty_lines: u64,
}

impl CsvStats {
    /// Lines dropped for any reason.
    pub fn dropped(&self) -> u64 {
        self.too_long + self.bad_checksum + self.bad_row
    }
}

/// Sans-IO line decoder for CSV streams and files.
#[derive(Debug, Clone)]
pub struct CsvDecoder {
    lines: LineSplitter,
    state: State,
}

/// Everything but the line buffer (so both can be borrowed at once).
#[derive(Debug, Clone)]
struct State {
    conv: ConvOptions,
    header: Option<HeaderMap>,
    default_header: Option<HeaderMap>,
    stats: CsvStats,
}

impl Default for CsvDecoder {
    fn default() -> Self {
        Self::new(CsvOptions::default())
    }
}

impl CsvDecoder {
    /// A decoder; the line buffer is allocated here, once.
    pub fn new(opts: CsvOptions) -> Self {
        Self {
            lines: LineSplitter::new(opts.max_line),
            state: State {
                conv: opts.conv,
                header: None,
                default_header: None,
                stats: CsvStats::default(),
            },
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> &CsvStats {
        &self.state.stats
    }

    /// The header in force, if one was seen.
    pub fn header(&self) -> Option<&HeaderMap> {
        self.state.header.as_ref()
    }

    /// Feed bytes; `on_item` receives every header, row, ACK and comment, in order.
    pub fn push(&mut self, bytes: &[u8], mut on_item: impl FnMut(CsvItem<'_>)) {
        let state = &mut self.state;
        self.lines.push(bytes, |l| state.line(l, &mut on_item));
    }

    /// End of input: a last line without `\n` is processed.
    pub fn finish(&mut self, mut on_item: impl FnMut(CsvItem<'_>)) {
        let state = &mut self.state;
        self.lines.finish(|l| state.line(l, &mut on_item));
    }
}

impl State {
    fn line(&mut self, line: Line<'_>, on_item: &mut impl FnMut(CsvItem<'_>)) {
        self.stats.lines += 1;
        let raw = match line {
            Line::TooLong => {
                self.stats.too_long += 1;
                return;
            }
            Line::Text(raw) => raw,
        };
        match classify(raw) {
            LineKind::BadChecksum => self.stats.bad_checksum += 1,
            LineKind::NotText => self.stats.bad_row += 1,
            LineKind::Empty => self.stats.empty_lines += 1,
            LineKind::Comment(comment) => {
                self.stats.comments += 1;
                match parse_ack(comment) {
                    Some(ack) => {
                        self.stats.acks += 1;
                        on_item(CsvItem::Ack(ack));
                    }
                    None => on_item(CsvItem::Comment(comment)),
                }
            }
            LineKind::Data(text) => self.data_line(text, on_item),
        }
    }

    fn data_line(&mut self, text: &str, on_item: &mut impl FnMut(CsvItem<'_>)) {
        let sep = separator(text);
        let numeric = is_numeric(text, sep);
        if let Some(h) = &self.header {
            if let Ok(row) = h.row(fields(text, sep)) {
                self.stats.rows += 1;
                return on_item(CsvItem::Row(row));
            }
        } else if numeric {
            let n = fields(text, sep).count();
            let stale = self.default_header.as_ref().map(|h| h.field_count) != Some(n);
            if stale {
                self.default_header = Some(HeaderMap::default_order(n, &self.conv));
            }
            if let Some(h) = &self.default_header {
                if let Ok(row) = h.row(fields(text, sep)) {
                    self.stats.rows += 1;
                    return on_item(CsvItem::Row(row));
                }
            }
        }
        if !numeric {
            let h = HeaderMap::from_fields(fields(text, sep), &self.conv);
            if !h.columns.is_empty() || !h.unresolved.is_empty() {
                self.stats.headers += 1;
                self.header = Some(h);
                if let Some(h) = &self.header {
                    on_item(CsvItem::Header(h));
                }
                return;
            }
        }
        self.stats.bad_row += 1;
    }
}
