//! CSV files into a [`Record`]: TSP/1 CSV (PROTOCOL.md §6), exported logs of commercial stands,
//! benchmark archives.
//!
//! Lines, checksums, comments, separators and fields follow the one CSV dialect of the project
//! ([`protocol::csv::line`](propid_wire::protocol::csv::line): comments `#…`, optional `*HH`
//! checksum, separator `,` else tab else `;`, fields trimmed and unquoted, a UTF-8 byte-order
//! mark ignored), with what files need on top: no line-length limit (exports have
//! 400-character headers), trailing empty columns, and columns the alias table does not know
//! (kept under their own names so that `--input`/`--output` can pick them). Known names are
//! mapped and converted by [`protocol::csv::columns`](propid_wire::protocol::csv::columns) (the
//! one alias, unit and name table of the project).
//!
//! A file without a header follows §6 (`t_us,throttle,thrust_N,…`) unless the caller names the
//! columns. Bad rows are counted, never fatal: a wrong checksum, text in a column that is used,
//! a row with too few fields. An empty file, a file without data rows, or a requested column
//! that is absent is an error naming what is missing and what is there.
//!
//! Time: a time column (`t_us`, `t_ms`, `t_s`, `Time (s)`, `t`, `time`) is resampled onto a
//! uniform grid when irregular ([`super::resample`]); `fs` overrides its rate; without a time
//! column `fs` is required.

use serde::Serialize;

mod columns;

use super::resample::{to_uniform, Jitter, ResampleError};
use columns::{channel, header_columns, Column, Picks};
use propid_wire::protocol::csv::columns::{self as csv_columns, ConvOptions};
use propid_wire::protocol::csv::line::{
    classify_str, fields, is_numeric, separator, text_lines, LineKind,
};
use propid_wire::record::{Channel, Record};

/// Default ESC pulse range for throttle columns in µs, when none is given.
pub const DEFAULT_ESC_US: (f64, f64) = (1000.0, 2000.0);

/// What the caller wants from the file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CsvFileOptions {
    /// Input column (source name or canonical name); `None` = the throttle column if any.
    pub input: Option<String>,
    /// Output columns; empty = the thrust column.
    pub outputs: Vec<String>,
    /// Sample rate, Hz: required without a time column, overrides it otherwise.
    pub fs_hz: Option<f64>,
    /// Names for a file without a header (otherwise §6's default order).
    pub columns: Option<Vec<String>>,
    /// ESC pulse range for throttle in µs; `None` = [`DEFAULT_ESC_US`].
    pub esc_us: Option<(f64, f64)>,
    /// Motor pole count (for electrical rpm).
    pub motor_poles: Option<u32>,
}

/// Why a file cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CsvFileError {
    /// Nothing but comments or blank lines.
    #[error("the file holds no data rows")]
    Empty,
    /// A requested (or the default) column is absent.
    #[error("no {what} column {wanted}; columns in the file: {available}")]
    MissingColumn {
        /// "input" or "output".
        what: &'static str,
        /// The name asked for (or the default's description).
        wanted: String,
        /// The columns present.
        available: String,
    },
    /// No time column and no `fs`.
    #[error("the file has no time column: give the sample rate with --fs HZ")]
    NeedRate,
    /// Timestamps unusable, or a bad rate.
    #[error("time base: {0}")]
    Time(#[from] ResampleError),
    /// Fewer than two usable rows.
    #[error("only {0} usable data row(s)")]
    TooFewRows(usize),
    /// A column needs an option to be converted (e.g. electrical rpm needs the pole count).
    #[error("column {column}: {reason}")]
    Conversion {
        /// The column.
        column: String,
        /// What is missing.
        reason: String,
    },
}

/// Rows that were not used, by cause.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct SkippedRows {
    /// Wrong `*HH` checksum.
    pub bad_checksum: usize,
    /// Text where a number was needed (in a column that is used).
    pub not_a_number: usize,
    /// Fewer fields than the columns used need.
    pub short_row: usize,
}

impl SkippedRows {
    /// All skipped rows.
    pub fn total(&self) -> usize {
        self.bad_checksum + self.not_a_number + self.short_row
    }
}

/// Where the data came from and what was done to it (published beside the model).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CsvSource {
    /// Input column as named in the file (`None`: response only).
    pub input: Option<String>,
    /// Output columns as named in the file.
    pub outputs: Vec<String>,
    /// Time column as named in the file (`None`: rate given).
    pub time: Option<String>,
    /// Sample rate used, Hz.
    pub rate_hz: f64,
    /// `"time column"` or `"--fs"`.
    pub rate_from: &'static str,
    /// Timing report (with a time column).
    pub jitter: Option<Jitter>,
    /// Data rows read.
    pub rows: usize,
    /// Rows skipped, by cause.
    pub skipped: SkippedRows,
    /// Comment lines.
    pub comments: usize,
    /// True when the file had a header line.
    pub header: bool,
}

/// A file read into a record.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvFile {
    /// Channels: the input first (when there is one), then the outputs.
    pub record: Record,
    /// Canonical name of the input channel in the record, if any.
    pub input: Option<String>,
    /// Canonical names of the output channels in the record.
    pub outputs: Vec<String>,
    /// The report.
    pub source: CsvSource,
}

