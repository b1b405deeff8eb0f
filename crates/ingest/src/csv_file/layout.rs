//! Where a CSV file's header and data are: lines of a preamble before the header, the header,
//! a units row under it, the first data row, and the separator.
//!
//! Exports put other things than a header first (`Motor: X2212`, `Date,2024-03-01`, a blank
//! line) and sometimes the units on a row of their own under the names (`Time,Thrust` then
//! `s,gf`). The rule:
//! 1. The first **data row** is the first line of two or more fields that are all empty,
//!    numbers ([`is_cell_number`]: decimal commas and a trailing `%` included), time stamps
//!    ([`parse_clock`]) or missing markers (`-`, `N/A`, `NULL`: [`is_missing_marker`]), at
//!    least one a number; its separator ([`separator`]) is the file's.
//! 2. A file whose first line is a data row has no header.
//! 3. Otherwise the **header** is, among the lines before the first data row that have at
//!    least as many fields as that row, a name the alias table knows and are no units row, the
//!    one with the most names the table maps whole, with their unit (the first of equals: of a
//!    title row `Zeit;Schub` above `Time (s);Thrust (g)`, the second); else the first line
//!    if it has a known name (a header narrower than its rows); else the first line with as many
//!    fields; else the first line. The lines before it are the preamble (counted, not read).
//! 4. A line under the header, before the first data row, whose cells are all units of the unit
//!    table ([`columns::is_unit`]) or empty or `-`, one at least a unit, is a **units row**: each
//!    unit joins its column's name (`Thrust` + `gf` → `Thrust (gf)`).
//! 5. The file's **decimal mark** is the one its data rows show
//!    ([`DecimalMark::of_fields`]: `0,45` for the comma, `0.45` for the point); it decides
//!    fields that either mark reads (`1,234`, `1.300`).

use propid_wire::protocol::csv::columns;
use propid_wire::protocol::csv::line::{
    fields, is_cell_number, is_missing_marker, is_number, parse_clock, separator, DecimalMark,
};

/// The layout of a file's lines (comments and blank lines already left out).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Layout {
    /// The field separator.
    pub(super) sep: char,
    /// The decimal mark of the data rows' numbers.
    pub(super) mark: DecimalMark,
    /// The header's names (units of a units row joined), `None` without a header.
    pub(super) names: Option<Vec<String>>,
    /// Lines before the header.
    pub(super) preamble: usize,
    /// True when a units row was read under the header.
    pub(super) units_row: bool,
    /// Index of the first line after the header (and its units row).
    pub(super) data_start: usize,
}

/// The layout of `lines` (rules of the module documentation); `lines` is not empty.
#[cfg(test)]
pub(super) fn layout(lines: &[&str]) -> Layout {
    layout_of(|| lines.iter().copied())
}

/// The layout of the lines `lines_of()` goes through (each call from the first line): the
/// lines up to the first data row are held, the rest only gone through for the decimal mark,
/// so that a file's lines are not held a second time.
pub(super) fn layout_of<'a, I>(lines_of: impl Fn() -> I) -> Layout
where
    I: Iterator<Item = &'a str>,
{
    // A data row: numbers, empty cells and missing markers (`-`, `N/A`: a sensor that did not
    // report), at least one number.
    let is_data = |l: &str| {
        let sep = separator(l);
        fields(l, sep).count() >= 2
            && fields(l, sep).all(|f| {
                f.is_empty()
                    || is_cell_number(&f)
                    || is_missing_marker(&f)
                    || parse_clock(&f).is_some()
            })
            && fields(l, sep).any(|f| is_number(&f))
    };
    // The lines up to the first data row (all of them when there is none).
    let mut lines: Vec<&str> = Vec::new();
    let mut first_data = None;
    for l in lines_of() {
        lines.push(l);
        if is_data(l) {
            first_data = Some(lines.len() - 1);
            break;
        }
    }
    let sep = separator(lines[first_data.unwrap_or(0)]);
    let mark_from =
        |start: usize| DecimalMark::of_fields(lines_of().skip(start).flat_map(|l| fields(l, sep)));
    if first_data == Some(0) {
        return Layout {
            sep,
            mark: mark_from(0),
            names: None,
            preamble: 0,
            units_row: false,
            data_start: 0,
        };
    }
    let before = first_data.unwrap_or(1);
    let width = first_data.map_or(0, |d| fields(lines[d], sep).count());
    let wide = |l: &&str| fields(l, sep).count() >= width;
    let known = |l: &&str| {
        fields(l, sep).any(|f| columns::lookup(&f).is_some() || columns::unitless(&f).is_some())
    };
    // Of two stacked name rows (a title row of quantity words above the names with their
    // units, two languages), the one whose names map with a unit; a units row is no header.
    let mapped = |l: &&str| {
        fields(l, sep)
            .filter(|f| columns::lookup(f).is_some())
            .count()
    };
    let candidates = &lines[..before];
    let header = candidates
        .iter()
        .enumerate()
        .filter(|(_, l)| wide(l) && known(l) && !is_units_row(l, sep))
        .max_by_key(|&(i, l)| (mapped(l), std::cmp::Reverse(i)))
        .map(|(i, _)| i)
        .or_else(|| known(&candidates[0]).then_some(0))
        .or_else(|| candidates.iter().position(wide))
        .unwrap_or(0);
    let mut names: Vec<String> = fields(lines[header], sep).map(|f| f.into_owned()).collect();
    let units_row = header + 1 < before && is_units_row(lines[header + 1], sep);
    if units_row {
        for (name, unit) in names.iter_mut().zip(fields(lines[header + 1], sep)) {
            if !unit.is_empty() && unit != "-" {
                *name = if unit.starts_with(['(', '[']) {
                    format!("{name} {unit}")
                } else {
                    format!("{name} ({unit})")
                };
            }
        }
    }
    let data_start = header + 1 + usize::from(units_row);
    Layout {
        sep,
        mark: mark_from(data_start),
        names: Some(names),
        preamble: header,
        units_row,
        data_start,
    }
}

