//! CSV files into a [`Record`]: exported logs of commercial stands, hobby benches, benchmark
//! archives, TSP/1 CSV (docs/PROTOCOL.md §6) with a header.
//!
//! Lines, checksums, comments, separators and fields follow the one CSV dialect of the project
//! ([`protocol::csv::line`](propid_wire::protocol::csv::line): comments `#…`, optional `*HH`
//! checksum, separator `,` else tab else `;`, fields trimmed and unquoted, a UTF-8 byte-order
//! mark ignored), with what files need on top: no line-length limit (exports have
//! 400-character headers), trailing empty columns, and columns the alias table does not know
//! (kept under their own names so that `--input`/`--output` can pick them). Known names are
//! mapped and converted by [`protocol::csv::columns`](propid_wire::protocol::csv::columns) (the
//! one alias, unit and name table of the project): thrust in N, gf, kgf, lbf, ozf; torque in
//! N·m, N·mm, ozf·in; speed in RPM, rad/s, Hz or eRPM (with the pole count); voltage and
//! current; every channel is converted to the record's canonical units, and the column, unit and
//! factor used are reported per channel ([`CsvSource::units`]).
//!
//! **The command.** A command column (`throttle`, `ESC signal`, `pwm`, `cmd`, in µs, %, 0..1,
//! DShot or without a unit) is the input whenever the file has one; without one the caller must
//! say `--input NAME`, or `--input none` ([`InputChoice::None`]) to have the steps found in the
//! response. Its full scale is decided from the options, the header and the values, and stated
//! ([`command_range`]); a scale that cannot be decided is an error naming the option to give.
//! An `--input` column the unit table does not know is read like a bare command, or taken as
//! it is when its values are a signal in its own units (signed or fractional, fitting no
//! command range: [`command_range::unknown_input_range`]).
//!
//! **Empty cells.** An empty cell is a missing value of its channel only: the other channels of
//! the row stay. Each channel is carried onto the time base from its own samples at its own rate
//! ([`super::resample`]: interpolation between its own samples, gaps wider than one and a half
//! of its own periods left NaN); the record's `missing` marks the samples where the input or an
//! output has no value, the channels read beside them ([`CsvFileOptions::optional`]) keep their
//! own NaNs. A column asked for beside them whose every cell is 0 or empty holds no reading (an
//! export keeps the columns of sensors the stand lacks: RCbenchmark's electrical or optical
//! speed): another column of its name that reads is taken instead, else it is left out and
//! said in [`CsvSource::unread`] ([`NO_READING`]).
//!
//! **Header.** Where the header is (after preamble lines, with a units row under it) is the
//! rule of `csv_file/layout.rs`. A file without a header is refused unless the caller names its
//! columns (`--columns`, which for a file with a header replace its names): a column order is
//! never guessed (§6's header-less order is a property of a TSP/1 CSV *stream*, read by
//! [`crate::tsp`]). A thrust column whose name says no unit, and a time column without
//! a unit counting whole milliseconds or microseconds, are refused naming `--columns`: their
//! unit is not guessed; nor is which of two columns of one name is meant (the time, the input
//! or an output: refused naming `--columns`; a column read beside them: left out, said). Bad
//! rows are counted, never fatal: a
//! wrong checksum, text in the time, input or an output column, a row with too few fields. An
//! empty file, a file without data rows, or a requested column that is absent is an error naming
//! what is missing and what is there.
//!
//! Numbers: a decimal point or a decimal comma, thousands grouped by the other mark, the file's
//! mark shown by its rows ([`DecimalMark`]; `1.234,5`, `1,234.5`, `"0,45"` in a quoted field of a
//! `,` file); a time column may hold date-time or time-of-day stamps, which keep increasing
//! across midnight ([`ClockColumn`]; the midnights passed are counted in `midnights`).
//!
//! Time: a time column (`t_us`, `t_ms`, `t_s`, `Time (s)`, `t`, `time`) is resampled onto a
//! uniform grid when irregular ([`super::resample`]); `fs` overrides its rate; without a time
//! column `fs` is required.

