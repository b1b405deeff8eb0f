//! Which columns of a CSV file are used: the file's columns (named by its header or by the
//! caller), the time, input, output and optional columns picked from them, and the record
//! channel each becomes.

use super::layout::Layout;
use super::{CsvFileError, CsvFileOptions, InputChoice};
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
    /// Optional columns the file has (not the input, an output or the time).
    pub(super) optional: Vec<usize>,
    /// Optional columns the file has that are left out, with why ([`super::Unread`]): every
    /// cell 0 or empty (an RPM column of an export whose stand has no such probe) with no
    /// other column of their name that reads ([`super::NO_READING`]), one column per motor
    /// ([`super::ONE_PER_MOTOR`]), or two columns of one name that both read
    /// ([`super::SAME_NAME`]).
    pub(super) silent: Vec<(usize, &'static str)>,
}

impl Picks {
    /// `reads(i)`: whether column `i` holds a reading, a number other than 0, in some row.
    pub(super) fn choose(
        columns: &[Column],
        opts: &CsvFileOptions,
        reads: impl Fn(usize) -> bool,
    ) -> Result<Self, CsvFileError> {
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
            InputChoice::Column(name) => {
                Some(
                    find(columns, name).ok_or_else(|| CsvFileError::MissingColumn {
                        what: "input",
                        wanted: name.clone(),
                        available: available(),
                    })?,
                )
            }
            InputChoice::Command => one_sensor(columns, Quantity::Throttle, "--input NAME")?,
            InputChoice::None => None,
        };
        let outputs: Vec<usize> = if opts.outputs.is_empty() {
            let thrust = one_sensor(columns, Quantity::Thrust, "--output NAME")?;
            if let (None, Some(e)) = (thrust, unitless_thrust(columns)) {
                return Err(e);
            }
            vec![thrust.ok_or_else(|| CsvFileError::MissingColumn {
                what: "output",
                wanted: "thrust (give --output NAME)".into(),
                available: available(),
            })?]
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
        if input.is_none() && opts.input == InputChoice::Command {
            return Err(CsvFileError::NoCommand {
                available: available(),
            });
        }
        let time = if opts.fs_hz.is_some() && time.is_none() {
            None
        } else {
            Some(time.ok_or(CsvFileError::NeedRate)?)
        };
        // A column needed whose name another column has too: which one is meant is not
        // guessed (the first was taken silently).
        for &i in time.iter().chain(&input).chain(&outputs) {
            one_of_its_name(columns, i)?;
        }
        let mut optional: Vec<usize> = Vec::new();
        let mut silent: Vec<(usize, &'static str)> = Vec::new();
        // A quantity already read is not read twice (a `Force (N)` beside the output `Thrust
        // (N)` would be a second thrust channel).
        let quantity = |i: usize| columns[i].spec.map(|s| s.quantity);
        for name in &opts.optional {
            let taken = |i: &usize| {
                let used = || input.iter().chain(&outputs).chain(&optional);
                Some(*i) == time
                    || used().any(|j| j == i)
                    || (quantity(*i).is_some() && used().any(|&j| quantity(j) == quantity(*i)))
            };
            // Of the columns of this name (RCbenchmark writes an electrical and an optical
            // speed, one of them 0 on every row when its sensor is absent), the first that reads.
            let found: Vec<usize> = find_all(columns, name)
                .into_iter()
                .filter(|i| !taken(i))
                .collect();
            // One per motor (`Motor 1 RPM`, `Motor 2 RPM`): which belongs beside the output is
            // not guessed.
            let per_motor = found.iter().any(|&a| {
                found
                    .iter()
                    .any(|&b| csv_columns::indexed_alike(&columns[a].name, &columns[b].name))
            });
            let reading: Vec<usize> = found.iter().copied().filter(|&i| reads(i)).collect();
            let twice = |i: usize| reading.iter().any(|&j| j != i && same_name(columns, i, j));
            match (reading.first(), found.first()) {
                (_, Some(&i)) if per_motor => silent.push((i, super::ONE_PER_MOTOR)),
                (Some(&i), _) if twice(i) => silent.push((i, super::SAME_NAME)),
                (Some(&i), _) => optional.push(i),
                (None, Some(&i)) => silent.push((i, super::NO_READING)),
                (None, None) => {}
            }
        }
        Ok(Self {
            time,
            input,
            outputs,
            optional,
            silent,
        })
    }

    /// Column indices in value order: time, input, outputs, optional.
    pub(super) fn all(&self) -> Vec<usize> {
        self.time.iter().chain(self.channels()).copied().collect()
    }

    /// The columns that become record channels, in order: input, outputs, optional.
    pub(super) fn channels(&self) -> impl Iterator<Item = &usize> + '_ {
        self.input
            .iter()
            .chain(self.outputs.iter())
            .chain(self.optional.iter())
    }
}

