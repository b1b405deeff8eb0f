//! Numbers of the CSV dialect, rule 5 of the [line rules](super): a decimal point or a decimal
//! comma, thousands grouped by the other mark, and the mark a file's rows show.

use super::between_digits;

/// The decimal mark of a file's numbers (rule 5 of the [line rules](super)); the
/// other mark groups thousands.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum DecimalMark {
    /// `1,234.5`, `0.45`.
    Point,
    /// `1.234,5`, `0,45`.
    Comma,
    /// The file's rows show neither (or both alike): a field with one mark reads it as its
    /// decimal mark (`1,234` is 1.234, `1.234` is 1.234), thousands only where nothing else
    /// reads (`1,234,567`).
    #[default]
    Unshown,
}

impl DecimalMark {
    /// The decimal mark and the thousands separator.
    fn marks(self) -> (char, char) {
        match self {
            DecimalMark::Point | DecimalMark::Unshown => ('.', ','),
            DecimalMark::Comma => (',', '.'),
        }
    }

    fn other(self) -> Self {
        match self {
            DecimalMark::Point => DecimalMark::Comma,
            DecimalMark::Comma => DecimalMark::Point,
            DecimalMark::Unshown => DecimalMark::Unshown,
        }
    }

    /// The mark a file's fields show: a field that only one mark reads (`0,45`, `12,3`,
    /// `1.234,5` for the comma; `0.45`, `1,234.5` for the point) is a vote for it; the mark
    /// with more votes is the file's, [`DecimalMark::Unshown`] when neither has more. Fields
    /// either mark reads alike (`12`) or differently (`1,234`) and text say nothing.
    pub fn of_fields<S: AsRef<str>>(fields: impl IntoIterator<Item = S>) -> Self {
        let (mut point, mut comma) = (0usize, 0usize);
        for f in fields {
            let f = f.as_ref();
            match (read_as(f, Self::Point), read_as(f, Self::Comma)) {
                (Some(_), None) => point += 1,
                (None, Some(_)) => comma += 1,
                _ => {}
            }
        }
        match comma.cmp(&point) {
            std::cmp::Ordering::Greater => Self::Comma,
            std::cmp::Ordering::Less => Self::Point,
            std::cmp::Ordering::Equal => Self::Unshown,
        }
    }
}

/// `field` as a number written with decimal mark `mark` and the other mark between groups of
/// three digits (`1,234,567.5`); without a thousands separator, Rust's `f64` syntax (with a
/// decimal comma: one `,` between two digits). `None` when it is not written so.
fn read_as(field: &str, mark: DecimalMark) -> Option<f64> {
    let (decimal, group) = mark.marks();
    if !field.contains(group) {
        if decimal == '.' {
            return field.parse().ok();
        }
        return match field.matches(',').count() {
            0 => field.parse().ok(),
            1 if between_digits(field.as_bytes(), field.find(',')?) => {
                field.replacen(',', ".", 1).parse().ok()
            }
            _ => None,
        };
    }
    let body = field.strip_prefix(['-', '+']).unwrap_or(field);
    let (int, frac) = match body.split_once(decimal) {
        Some((i, f)) => (i, Some(f)),
        None => (body, None),
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|c| c.is_ascii_digit());
    let mut groups = int.split(group);
    let first = groups.next()?;
    let grouped = digits(first)
        && first.len() <= 3
        && !first.starts_with('0')
        && groups.all(|g| g.len() == 3 && digits(g));
    if !grouped || frac.is_some_and(|f| !digits(f)) {
        return None;
    }
    let mut plain: String = field.chars().filter(|&c| c != group).collect();
    if decimal == ',' {
        plain = plain.replacen(',', ".", 1);
    }
    plain.parse().ok()
}

/// A field as a number in a file whose decimal mark is `mark` (rule 5 of the
/// [line rules](super)): read with that mark, the other one grouping thousands; a
/// field with a single mark that `mark` cannot read (`2.5` or `0,25` where the file's mark is
/// the other) is read with its own; where the file shows no mark, a field with one mark reads
/// it as its decimal mark. `None` for anything else (text, `1.2.3`).
pub fn parse_number(field: &str, mark: DecimalMark) -> Option<f64> {
    let single = field.matches([',', '.']).count() == 1;
    match mark {
        DecimalMark::Unshown => {
            let own = match single && field.contains(',') {
                true => DecimalMark::Comma,
                false => DecimalMark::Point,
            };
            read_as(field, own).or_else(|| read_as(field, own.other()))
        }
        m => read_as(field, m).or_else(|| single.then(|| read_as(field, m.other())).flatten()),
    }
}