use std::collections::BTreeMap;

use serde::Serialize;

mod columns;
pub mod command_range;
mod convert;
mod layout;

use super::held::{held_period, hold_command, unhold};
use super::interpolated::exporter_interpolated;
use super::resample::{is_zero_usize, to_uniform, Carried, Jitter, ResampleError};
use columns::{channel, header_columns, Column, Picks};
pub use command_range::{command_range, CommandRange, GivenRanges, RangeError};
use convert::{convert, Converted};
use layout::{layout_of, Layout};
use propid_wire::protocol::csv::columns::{ColumnSpec, Quantity, Scale, Unit};
use propid_wire::protocol::csv::encoding::Encoding;
use propid_wire::protocol::csv::line::{
    classify_str, fields, is_missing_marker, parse_cell, text_lines, ClockColumn, DecimalMark,
    LineKind,
};
use propid_wire::record::{Channel, Record};

/// Default ESC pulse range for throttle columns in µs, when none is given.
pub const DEFAULT_ESC_US: (f64, f64) = (Scale::ESC_US.raw_min, Scale::ESC_US.raw_max);

/// Which column is the input.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum InputChoice {
    /// The file's command column; a file without one is an error ([`CsvFileError::NoCommand`]).
    #[default]
    Command,
    /// This column (source name or canonical name).
    Column(String),
    /// No input: the caller finds steps in the response (`--input none`).
    None,
}

/// What the caller wants from the file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CsvFileOptions {
    /// The input column.
    pub input: InputChoice,
    /// Output columns; empty = the thrust column.
    pub outputs: Vec<String>,
    /// Columns read too when the file has them (not outputs: their empty cells do not mark
    /// samples missing), skipped when absent or not convertible.
    pub optional: Vec<String>,
    /// Sample rate, Hz: required without a time column, overrides it otherwise.
    pub fs_hz: Option<f64>,
    /// Names of the file's columns: required for a file without a header; for a file with one,
    /// they replace its names (to give a column the unit its header does not say).
    pub columns: Option<Vec<String>>,
    /// ESC pulse range of a command in µs (`--esc-us`).
    pub esc_us: Option<(f64, f64)>,
    /// Raw command values at throttle 0 and 1 (`--input-range`).
    pub input_range: Option<(f64, f64)>,
    /// Motor pole count (for electrical rpm).
    pub motor_poles: Option<u32>,
}