/// The first column of quantity `q` (one sensor may be written in two units, `Thrust (kgf)`
/// and `Thrust (N)`), unless the file has the same sensor for several motors (`Motor 1 Thrust
/// (N)`, `Motor 2 Thrust (N)`; [`csv_columns::indexed_alike`]): which motor is not guessed, an
/// error names them and `option`. A column named a thrust is taken before one named by a
/// force's generic words (`Thrust (N)` before a `Force (N)`, `Load (g)` or `Lift (g)` left of
/// it: a second load cell, a drag or a weight).
fn one_sensor(
    columns: &[Column],
    q: Quantity,
    option: &'static str,
) -> Result<Option<usize>, CsvFileError> {
    let of_q: Vec<usize> = (0..columns.len())
        .filter(|&i| columns[i].spec.is_some_and(|s| s.quantity == q))
        .collect();
    let Some(&first) = of_q.first() else {
        return Ok(None);
    };
    let name = |i: usize| columns[i].name.as_str();
    if !of_q
        .iter()
        .any(|&i| csv_columns::indexed_alike(name(i), name(first)))
    {
        let named_thrust = of_q.iter().copied().find(|&i| {
            q == Quantity::Thrust
                && csv_columns::sensor_word(name(i)).ends_with(Quantity::Thrust.key())
        });
        return Ok(Some(named_thrust.unwrap_or(first)));
    }
    Err(CsvFileError::TwoSensors {
        quantity: q.key(),
        columns: of_q
            .iter()
            .map(|&i| columns[i].name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        option,
    })
}

/// Whether columns `i` and `j` have one name (as written, or normalised: `Thrust (N)` and
/// `thrust(N)`).
fn same_name(columns: &[Column], i: usize, j: usize) -> bool {
    let (a, b) = (&columns[i].name, &columns[j].name);
    a == b || csv_columns::normalise(a) == csv_columns::normalise(b)
}

/// Refuses column `i` when another column has its name ([`CsvFileError::SameName`]).
fn one_of_its_name(columns: &[Column], i: usize) -> Result<(), CsvFileError> {
    let same: Vec<String> = (0..columns.len())
        .filter(|&j| same_name(columns, i, j))
        .map(|j| (j + 1).to_string())
        .collect();
    if same.len() < 2 {
        return Ok(());
    }
    Err(CsvFileError::SameName {
        column: columns[i].name.clone(),
        positions: same.join(", "),
    })
}

/// A column by its name as written, its normalised name, or its canonical channel name.
fn find(columns: &[Column], name: &str) -> Option<usize> {
    find_all(columns, name).first().copied()
}

/// The columns of a name as written or normalised, else of that canonical channel name, in
/// file order.
fn find_all(columns: &[Column], name: &str) -> Vec<usize> {
    let want = csv_columns::normalise(name);
    let by_name: Vec<usize> = (0..columns.len())
        .filter(|&i| columns[i].name == name || csv_columns::normalise(&columns[i].name) == want)
        .collect();
    if !by_name.is_empty() {
        return by_name;
    }
    (0..columns.len())
        .filter(|&i| {
            columns[i]
                .spec
                .and_then(|s| s.quantity.channel_name())
                .is_some_and(|n| n.eq_ignore_ascii_case(name))
        })
        .collect()
}

/// The record channel of a column: its canonical name and unit when it has one, else its own
/// name; `interpolated` marks the values carried between its readings.
pub(super) fn channel(col: &Column, data: Vec<f64>, interpolated: Vec<bool>) -> Channel {
    let (name, unit) = match col
        .spec
        .and_then(|s| s.quantity.channel_name().map(|n| (n, s)))
    {
        Some((name, spec)) => (name.to_string(), spec.quantity.canonical_unit().to_string()),
        None => (col.name.clone(), "?".to_string()),
    };
    let interpolated = if interpolated.contains(&true) {
        interpolated
    } else {
        Vec::new()
    };
    Channel {
        name,
        unit,
        data,
        interpolated,
    }
}

/// A column's key in reports: its quantity's ([`Quantity::key`]), else its own name.
pub(super) fn key(col: &Column) -> String {
    col.spec
        .map_or_else(|| col.name.clone(), |s| s.quantity.key().to_string())
}

/// The columns of the file: the names given (`--columns`, also over a header's), else the
/// header's (with the units of a units row); a file with neither is refused
/// ([`CsvFileError::NoHeader`]: no column order is guessed).
/// `first_row` is the first line after the header (its width is the file's).
pub(super) fn header_columns(
    first_row: Option<&str>,
    layout: &Layout,
    opts: &CsvFileOptions,
) -> Result<Vec<Column>, CsvFileError> {
    let named = |name: &str| Column {
        name: name.to_string(),
        spec: csv_columns::lookup(name),
    };
    let width = first_row.map_or(0, |l| fields(l, layout.sep).count());
    match (&opts.columns, &layout.names) {
        (Some(names), _) => {
            let mut cols: Vec<Column> = names.iter().map(|n| named(n)).collect();
            cols.extend((cols.len()..width).map(|i| named(&format!("col{}", i + 1))));
            Ok(cols)
        }
        (None, Some(names)) => Ok(names.iter().map(|n| named(n)).collect()),
        (None, None) => Err(CsvFileError::NoHeader { fields: width }),
    }
}

/// The refusal for a thrust column whose name says no unit, with a `--columns` for the file.
fn unitless_thrust(columns: &[Column]) -> Option<CsvFileError> {
    let i = columns
        .iter()
        .position(|c| csv_columns::unitless(&c.name) == Some(Quantity::Thrust))?;
    let names: Vec<String> = columns
        .iter()
        .enumerate()
        .map(|(j, c)| match j == i {
            true => format!("{} (N)", c.name),
            false => c.name.clone(),
        })
        .collect();
    let example = format!("--columns '{}'", names.join(","));
    Some(CsvFileError::Unitless {
        column: columns[i].name.clone(),
        quantity: Quantity::Thrust.key(),
        units: csv_columns::units_of(Quantity::Thrust),
        example,
    })
}
