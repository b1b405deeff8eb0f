//! The CSV fallback of TSP/1 (PROTOCOL.md §6), sans-IO: bytes in, header / rows / ACKs out.
//!
//! Rules, in the order a line meets them:
//! - Lines end in `\n`; `\r` is ignored. A line longer than the limit (255 characters by the
//!   protocol; raise it for exported files) is dropped whole and counted (`too_long`).
//! - A line starting with `#` is a comment, a banner or an acknowledgement
//!   (`#ACK <CMD> OK <t_us>`, `#ACK <CMD> ERR <code>`, see [`CsvAck`]).
//! - An optional trailing `*HH` is the XOR of every byte before the `*`, in hex (as NMEA); a
//!   wrong one drops the line (`bad_checksum`).
//! - Fields are separated by `,` (or by tabs / `;` when the line holds no comma).
//! - The header is the first non-comment line with a non-numeric field; its names are looked up
//!   in the alias table of [`csv_columns`](super::csv_columns) (unknown columns are ignored).
//!   Later, a line whose known-name columns are numbers is a row; a non-numeric line that names
//!   at least one known column replaces the header (a rebooted bench prints it again); any
//!   other non-numeric line is a bad row.
//! - Without a header, rows follow `t_us,throttle,thrust_N[,torque_Nm,rpm,voltage_V,current_A]`.
//! - Values are converted to canonical units (throttle fraction, s, N, N·m, rev/min, V, A). An
//!   empty field is "not measured" (`None`); text in a mapped field drops the row (`bad_row`).
//!
//! The decoder keeps one line buffer of fixed capacity; only a header allocates (once).

use serde::{Deserialize, Serialize};

use super::csv_columns::{self, ColumnSpec, ConvError, ConvOptions, Quantity, DEFAULT_ORDER};
use super::csv_command::CsvCommandKind;

/// Longest line the protocol allows, characters (without the newline).
pub const MAX_LINE: usize = 255;

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

/// One mapped column of a header.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MappedColumn {
    /// Field position in the line.
    pub index: usize,
    /// The name as written in the source.
    pub source_name: String,
    /// Quantity and unit.
    pub spec: ColumnSpec,
    /// Conversion to canonical units.
    #[serde(skip)]
    pub conv: csv_columns::Affine,
}

/// A known column that cannot be used for lack of an option.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnresolvedColumn {
    /// Field position.
    pub index: usize,
    /// The name as written.
    pub source_name: String,
    /// Why.
    #[serde(serialize_with = "ser_display")]
    pub reason: ConvError,
}

fn ser_display<S: serde::Serializer>(e: &ConvError, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(e)
}

/// Header → canonical channel mapping. At most one column per quantity: the first one that
/// maps (for instance RCbenchmark's electrical speed before its optical speed).
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct HeaderMap {
    /// Mapped columns, in field order.
    pub columns: Vec<MappedColumn>,
    /// Known columns that need an option to be used.
    pub unresolved: Vec<UnresolvedColumn>,
    /// Number of fields in the header line.
    pub field_count: usize,
}