/// Why a file cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CsvFileError {
    /// Nothing but comments or blank lines.
    #[error("the file holds no data rows")]
    Empty,
    /// The first data line is numbers, not names, and no names were given.
    #[error(
        "the file has no header line (its first line is numbers): name its {fields} columns \
         with --columns NAME,NAME,... (e.g. --columns t_s,throttle,thrust_N); no column order \
         is guessed"
    )]
    NoHeader {
        /// Fields of the first line.
        fields: usize,
    },
    /// The thrust column's name says no unit (`Thrust`): newtons or gram-force is not guessed.
    #[error(
        "column {column} is a {quantity} without a unit ({units}): name the file's columns with \
         their units, --columns NAME,NAME,... (they replace the header's names; e.g. {example})"
    )]
    Unitless {
        /// The column.
        column: String,
        /// Its quantity (`thrust`).
        quantity: &'static str,
        /// The units it may be written in.
        units: String,
        /// A `--columns` value for this file.
        example: String,
    },
    /// A time column without a unit whose whole-number values step by 1 or more: seconds,
    /// milliseconds or microseconds is not guessed.
    #[error(
        "time column {column} has no unit and counts whole numbers (milliseconds or \
         microseconds of a logger's clock?): name the file's columns with --columns NAME,NAME,... \
         (they replace the header's names), with time_ms, time_us or time_s in its place"
    )]
    UnitlessTime {
        /// The column.
        column: String,
    },
    /// The same sensor for several motors, of the quantity the input or the output is picked
    /// by (a stand with a load cell per motor): which one is not guessed.
    #[error(
        "the file has more than one {quantity} column ({columns}): give {option} for the one to \
         use"
    )]
    TwoSensors {
        /// The quantity's key (`thrust`, `throttle`).
        quantity: &'static str,
        /// Its columns.
        columns: String,
        /// The option that picks one.
        option: &'static str,
    },
    /// Two or more columns of one name, one of them needed (the time, the input or an
    /// output): which one is meant is not guessed.
    #[error(
        "the file has more than one column named {column:?} (columns {positions}): which one \
         is meant is not guessed; name the file's columns with --columns NAME,NAME,... (they \
         replace the header's names), each its own"
    )]
    SameName {
        /// The name, as written in the file.
        column: String,
        /// The columns of that name, counted from 1, comma separated.
        positions: String,
    },
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
    /// No command column and no `--input`.
    #[error(
        "no command column (throttle, ESC signal, pwm, cmd, in µs, %, 0..1 or raw); columns in \
         the file: {available}: give --input NAME, or --input none to find the steps in the \
         response"
    )]
    NoCommand {
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
    #[error("only {rows} usable data row(s){why}")]
    TooFewRows {
        /// The usable rows.
        rows: usize,
        /// Why the others were not: the first unreadable cell of a needed column (`: 1400
        /// row(s) with a cell that is no number, the first "4,5e" in Thrust (N) (data row
        /// 1)`), rows too short for the columns used, or nothing.
        why: String,
    },
    /// A column needs an option to be converted (e.g. electrical rpm needs the pole count).
    #[error("column {column}: {reason}")]
    Conversion {
        /// The column.
        column: String,
        /// What is missing.
        reason: String,
    },
    /// The command's full scale cannot be decided.
    #[error("command column {column}: {source}")]
    CommandRange {
        /// The column.
        column: String,
        /// Why.
        source: RangeError,
    },
}

/// Rows that were not used, by cause.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct SkippedRows {
    /// Wrong `*HH` checksum.
    pub bad_checksum: usize,
    /// Text where a number was needed (in the time, input or an output column).
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

/// The unit of one column as read: `canonical = (raw − zero) · factor`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColumnUnit {
    /// The column as named in the file.
    pub column: String,
    /// Its unit (`gf`, `N·mm`, `µs`, `raw ESC`, ...; `?` for a column the table does not know).
    pub unit: String,
    /// Canonical units per raw unit.
    pub factor: f64,
    /// The raw value that maps to 0 (a command's `raw_min`; omitted when 0).
    #[serde(skip_serializing_if = "is_zero")]
    pub zero: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
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
    /// Lines before the header that are not `#` comments (an export's preamble: motor,
    /// propeller, date), skipped.
    #[serde(skip_serializing_if = "is_zero_usize")]
    pub preamble: usize,
    /// True when the units were read from a row of their own under the header's names.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub units_row: bool,
    /// `","` when the file's numbers are written with a decimal comma (omitted for the point).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decimal_mark: Option<&'static str>,
    /// Midnights a time column of times of day passed (a day added after each).
    #[serde(skip_serializing_if = "is_zero_usize")]
    pub midnights: usize,
    /// The file's encoding when it is not UTF-8 (`"windows-1252"`, `"utf-16le"`, ...;
    /// [`propid_wire::protocol::csv::encoding`]); set by the file loader, omitted for UTF-8.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub encoding: Option<Encoding>,
    /// How each channel read was carried onto the time base, by its key (`thrust`, ...): own
    /// samples, own period, samples bridged across empty cells, samples left NaN.
    pub channels: BTreeMap<String, Carried>,
    /// Column, unit and factor of each channel read, by its key (`time`, `throttle`,
    /// `thrust`, `torque`, `rpm`, `voltage`, `current`, or the column's own name); identify
    /// publishes it as `source.units`.
    #[serde(skip)]
    pub units: BTreeMap<String, ColumnUnit>,
    /// The command's scale (raw values at throttle 0 and 1) and where it came from; identify
    /// publishes it as `source.input_range` and `source.input_range_from`.
    #[serde(skip)]
    pub input_range: Option<CommandRange>,
    /// Columns asked for beside the outputs that the file has but that could not be converted
    /// (an eRPM without `--poles`), with why: left out, said.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unread: Vec<Unread>,
}

