//! Every used column of a CSV file into canonical units: a command, or an input column of
//! unknown unit, by its decided scale ([`command_range`]), any other by the one unit table
//! ([`protocol::csv::columns`](propid_wire::protocol::csv::columns)), each reported with its
//! column, unit and factor ([`ColumnUnit`]).

use std::collections::BTreeMap;

use super::columns::{self, Column, Picks};
use super::command_range::unknown_input_range;
use super::{
    command_range, ColumnUnit, CommandRange, CsvFileError, CsvFileOptions, GivenRanges, Unread,
    DEFAULT_ESC_US,
};
use propid_wire::protocol::csv::columns::{
    Affine, ColumnSpec, ConvError, ConvOptions, Quantity, Unit,
};

/// What [`convert`] did: the units report, the command's scale, the optional columns left out.
pub(super) struct Converted {
    pub(super) units: BTreeMap<String, ColumnUnit>,
    pub(super) input_range: Option<CommandRange>,
    pub(super) unread: Vec<Unread>,
}

/// Converts every used column to canonical units in place: a command by its decided scale
/// ([`command_range`]), any other by the unit table. An optional column that cannot be
/// converted is dropped from `picks` and `values`, and said ([`Unread`]).
pub(super) fn convert(
    columns: &[Column],
    picks: &mut Picks,
    values: &mut Vec<Vec<f64>>,
    opts: &CsvFileOptions,
) -> Result<Converted, CsvFileError> {
    let conv = ConvOptions {
        esc_min_us: Some(opts.esc_us.unwrap_or(DEFAULT_ESC_US).0),
        esc_max_us: Some(opts.esc_us.unwrap_or(DEFAULT_ESC_US).1),
        motor_poles: opts.motor_poles,
    };
    let given = GivenRanges {
        input_range: opts.input_range,
        esc_us: opts.esc_us,
    };
    let mut units = BTreeMap::new();
    let mut input_range = None;
    let mut dropped = Vec::new();
    let mut unread = Vec::new();
    let used = picks.all();
    for (n, &i) in used.iter().enumerate() {
        let col = &columns[i];
        let optional = picks.optional.contains(&i);
        let is_command = col.spec.is_some_and(|s| s.unit.command_scales().is_some());
        let scale = match (col.spec, opts.input_range) {
            // `--input-range` scales the input whatever the table knows of its name.
            (_, Some(range)) if picks.input == Some(i) && !is_command => {
                Some(Ok(CommandRange::given_input(range)))
            }
            (Some(spec), _) => command_range(spec.unit, &values[n], &given),
            // An input the table does not know: read as a bare command, raw when signed.
            (None, _) if picks.input == Some(i) => Some(unknown_input_range(&values[n], &given)),
            (None, _) => None,
        };
        let (affine, unit) = match (scale, col.spec) {
            (Some(Ok(r)), _) => {
                let out = (r.affine(), r.unit.to_string());
                if picks.input == Some(i) {
                    input_range = Some(r);
                }
                out
            }
            (Some(Err(source)), _) => {
                return Err(CsvFileError::CommandRange {
                    column: col.name.clone(),
                    source,
                })
            }
            // Unix time stamps in s (with a fraction), ms, µs or ns (a logger's `timestamp`,
            // with or without a unit in its name): their size says which.
            (
                None,
                None
                | Some(ColumnSpec {
                    unit: Unit::Clock, ..
                }),
            ) if picks.time == Some(i) && epoch_unit(&values[n], col.spec.is_none()).is_some() => {
                let (div, unit, first) =
                    epoch_unit(&values[n], col.spec.is_none()).unwrap_or((1.0, "s", 0.0));
                // Counted from the first stamp (its `zero`), so that 10¹² ms keep their
                // resolution as seconds.
                let affine = Affine {
                    zero: first,
                    mul: 1.0,
                    div,
                };
                (affine, unit.to_string())
            }
            (None, None) if picks.time == Some(i) && counts_ticks(&values[n]) => {
                return Err(CsvFileError::UnitlessTime {
                    column: col.name.clone(),
                })
            }
            (None, None) => (Affine::IDENTITY, time_or_unknown(picks, i)),
            (None, Some(spec)) => match spec.conversion(&conv) {
                Ok(a) => (a, spec.unit.symbol().to_string()),
                Err(e) if optional => {
                    dropped.push(n);
                    unread.push(Unread {
                        column: col.name.clone(),
                        reason: needs(e),
                    });
                    continue;
                }
                Err(e) => {
                    return Err(CsvFileError::Conversion {
                        column: col.name.clone(),
                        reason: needs(e),
                    })
                }
            },
        };
        for v in &mut values[n] {
            *v = affine.apply(*v);
        }
        let key = if picks.time == Some(i) {
            Quantity::Time.key().to_string()
        } else {
            columns::key(col)
        };
        units.insert(
            key,
            ColumnUnit {
                column: col.name.clone(),
                unit,
                factor: affine.factor(),
                zero: affine.zero,
            },
        );
    }
    for &n in dropped.iter().rev() {
        values.remove(n);
        picks.optional.retain(|&i| i != used[n]);
    }
    Ok(Converted {
        units,
        input_range,
        unread,
    })
}