impl HeaderMap {
    /// Map the fields of a header line.
    pub fn from_fields<'a>(fields: impl IntoIterator<Item = &'a str>, o: &ConvOptions) -> Self {
        let mut map = HeaderMap::default();
        for (index, name) in fields.into_iter().enumerate() {
            map.field_count = index + 1;
            if let Some(spec) = csv_columns::lookup(name) {
                map.add(index, name.trim().trim_start_matches('\u{feff}'), spec, o);
            }
        }
        map
    }

    /// The header-less default order for lines of `field_count` fields.
    pub fn default_order(field_count: usize, o: &ConvOptions) -> Self {
        let mut map = HeaderMap {
            field_count,
            ..Default::default()
        };
        for (index, spec) in DEFAULT_ORDER.iter().enumerate().take(field_count) {
            let name = default_name(spec.quantity);
            map.add(index, name, *spec, o);
        }
        map
    }

    fn add(&mut self, index: usize, name: &str, spec: ColumnSpec, o: &ConvOptions) {
        if self.column(spec.quantity).is_some() {
            return;
        }
        match spec.conversion(o) {
            Ok(conv) => self.columns.push(MappedColumn {
                index,
                source_name: name.to_string(),
                spec,
                conv,
            }),
            Err(reason) => self.unresolved.push(UnresolvedColumn {
                index,
                source_name: name.to_string(),
                reason,
            }),
        }
    }

    /// The column of a quantity, if mapped.
    pub fn column(&self, q: Quantity) -> Option<&MappedColumn> {
        self.columns.iter().find(|c| c.spec.quantity == q)
    }

    /// Parse a data line's fields into a row. Text in a mapped field is an error.
    pub fn row<'a>(&self, fields: impl IntoIterator<Item = &'a str>) -> Result<CsvRow, RowError> {
        let mut row = CsvRow::default();
        // `columns` is in field order, so one pass pairs fields and columns.
        let mut cols = self.columns.iter().peekable();
        for (i, f) in fields.into_iter().enumerate() {
            let Some(col) = cols.next_if(|c| c.index == i) else {
                continue;
            };
            let f = f.trim();
            if f.is_empty() {
                continue;
            }
            let raw: f64 = f.parse().map_err(|_| RowError::NotANumber(i))?;
            row.set(col.spec.quantity, col.conv.apply(raw));
        }
        Ok(row)
    }
}

fn default_name(q: Quantity) -> &'static str {
    match q {
        Quantity::Time => "t_us",
        Quantity::Index => "idx",
        Quantity::Throttle => "throttle",
        Quantity::Thrust => "thrust_N",
        Quantity::Torque => "torque_Nm",
        Quantity::Rpm => "rpm",
        Quantity::Voltage => "voltage_V",
        Quantity::Current => "current_A",
    }
}

/// Why a data line is not a row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RowError {
    /// The mapped field at this position is not a number.
    #[error("field {0} is not a number")]
    NotANumber(usize),
}

/// One data row in canonical units; `None` = column absent or field empty.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CsvRow {
    /// Time, s.
    pub t_s: Option<f64>,
    /// Sample index.
    pub index: Option<f64>,
    /// Throttle fraction 0..1.
    pub throttle: Option<f64>,
    /// Thrust, N.
    pub thrust_n: Option<f64>,
    /// Torque, N·m.
    pub torque_nm: Option<f64>,
    /// Rotor speed, rev/min.
    pub rpm: Option<f64>,
    /// Voltage, V.
    pub voltage_v: Option<f64>,
    /// Current, A.
    pub current_a: Option<f64>,
}

impl CsvRow {
    /// The value of a quantity.
    pub fn get(&self, q: Quantity) -> Option<f64> {
        match q {
            Quantity::Time => self.t_s,
            Quantity::Index => self.index,
            Quantity::Throttle => self.throttle,
            Quantity::Thrust => self.thrust_n,
            Quantity::Torque => self.torque_nm,
            Quantity::Rpm => self.rpm,
            Quantity::Voltage => self.voltage_v,
            Quantity::Current => self.current_a,
        }
    }

    fn set(&mut self, q: Quantity, v: f64) {
        let slot = match q {
            Quantity::Time => &mut self.t_s,
            Quantity::Index => &mut self.index,
            Quantity::Throttle => &mut self.throttle,
            Quantity::Thrust => &mut self.thrust_n,
            Quantity::Torque => &mut self.torque_nm,
            Quantity::Rpm => &mut self.rpm,
            Quantity::Voltage => &mut self.voltage_v,
            Quantity::Current => &mut self.current_a,
        };
        *slot = Some(v);
    }
}