impl CsvSource {
    /// Whether the input column is a stand's command (a throttle, an ESC signal, read on a
    /// command's scale: [`command_range::is_a_command`]), not a measured signal (a benchmark's
    /// pump voltage, a shaker's force); `true` without an input column (steps found from the
    /// response are a command's levels). A command's holds are levels by the motor's time
    /// scale too ([`propid_numerics::segment::SegmentRules::at_rate`]), and it is held, never
    /// interpolated, between its rows.
    pub fn input_is_a_command(&self) -> bool {
        self.input.is_none() || command_range::is_a_command(self.input_range.as_ref())
    }
}

/// A column left out, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Unread {
    /// The column as named in the file.
    pub column: String,
    /// Why it could not be read.
    pub reason: String,
}

/// A file read into a record.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvFile {
    /// Channels: the input first (when there is one), then the outputs, then the optional ones.
    pub record: Record,
    /// Canonical name of the input channel in the record, if any.
    pub input: Option<String>,
    /// Canonical names of the output channels in the record.
    pub outputs: Vec<String>,
    /// Canonical names of the optional channels the file has, in the order asked for.
    pub optional: Vec<String>,
    /// The report.
    pub source: CsvSource,
}

/// The raw values of the columns used, one vector per column (NaN = empty cell).
struct Parsed {
    values: Vec<Vec<f64>>,
    rows: usize,
    skipped: SkippedRows,
    comments: usize,
    layout: Layout,
    midnights: usize,
}

/// A CSV text read into the raw values of the columns used ([`parse_csv`]), before they are
/// converted and carried onto the time base ([`ParsedCsv::build`]): the text is no longer
/// needed, and a loader drops it before the second step.
pub struct ParsedCsv {
    columns: Vec<Column>,
    picks: Picks,
    parsed: Parsed,
}

/// Reads CSV text (the whole file) into a record: [`parse_csv`], then [`ParsedCsv::build`].
pub fn read_csv(text: &str, opts: &CsvFileOptions) -> Result<CsvFile, CsvFileError> {
    parse_csv(text, opts)?.build(opts)
}

impl ParsedCsv {
    /// Converts the parsed columns, carries them onto the time base and puts the record
    /// together.
    pub fn build(self, opts: &CsvFileOptions) -> Result<CsvFile, CsvFileError> {
        build(&self.columns, self.picks, self.parsed, opts)
    }
}