/// Reads CSV text (the whole file) into a record.
pub fn read_csv(text: &str, opts: &CsvFileOptions) -> Result<CsvFile, CsvFileError> {
    let mut skipped = SkippedRows::default();
    let mut comments = 0;
    let mut lines = Vec::new();
    for raw in text_lines(text) {
        match classify_str(raw) {
            LineKind::Empty => {}
            LineKind::Comment(_) => comments += 1,
            LineKind::Data(l) => lines.push(l),
            LineKind::BadChecksum | LineKind::NotText => skipped.bad_checksum += 1,
        }
    }
    let Some(first) = lines.first() else {
        return Err(CsvFileError::Empty);
    };
    let sep = separator(first);
    let header = !is_numeric(first, sep);
    let mut columns = header_columns(&lines, sep, header, opts);
    // A header ending in a separator (benchmark files) has an empty, unnamed last column.
    if columns.last().is_some_and(|c| c.name.is_empty()) {
        columns.pop();
    }
    let data = &lines[usize::from(header)..];
    if data.is_empty() {
        return Err(CsvFileError::Empty);
    }
    let picks = Picks::choose(&columns, opts)?;
    let conv = ConvOptions {
        esc_min_us: Some(opts.esc_us.unwrap_or(DEFAULT_ESC_US).0),
        esc_max_us: Some(opts.esc_us.unwrap_or(DEFAULT_ESC_US).1),
        motor_poles: opts.motor_poles,
    };
    let used = picks.all();
    let maps: Vec<csv_columns::Affine> = used
        .iter()
        .map(|&i| match columns[i].spec {
            Some(spec) => spec
                .conversion(&conv)
                .map_err(|e| CsvFileError::Conversion {
                    column: columns[i].name.clone(),
                    reason: e.to_string(),
                }),
            None => Ok(csv_columns::Affine {
                zero: 0.0,
                mul: 1.0,
                div: 1.0,
            }),
        })
        .collect::<Result<_, _>>()?;
    let mut values: Vec<Vec<f64>> = vec![Vec::with_capacity(data.len()); used.len()];
    let mut row = Vec::new();
    for line in data {
        row.clear();
        row.extend(fields(line, sep));
        if used.iter().any(|&i| i >= row.len()) {
            skipped.short_row += 1;
            continue;
        }
        let parsed: Option<Vec<f64>> = used
            .iter()
            .zip(&maps)
            .map(|(&i, m)| parse_field(row[i]).map(|v| m.apply(v)))
            .collect();
        match parsed {
            Some(row) => values.iter_mut().zip(row).for_each(|(c, v)| c.push(v)),
            None => skipped.not_a_number += 1,
        }
    }
    let rows = values[0].len();
    if rows < 2 {
        return Err(CsvFileError::TooFewRows(rows));
    }
    let table = Table {
        columns,
        picks,
        values,
        header,
        rows,
        skipped,
        comments,
    };
    build(table, opts)
}

/// What the text held, before the time base: the columns, the ones picked, and what was read.
struct Table {
    /// Every column of the file (named by the header, the caller or §6's order).
    columns: Vec<Column>,
    /// The time, input and output columns used.
    picks: Picks,
    /// The picked columns' converted values, in [`Picks::all`] order: time, input, outputs.
    values: Vec<Vec<f64>>,
    /// True when the file had a header line.
    header: bool,
    /// Data rows read.
    rows: usize,
    /// Rows skipped, by cause.
    skipped: SkippedRows,
    /// Comment lines.
    comments: usize,
}

/// The record from the table: time base (resampled, or `fs`), missing samples, channels, and
/// the source report.
fn build(table: Table, opts: &CsvFileOptions) -> Result<CsvFile, CsvFileError> {
    let Table {
        columns,
        picks,
        mut values,
        header,
        rows,
        skipped,
        comments,
    } = table;
    let time_vals = picks.time.map(|_| values.remove(0));
    let (t0_s, dt_s, missing, jitter, rate_from) = match time_vals {
        Some(t) => {
            let u = to_uniform(&t, &values, opts.fs_hz)?;
            values = u.channels;
            let from = if opts.fs_hz.is_some() {
                "--fs"
            } else {
                "time column"
            };
            (u.t0_s, u.jitter.dt_s, u.missing, Some(u.jitter), from)
        }
        None => {
            let fs = opts.fs_hz.ok_or(CsvFileError::NeedRate)?;
            if !(fs.is_finite() && fs > 0.0) {
                return Err(ResampleError::BadRate(fs).into());
            }
            (0.0, 1.0 / fs, vec![false; rows], None, "--fs")
        }
    };
    // An empty field (not measured) is NaN: mark the sample missing, as the record requires.
    let mut missing = missing;
    for ch in &values {
        for (m, v) in missing.iter_mut().zip(ch) {
            *m |= !v.is_finite();
        }
    }
    for ch in &mut values {
        for (v, m) in ch.iter_mut().zip(&missing) {
            if *m {
                *v = f64::NAN;
            }
        }
    }
    let chosen: Vec<usize> = picks.input.iter().chain(&picks.outputs).copied().collect();
    let channels: Vec<Channel> = chosen
        .iter()
        .zip(values)
        .map(|(&i, data)| channel(&columns[i], data))
        .collect();
    let input = picks.input.map(|_| channels[0].name.clone());
    let outputs = channels[usize::from(picks.input.is_some())..]
        .iter()
        .map(|c| c.name.clone())
        .collect();
    let source = CsvSource {
        input: picks.input.map(|i| columns[i].name.clone()),
        outputs: picks
            .outputs
            .iter()
            .map(|&i| columns[i].name.clone())
            .collect(),
        time: picks.time.map(|i| columns[i].name.clone()),
        rate_hz: 1.0 / dt_s,
        rate_from,
        jitter,
        rows,
        skipped,
        comments,
        header,
    };
    Ok(CsvFile {
        record: Record {
            dt_s,
            t0_s,
            channels,
            missing,
            events: Vec::new(),
        },
        input,
        outputs,
        source,
    })
}

/// An empty field is "not measured" (NaN); text is `None`.
fn parse_field(f: &str) -> Option<f64> {
    if f.is_empty() {
        return Some(f64::NAN);
    }
    f.parse().ok()
}