/// Rule 4: every cell a unit, empty or `-`, one at least a unit.
fn is_units_row(line: &str, sep: char) -> bool {
    let mut any = false;
    for f in fields(line, sep) {
        if columns::is_unit(&f) {
            any = true;
        } else if !(f.is_empty() || f == "-") {
            return false;
        }
    }
    any
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preamble_header_and_units_row() {
        let lines = [
            "Motor: X2212 920KV",
            "Propeller,10x4.5",
            "Time,Throttle,Thrust,Torque,Note",
            "s,%,gf,N·mm,",
            "0.0,30,120.5,3.1,",
            "0.1,30,121.5,3.2,tare",
        ];
        let l = layout(&lines);
        assert_eq!(l.sep, ',');
        assert_eq!(l.preamble, 2);
        assert!(l.units_row);
        assert_eq!(l.data_start, 4);
        assert_eq!(
            l.names.unwrap(),
            [
                "Time (s)",
                "Throttle (%)",
                "Thrust (gf)",
                "Torque (N·mm)",
                "Note"
            ]
        );
    }

    #[test]
    fn a_header_first_a_numbers_first_and_a_text_first_row() {
        let l = layout(&["t_s,thrust_N", "0,1"]);
        assert_eq!((l.preamble, l.units_row, l.data_start), (0, false, 1));
        let l = layout(&["0,1", "1,2"]);
        assert_eq!((l.names, l.data_start), (None, 0));
        // The first data row carries text in a column (an app message): the header is still the
        // first line, the text row is data.
        let l = layout(&["Time (s),Thrust (N),Msg", "0,1,started", "0.1,1.1,"]);
        assert_eq!((l.preamble, l.data_start), (0, 1));
        // Decimal commas, `;`-separated.
        let l = layout(&["Zeit;Schub", "Time (s);Thrust (g)", "0,01;12,5"]);
        assert_eq!((l.sep, l.preamble, l.data_start), (';', 1, 2));
        assert_eq!(l.mark, DecimalMark::Comma);
        // Thousands in a tab file with decimal points; in quoted fields of a `,` file.
        let l = layout(&["Time (s)\teRPM", "0.010\t12,345", "0.020\t12,346"]);
        assert_eq!((l.sep, l.mark, l.data_start), ('\t', DecimalMark::Point, 1));
        // `;` with decimal points and thousands commas.
        let l = layout(&["Time (s);Thrust (g)", "0.010;1,234.5", "0.020;12,345"]);
        assert_eq!((l.sep, l.mark, l.data_start), (';', DecimalMark::Point, 1));
        // Stray and escaped quotes in the header: each name its own field.
        let l = layout(&[
            "Time (s),Torque (in-oz\"),\"Thrust \"\"gf\"\"\",Prop",
            "0.010,1.5,305.1,5\"x4.5",
        ]);
        let names = ["Time (s)", "Torque (in-oz\")", "Thrust \"gf\"", "Prop"];
        assert_eq!(l.names.as_deref(), Some(&names.map(String::from)[..]));
        let l = layout(&["\"t (s)\",\"F (N)\"", "\"0,010\",\"1,234\""]);
        assert_eq!((l.sep, l.mark, l.data_start), (',', DecimalMark::Comma, 1));
        // A header narrower than its rows (trailing separators on data rows only), a text row
        // first: still the first line.
        let l = layout(&["t_s,thrust_N", "x,1,a,b", "0,1,,"]);
        assert_eq!((l.preamble, l.data_start), (0, 1));
    }
}