/// Reads CSV text (the whole file) into the raw values of the columns used: the file's lines
/// are gone through a few times (layout, the columns that read, the rows), never held.
pub fn parse_csv(text: &str, opts: &CsvFileOptions) -> Result<ParsedCsv, CsvFileError> {
    let data_lines = || {
        text_lines(text).filter_map(|raw| match classify_str(raw) {
            LineKind::Data(l) => Some(l),
            _ => None,
        })
    };
    let mut skipped = SkippedRows::default();
    let mut comments = 0;
    let mut count: usize = 0;
    for raw in text_lines(text) {
        match classify_str(raw) {
            LineKind::Empty => {}
            LineKind::Comment(_) => comments += 1,
            LineKind::Data(_) => count += 1,
            LineKind::BadChecksum | LineKind::NotText => skipped.bad_checksum += 1,
        }
    }
    if count == 0 {
        return Err(CsvFileError::Empty);
    }
    let layout = layout_of(data_lines);
    let (sep, mark) = (layout.sep, layout.mark);
    let first_row = data_lines().nth(layout.data_start);
    let mut columns = header_columns(first_row, &layout, opts)?;
    // A header ending in separators (benchmark files) has empty, unnamed last columns.
    while columns.last().is_some_and(|c| c.name.is_empty()) {
        columns.pop();
    }
    let data = || data_lines().skip(layout.data_start);
    let rows_in_file = count.saturating_sub(layout.data_start);
    if rows_in_file == 0 {
        return Err(CsvFileError::Empty);
    }
    let picks = Picks::choose(&columns, opts, |i| column_reads(data(), &layout, i))?;
    let used = picks.all();
    let required = used.len() - picks.optional.len();
    let mut values: Vec<Vec<f64>> = vec![Vec::with_capacity(rows_in_file); used.len()];
    let mut row = Vec::new();
    let mut parsed = Vec::with_capacity(used.len());
    let mut clock = false;
    let mut stamps = ClockColumn::default();
    // The first cell of a needed column that was no number (its text, column and line).
    let mut first_unread: Option<(String, usize, usize)> = None;
    'rows: for (line_no, line) in data().enumerate() {
        row.clear();
        row.extend(fields(line, sep));
        if used[..required].iter().any(|&i| i >= row.len()) {
            skipped.short_row += 1;
            continue;
        }
        parsed.clear();
        for (n, &i) in used.iter().enumerate() {
            let field = row
                .get(i)
                .map_or("", |f: &std::borrow::Cow<str>| f.as_ref());
            let mut value = parse_field(field, mark);
            // A time column of time stamps (`18:55:23.120`, `2024-08-13 18:55:23.120`).
            if value.is_none() && n == 0 && picks.time.is_some() {
                value = stamps.read(field);
                clock |= value.is_some();
            }
            match (value, n < required) {
                (Some(v), _) => parsed.push(v),
                (None, true) => {
                    skipped.not_a_number += 1;
                    first_unread.get_or_insert((field.to_string(), i, line_no));
                    continue 'rows;
                }
                // Text in a channel only read beside the others: that channel's value is missing.
                (None, false) => parsed.push(f64::NAN),
            }
        }
        values.iter_mut().zip(&parsed).for_each(|(c, &v)| c.push(v));
    }
    let rows = values[0].len();
    if rows < 2 {
        let why = match first_unread {
            Some((text, i, n)) => format!(
                ": {} row(s) with a cell that is no number, the first {text:?} in {} (data row {})",
                skipped.not_a_number,
                columns[i].name,
                n + 1
            ),
            None if skipped.short_row > 0 => {
                format!(
                    ": {} row(s) too short for the columns used",
                    skipped.short_row
                )
            }
            None => String::new(),
        };
        return Err(CsvFileError::TooFewRows { rows, why });
    }
    if let (true, Some(t)) = (clock, picks.time) {
        columns[t].spec = Some(ColumnSpec {
            quantity: Quantity::Time,
            unit: Unit::Clock,
        });
    }
    let parsed = Parsed {
        values,
        rows,
        skipped,
        comments,
        layout,
        midnights: stamps.midnights,
    };
    Ok(ParsedCsv {
        columns,
        picks,
        parsed,
    })
}