/// A cell as a number ([`parse_number`]), also with a percent sign after it (`45%`, `45 %`: a
/// spreadsheet's percent format keeps the sign in the text it exports; the number is the
/// percentage, the column's unit says what it is of).
pub fn parse_cell(field: &str, mark: DecimalMark) -> Option<f64> {
    parse_number(field, mark).or_else(|| parse_number(percent(field)?, mark))
}

/// True when `field` is a number written with either decimal mark, also with a percent sign
/// after it ([`parse_cell`]).
pub fn is_cell_number(field: &str) -> bool {
    is_number(field) || percent(field).is_some_and(is_number)
}

/// The number before a trailing percent sign, `None` without one.
fn percent(field: &str) -> Option<&str> {
    field.strip_suffix('%').map(str::trim_end)
}

/// Cell texts an exported log writes for "no value" (compared without case, trimmed): a
/// spreadsheet's `#N/A`, a database's `NULL`, pandas' `NaN` and `None`, a person's `-` or `n/a`.
/// In a file they are an empty cell: a missing value of that channel only, never text that
/// makes the row unreadable.
pub const MISSING_MARKERS: [&str; 8] = ["-", "--", "n/a", "na", "#n/a", "null", "none", "nan"];

/// True when `field` is one of [`MISSING_MARKERS`].
pub fn is_missing_marker(field: &str) -> bool {
    let f = field.trim();
    MISSING_MARKERS.iter().any(|m| f.eq_ignore_ascii_case(m))
}

/// True when `field` is a number written with either decimal mark.
pub fn is_number(field: &str) -> bool {
    read_as(field, DecimalMark::Point).is_some() || read_as(field, DecimalMark::Comma).is_some()
}

#[cfg(test)]
mod tests {
    use super::super::{fields, is_numeric, separator};
    use super::*;

    #[test]
    fn missing_markers_are_known_without_case_and_numbers_are_not_markers() {
        for m in [
            "-", "--", "N/A", "n/a", "NA", "#N/A", "NULL", "None", "NaN", " nan ",
        ] {
            assert!(is_missing_marker(m), "{m}");
        }
        for f in ["", "0", "-1", "1-2", "n", "none yet", "x"] {
            assert!(!is_missing_marker(f), "{f}");
        }
    }

    #[test]
    fn thousands_separators_with_either_decimal_mark() {
        let (point, comma) = (DecimalMark::Point, DecimalMark::Comma);
        // Unambiguous: the last mark is the decimal one, the other groups by three.
        assert_eq!(parse_number("1.234,5", comma), Some(1234.5));
        assert_eq!(parse_number("-1.234.567,25", comma), Some(-1_234_567.25));
        assert_eq!(parse_number("1,234.5", point), Some(1234.5));
        assert_eq!(parse_number("12,345", point), Some(12345.0));
        assert_eq!(parse_number("1,234,567", point), Some(1_234_567.0));
        // One mark then three digits: the file's mark decides.
        assert_eq!(parse_number("1,234", comma), Some(1.234));
        assert_eq!(parse_number("1.234", point), Some(1.234));
        assert_eq!(parse_number("1.300", comma), Some(1300.0));
        // Not groups of three, a leading zero group, the marks mixed up: not a number.
        for bad in [
            "1,23.5",
            "1.2345,6",
            "0.123,4",
            "1,234,5.6",
            "12,34,567",
            "1.2.3",
        ] {
            assert_eq!(parse_number(bad, point), None, "{bad}");
            assert_eq!(parse_number(bad, comma), None, "{bad}");
        }
        assert_eq!(parse_number("1,234.5", comma), None);
        assert_eq!(parse_number("1.234,5", point), None);
        // Separators: thousands in a tab or `;` line are not the separator.
        assert_eq!(separator("1,234.5\t0.45"), '\t');
        assert_eq!(separator("0,010;1.300,0;42.000"), ';');
        assert!(is_numeric("0,010;1.300,0;42.000", ';'));
    }

