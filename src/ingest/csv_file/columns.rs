//! Which columns of a CSV file are used: the file's columns (named by its header, by the
//! caller, or by §6's default order), the time, input and output columns picked from them, and
//! the record channel each becomes.

use super::{CsvFileError, CsvFileOptions};
use propid_wire::protocol::csv::columns::{self as csv_columns, ColumnSpec, Quantity};
use propid_wire::protocol::csv::line::fields;
use propid_wire::record::Channel;

/// One column of the file.
#[derive(Debug, Clone)]
pub(super) struct Column {
    pub(super) name: String,
    pub(super) spec: Option<ColumnSpec>,
}

/// The columns used, as indices into the file's columns.
pub(super) struct Picks {
    pub(super) time: Option<usize>,
    pub(super) input: Option<usize>,
    pub(super) outputs: Vec<usize>,
}

impl Picks {
    pub(super) fn choose(columns: &[Column], opts: &CsvFileOptions) -> Result<Self, CsvFileError> {
        let available = || {
            columns
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let by_quantity = |q: Quantity| {
            columns
                .iter()
                .position(|c| c.spec.is_some_and(|s| s.quantity == q))
        };
        let time = by_quantity(Quantity::Time).or_else(|| {
            columns
                .iter()
                .position(|c| matches!(csv_columns::normalise(&c.name).as_str(), "t" | "time"))
        });
        let input = match &opts.input {
            Some(name) => Some(
                find(columns, name).ok_or_else(|| CsvFileError::MissingColumn {
                    what: "input",
                    wanted: name.clone(),
                    available: available(),
                })?,
            ),
            None => by_quantity(Quantity::Throttle),
        };
        let outputs = if opts.outputs.is_empty() {
            vec![
                by_quantity(Quantity::Thrust).ok_or_else(|| CsvFileError::MissingColumn {
                    what: "output",
                    wanted: "thrust (give --output NAME)".into(),
                    available: available(),
                })?,
            ]
        } else {
            opts.outputs
                .iter()
                .map(|name| {
                    find(columns, name).ok_or_else(|| CsvFileError::MissingColumn {
                        what: "output",
                        wanted: name.clone(),
                        available: available(),
                    })
                })
                .collect::<Result<_, _>>()?
        };
        let time = if opts.fs_hz.is_some() && time.is_none() {
            None
        } else {
            Some(time.ok_or(CsvFileError::NeedRate)?)
        };
        Ok(Self {
            time,
            input,
            outputs,
        })
    }

    /// Column indices in value order: time, input, outputs.
    pub(super) fn all(&self) -> Vec<usize> {
        self.time
            .iter()
            .chain(self.input.iter())
            .chain(self.outputs.iter())
            .copied()
            .collect()
    }
}

/// A column by its name as written, its normalised name, or its canonical channel name.
fn find(columns: &[Column], name: &str) -> Option<usize> {
    let want = csv_columns::normalise(name);
    columns
        .iter()
        .position(|c| c.name == name || csv_columns::normalise(&c.name) == want)
        .or_else(|| {
            columns.iter().position(|c| {
                c.spec
                    .and_then(|s| s.quantity.channel_name())
                    .is_some_and(|n| n.eq_ignore_ascii_case(name))
            })
        })
}

/// The record channel of a column: its canonical name and unit when it has one, else its own
/// name.
pub(super) fn channel(col: &Column, data: Vec<f64>) -> Channel {
    match col
        .spec
        .and_then(|s| s.quantity.channel_name().map(|n| (n, s)))
    {
        Some((name, spec)) => Channel {
            name: name.to_string(),
            unit: spec.quantity.canonical_unit().to_string(),
            data,
        },
        None => Channel {
            name: col.name.clone(),
            unit: "?".into(),
            data,
        },
    }
}

/// The columns of the file: the header's names, else the names given, else §6's order.
pub(super) fn header_columns(
    lines: &[&str],
    sep: char,
    header: bool,
    opts: &CsvFileOptions,
) -> Vec<Column> {
    let named = |name: &str| Column {
        name: name.to_string(),
        spec: csv_columns::lookup(name),
    };
    if header {
        return fields(lines[0], sep).map(named).collect();
    }
    let width = fields(lines[0], sep).count();
    if let Some(names) = &opts.columns {
        let mut cols: Vec<Column> = names.iter().map(|n| named(n)).collect();
        cols.extend((cols.len()..width).map(|i| named(&format!("col{}", i + 1))));
        return cols;
    }
    (0..width)
        .map(|i| match csv_columns::DEFAULT_ORDER.get(i) {
            Some(spec) => Column {
                name: spec.quantity.name().to_string(),
                spec: Some(*spec),
            },
            None => named(&format!("col{}", i + 1)),
        })
        .collect()
}