/// Converts the parsed columns, carries them onto the time base and puts the record together.
fn build(
    columns: &[Column],
    mut picks: Picks,
    parsed: Parsed,
    opts: &CsvFileOptions,
) -> Result<CsvFile, CsvFileError> {
    let Parsed {
        mut values,
        rows,
        skipped,
        comments,
        layout,
        midnights,
    } = parsed;
    let Converted {
        units,
        input_range,
        mut unread,
    } = convert(columns, &mut picks, &mut values, opts)?;
    unread.extend(picks.silent.iter().map(|&(i, why)| Unread {
        column: columns[i].name.clone(),
        reason: why.to_string(),
    }));
    let time_vals = picks.time.map(|_| values.remove(0));
    // A measured channel written on every row as its last reading: its repeats are cells not
    // updated; a command written only where it changes holds until the next (`super::held`).
    let n_in = usize::from(picks.input.is_some());
    let command_held = values
        .first_mut()
        .filter(|_| n_in == 1)
        .map_or(0, |c| hold_command(c));
    let held: Vec<Option<usize>> = values
        .iter_mut()
        .enumerate()
        .map(|(i, ch)| {
            let period = (i >= n_in).then(|| held_period(ch)).flatten()?;
            unhold(ch, period);
            Some(period)
        })
        .collect();
    // A command is carried onto the grid by holding it (an ESC keeps its last command), any
    // other channel by interpolating it (`super::resample`).
    let is_command = command_range::is_a_command(input_range.as_ref());
    let carry_held: Vec<bool> = (0..values.len()).map(|i| i < n_in && is_command).collect();
    let (t0_s, dt_s, jitter, rate_from, carried, mut bridged) = match time_vals {
        Some(t) => {
            let u = to_uniform(&t, &values, opts.fs_hz, &carry_held)?;
            values = u.channels;
            let from = if opts.fs_hz.is_some() {
                "--fs"
            } else {
                "time column"
            };
            (
                u.t0_s,
                u.jitter.dt_s,
                Some(u.jitter),
                from,
                u.carried,
                u.bridged,
            )
        }
        None => {
            let fs = opts.fs_hz.ok_or(CsvFileError::NeedRate)?;
            if !(fs.is_finite() && fs > 0.0) {
                return Err(ResampleError::BadRate(fs).into());
            }
            // Rows at the given rate are the grid; each channel is carried at its own rate.
            let t: Vec<f64> = (0..rows).map(|k| k as f64 / fs).collect();
            let u = to_uniform(&t, &values, Some(fs), &carry_held)?;
            values = u.channels;
            (0.0, 1.0 / fs, None, "--fs", u.carried, u.bridged)
        }
    };
    // A measured channel the exporter interpolated onto every row: its values stay, marked as
    // not read (`super::interpolated`).
    let lined: Vec<usize> = values
        .iter()
        .zip(bridged.iter_mut())
        .enumerate()
        .map(|(i, (ch, mask))| {
            let marked = (i >= n_in && !mask.contains(&true))
                .then(|| exporter_interpolated(ch))
                .flatten();
            marked.map_or(0, |m| {
                *mask = m;
                mask.iter().filter(|b| **b).count()
            })
        })
        .collect();
    // The samples where the input or an output has no value are missing; the optional channels
    // keep their own NaNs.
    let identified = values.len() - picks.optional.len();
    let mut missing = vec![false; values.first().map_or(0, Vec::len)];
    for ch in &values[..identified] {
        for (m, v) in missing.iter_mut().zip(ch) {
            *m |= !v.is_finite();
        }
    }
    let chosen: Vec<usize> = picks.channels().copied().collect();
    let channels: Vec<Channel> = chosen
        .iter()
        .zip(values)
        .zip(bridged)
        .map(|((&i, data), interpolated)| channel(&columns[i], data, interpolated))
        .collect();
    let key = |i: usize| columns::key(&columns[i]);
    let channels_report = chosen
        .iter()
        .zip(carried)
        .zip(held)
        .zip(lined)
        .enumerate()
        .map(|(j, (((&i, c), held_rows), interpolated_rows))| {
            let command_held = if j == 0 { command_held } else { 0 };
            let c = Carried {
                held_rows,
                command_held,
                interpolated_rows,
                ..c
            };
            (key(i), c)
        })
        .collect();
    let names = |range: std::ops::Range<usize>| -> Vec<String> {
        channels[range].iter().map(|c| c.name.clone()).collect()
    };
    let input = picks.input.map(|_| channels[0].name.clone());
    let outputs = names(n_in..n_in + picks.outputs.len());
    let optional = names(n_in + picks.outputs.len()..channels.len());
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
        header: layout.names.is_some(),
        preamble: layout.preamble,
        units_row: layout.units_row,
        decimal_mark: (layout.mark == DecimalMark::Comma).then_some(","),
        midnights,
        encoding: None,
        channels: channels_report,
        units,
        input_range,
        unread,
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
        optional,
        source,
    })
}

/// Why a column asked for beside the outputs whose every cell is 0 or empty is left out.
pub const NO_READING: &str =
    "no reading: every cell is 0 or empty (no sensor on this column), left out";

/// Why a column asked for beside the outputs is left out when another column of its name reads
/// too.
pub const SAME_NAME: &str = "two columns of this name read: which one is meant is not guessed, \
     left out (--columns NAME,NAME,... gives each its own name)";