    #[test]
    fn semicolon_files_with_decimal_points_and_thousands_commas() {
        // A European-locale export with English numbers: `;` separates, `,` groups thousands.
        let rows = ["1,234.5;0.45;12,345", "1,240.0;0.46;12,400;-1,000.5"];
        assert!(rows.iter().all(|r| separator(r) == ';'));
        let mark = DecimalMark::of_fields(rows.iter().flat_map(|r| fields(r, ';')));
        assert_eq!(mark, DecimalMark::Point);
        let read = |r: &str| -> Vec<Option<f64>> {
            fields(r, ';').map(|f| parse_number(&f, mark)).collect()
        };
        assert_eq!(
            read(rows[1]),
            [Some(1240.0), Some(0.46), Some(12400.0), Some(-1000.5)]
        );
        assert_eq!(read(rows[0]), [Some(1234.5), Some(0.45), Some(12345.0)]);
        // The same shapes with decimal commas are still decimal commas.
        let eu = ["0,45;12,3;1.234,5", "0,46;12,4;1.300"];
        assert!(eu.iter().all(|r| separator(r) == ';'));
        let mark = DecimalMark::of_fields(eu.iter().flat_map(|r| fields(r, ';')));
        assert_eq!(mark, DecimalMark::Comma);
        let read: Vec<Option<f64>> = fields(eu[1], ';').map(|f| parse_number(&f, mark)).collect();
        assert_eq!(read, [Some(0.46), Some(12.4), Some(1300.0)]);
    }

    #[test]
    fn a_files_fields_show_its_decimal_mark() {
        let mark =
            |rows: &[&str], sep| DecimalMark::of_fields(rows.iter().flat_map(|r| fields(r, sep)));
        // `0,010` only a comma reads: `1.300` is then 1300, not 1.3.
        let eu = ["0,000;1.300;307,23", "0,010;1.300;307,39"];
        assert_eq!(mark(&eu, ';'), DecimalMark::Comma);
        // `0.010` only a point reads: `12,345` is then 12345.
        let tab = ["0.000\t1,300\t12,345", "0.010\t1,300\t12,345"];
        assert_eq!(mark(&tab, '\t'), DecimalMark::Point);
        // A plain `,` file: its fields hold no comma, `1.234` stays 1.234.
        let plain = ["1.234,1.500,1000", "1.235,1.501,1001"];
        assert_eq!(mark(&plain, ','), DecimalMark::Unshown);
        assert_eq!(parse_number("1.234", mark(&plain, ',')), Some(1.234));
        // Nothing to tell (integers, text, one mark then three digits): each field's one mark
        // is its decimal mark; thousands only where nothing else reads.
        let unshown = mark(&["12;x;1,234"], ';');
        assert_eq!(unshown, DecimalMark::Unshown);
        assert_eq!(parse_number("1,234", unshown), Some(1.234));
        assert_eq!(parse_number("1.234", unshown), Some(1.234));
        assert_eq!(parse_number("1,234,567", unshown), Some(1_234_567.0));
        assert_eq!(parse_number("1.234,5", unshown), Some(1234.5));
        assert_eq!(parse_number("12", unshown), Some(12.0));
    }

    #[test]
    fn a_percent_sign_after_a_cells_number_is_read_past() {
        assert_eq!(parse_cell("45%", DecimalMark::Point), Some(45.0));
        assert_eq!(parse_cell("45 %", DecimalMark::Point), Some(45.0));
        assert_eq!(parse_cell("4,5%", DecimalMark::Comma), Some(4.5));
        assert_eq!(parse_cell("0.45", DecimalMark::Point), Some(0.45));
        for not in ["%", "abc%", "45%%", "% 45", "4 5%"] {
            assert_eq!(parse_cell(not, DecimalMark::Point), None, "{not}");
            assert!(!is_cell_number(not), "{not}");
        }
        assert!(is_cell_number("12,5 %"));
        assert!(!is_number("12,5 %"));
    }
}