/// A `#ACK` line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CsvAck {
    /// The command acknowledged.
    pub command: CsvCommandKind,
    /// `Ok(t_us)` for `OK <t_us>` (`None` when the time is absent), `Err(code)` for `ERR <code>`.
    pub result: Result<Option<u64>, i64>,
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
    opts: CsvOptions,
    line: Vec<u8>,
    overflow: bool,
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
            opts,
            line: Vec::with_capacity(opts.max_line),
            overflow: false,
            header: None,
            default_header: None,
            stats: CsvStats::default(),
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> &CsvStats {
        &self.stats
    }

    /// The header in force, if one was seen.
    pub fn header(&self) -> Option<&HeaderMap> {
        self.header.as_ref()
    }

    /// Feed bytes; `on_item` receives every header, row, ACK and comment, in order.
    pub fn push(&mut self, bytes: &[u8], mut on_item: impl FnMut(CsvItem<'_>)) {
        let mut rest = bytes;
        while let Some(i) = rest.iter().position(|&b| b == b'\n') {
            self.append(&rest[..i]);
            rest = &rest[i + 1..];
            self.end_line(&mut on_item);
        }
        self.append(rest);
    }

    /// End of input: a last line without `\n` is processed.
    pub fn finish(&mut self, mut on_item: impl FnMut(CsvItem<'_>)) {
        if !self.line.is_empty() || self.overflow {
            self.end_line(&mut on_item);
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
            if self.line.len() >= self.opts.max_line {
                self.overflow = true;
                return;
            }
            self.line.push(b);
        }
    }

    fn end_line(&mut self, on_item: &mut impl FnMut(CsvItem<'_>)) {
        self.stats.lines += 1;
        let line = std::mem::take(&mut self.line);
        if self.overflow {
            self.stats.too_long += 1;
        } else {
            self.handle(&line, on_item);
        }
        self.line = line;
        self.line.clear();
        self.overflow = false;
    }

    fn handle(&mut self, raw: &[u8], on_item: &mut impl FnMut(CsvItem<'_>)) {
        let Some(text) = strip_checksum(raw) else {
            self.stats.bad_checksum += 1;
            return;
        };
        let Ok(text) = std::str::from_utf8(text) else {
            self.stats.bad_row += 1;
            return;
        };
        let text = text.trim_start_matches('\u{feff}').trim();
        if text.is_empty() {
            self.stats.empty_lines += 1;
            return;
        }
        if let Some(comment) = text.strip_prefix('#') {
            self.stats.comments += 1;
            match parse_ack(comment) {
                Some(ack) => {
                    self.stats.acks += 1;
                    on_item(CsvItem::Ack(ack));
                }
                None => on_item(CsvItem::Comment(comment)),
            }
            return;
        }
        self.data_line(text, on_item);
    }

    fn data_line(&mut self, text: &str, on_item: &mut impl FnMut(CsvItem<'_>)) {
        let sep = separator(text);
        let numeric = text
            .split(sep)
            .all(|f| f.trim().is_empty() || f.trim().parse::<f64>().is_ok());
        if let Some(h) = &self.header {
            if let Ok(row) = h.row(text.split(sep)) {
                self.stats.rows += 1;
                return on_item(CsvItem::Row(row));
            }
        } else if numeric {
            let n = text.split(sep).count();
            let stale = self.default_header.as_ref().map(|h| h.field_count) != Some(n);
            if stale {
                self.default_header = Some(HeaderMap::default_order(n, &self.opts.conv));
            }
            if let Some(h) = &self.default_header {
                if let Ok(row) = h.row(text.split(sep)) {
                    self.stats.rows += 1;
                    return on_item(CsvItem::Row(row));
                }
            }
        }
        if !numeric {
            let h = HeaderMap::from_fields(text.split(sep), &self.opts.conv);
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

/// Field separator of a line: `,`, else tab, else `;`.
fn separator(text: &str) -> char {
    if text.contains(',') {
        ','
    } else if text.contains('\t') {
        '\t'
    } else {
        ';'
    }
}

/// Check and remove a trailing `*HH`; `None` when it is present and wrong.
fn strip_checksum(line: &[u8]) -> Option<&[u8]> {
    let n = line.len();
    if n >= 3 && line[n - 3] == b'*' {
        let hex = std::str::from_utf8(&line[n - 2..]).ok();
        if let Some(want) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
            let got = line[..n - 3].iter().fold(0u8, |a, b| a ^ b);
            return (got == want).then_some(&line[..n - 3]);
        }
    }
    Some(line)
}

/// The `*HH` checksum of a line: XOR of its bytes.
pub fn checksum(line: &[u8]) -> u8 {
    line.iter().fold(0, |a, b| a ^ b)
}

/// Parse `ACK <CMD> OK <t_us>` / `ACK <CMD> ERR <code>` (the text after `#`).
fn parse_ack(s: &str) -> Option<CsvAck> {
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

#[cfg(test)]
mod tests;