/// Why a column asked for beside the outputs that the file has once per motor is left out.
pub const ONE_PER_MOTOR: &str =
    "one column per motor: which one belongs beside the output is not guessed, left out";

/// Whether column `i` holds a reading, a number other than 0, in some data line (a stand's
/// export keeps the columns of sensors it does not have, written 0 or left empty).
fn column_reads<'a>(mut data: impl Iterator<Item = &'a str>, layout: &Layout, i: usize) -> bool {
    data.any(|line| {
        fields(line, layout.sep)
            .nth(i)
            .and_then(|f| parse_field(&f, layout.mark))
            .is_some_and(|v| v.is_finite() && v != 0.0)
    })
}

/// An empty field, or a missing marker (`-`, `N/A`, `NULL`, ...: [`is_missing_marker`]), is
/// "not measured" (NaN); other text is `None`; a number is read by the dialect's rule
/// ([`parse_cell`] with the file's decimal mark: `45%` is 45).
fn parse_field(f: &str, mark: DecimalMark) -> Option<f64> {
    if f.is_empty() || is_missing_marker(f) {
        return Some(f64::NAN);
    }
    parse_cell(f, mark)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step at row 50 under `header`, each row ending in `tail`.
    fn steps(header: &str, tail: &str) -> String {
        let mut s = format!("{header}\n");
        for k in 0..100 {
            let (u, y) = (
                if k < 50 { 1300 } else { 1500 },
                if k < 51 { 1.0 } else { 3.0 },
            );
            s += &format!("{},{u},{y}{tail}\n", k as f64 * 0.01);
        }
        s
    }

    #[test]
    fn a_needed_column_whose_name_another_has_is_refused() {
        let none = CsvFileOptions::default();
        let text = steps("t_s,throttle_us,Thrust (N),Thrust (N)", ",2.0");
        let e = read_csv(&text, &none).unwrap_err();
        assert_eq!(
            e,
            CsvFileError::SameName {
                column: "Thrust (N)".into(),
                positions: "3, 4".into()
            }
        );
        assert!(e.to_string().contains("--columns"), "{e}");
        // The time too, by its normalised name.
        let e = read_csv(&steps("t_s,throttle_us,thrust_N,T_S", ",9"), &none).unwrap_err();
        assert!(matches!(e, CsvFileError::SameName { .. }), "{e}");
        // Named apart, it reads.
        let names = ["t_s", "throttle_us", "thrust_N", "other"];
        let apart = CsvFileOptions {
            columns: Some(names.map(String::from).to_vec()),
            ..CsvFileOptions::default()
        };
        assert_eq!(read_csv(&text, &apart).unwrap().outputs, ["thrust_N"]);
        // A column no one asks for may be there twice.
        assert!(read_csv(&steps("t_s,throttle_us,thrust_N,Note,Note", ",a,b"), &none).is_ok());
    }

    #[test]
    fn an_optional_column_twice_is_left_out_when_both_read() {
        let current = CsvFileOptions {
            optional: vec!["current_A".into()],
            ..CsvFileOptions::default()
        };
        let header = "t_s,throttle_us,thrust_N,current_A,current_A";
        let f = read_csv(&steps(header, ",2.0,3.0"), &current).unwrap();
        assert!(f.optional.is_empty());
        assert_eq!(f.source.unread.len(), 1);
        assert_eq!(f.source.unread[0].reason, SAME_NAME);
        // One of them 0 on every row (no sensor): the other is read.
        let f = read_csv(&steps(header, ",0,3.0"), &current).unwrap();
        assert_eq!(f.optional, ["current_A"]);
        assert_eq!(f.record.channel("current_A").unwrap().data[10], 3.0);
    }

    #[test]
    fn cr_only_crlf_and_lf_files_read_alike() {
        let lf = steps("t_s,throttle_us,thrust_N", "");
        let want = read_csv(&lf, &CsvFileOptions::default()).unwrap();
        for end in ["\r", "\r\n"] {
            let text = lf.replace('\n', end);
            assert_eq!(read_csv(&text, &CsvFileOptions::default()).unwrap(), want);
        }
    }
}