/// What a conversion lacks, with the option that gives it.
fn needs(e: ConvError) -> String {
    let option = match e {
        ConvError::NeedsPoles => "--poles N",
        ConvError::NeedsEscRange => "--esc-us MIN,MAX",
        ConvError::NeedsRange => "--input-range MIN,MAX",
    };
    format!("{e}: give {option}")
}

/// True when a time column without a unit holds whole numbers stepping by 1 or more (the
/// median step): milliseconds or microseconds of a logger's clock (`millis()`), not seconds of
/// a stand logging once a second or slower — not to be taken as seconds in silence.
fn counts_ticks(t: &[f64]) -> bool {
    let finite: Vec<f64> = t.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.len() < 2 || finite.iter().any(|v| v.fract() != 0.0) {
        return false;
    }
    let mut steps: Vec<f64> = finite
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    if steps.is_empty() {
        return false;
    }
    let mid = steps.len() / 2;
    let (_, median, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
    *median >= 1.0
}

/// Earliest and latest plausible Unix time of a log, s (2000-01-01, 2100-01-01).
const UNIX_SPAN_S: [f64; 2] = [946_684_800.0, 4_102_444_800.0];

/// The divisor to seconds and the unit of a time column of Unix time stamps in milliseconds,
/// microseconds or nanoseconds, when every number of it is one (between 2000 and 2100 in that
/// unit: the three ranges are a thousandfold apart, and no clock since boot reaches them: 10¹²
/// ms is 31 years). Whole seconds are not inferred: a count of 10⁹ could be a microsecond
/// counter 17 minutes after boot as well; seconds with a fraction (`1732449600.125`, no counter
/// writes them) are, and said, in a column without a unit (`seconds`: false for a date-time
/// column, whose stamps the reader has made Unix seconds already). Also the first stamp.
fn epoch_unit(t: &[f64], seconds: bool) -> Option<(f64, &'static str, f64)> {
    let mut finite = t.iter().copied().filter(|v| v.is_finite()).peekable();
    let first = *finite.peek()?;
    let (lo, hi, fraction) = finite
        .fold((f64::INFINITY, f64::NEG_INFINITY, false), |(a, b, f), v| {
            (a.min(v), b.max(v), f || v.fract() != 0.0)
        });
    [
        (1.0, "s (Unix time)"),
        (1e3, "ms (Unix time)"),
        (1e6, "µs (Unix time)"),
        (1e9, "ns (Unix time)"),
    ]
    .into_iter()
    .filter(|(div, _)| *div > 1.0 || (fraction && seconds))
    .find(|(div, _)| lo >= UNIX_SPAN_S[0] * div && hi <= UNIX_SPAN_S[1] * div)
    .map(|(div, unit)| (div, unit, first))
}

/// The unit of a column the table does not know: seconds for a time column found by its name
/// (`t`, `time`), `?` otherwise.
fn time_or_unknown(picks: &Picks, i: usize) -> String {
    if picks.time == Some(i) {
        Quantity::Time.canonical_unit().to_string()
    } else {
        "?".to_string()
    }
}
