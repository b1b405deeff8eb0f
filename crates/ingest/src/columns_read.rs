//! How a CSV file's channels were read: per channel the column, its unit and the factor to
//! canonical units, and the command's scale. `identify` and `diagnose` publish it in their
//! `source` under the same names (`units`, `input_range`, `input_range_from`) and print it in
//! their summaries in the same words.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::csv_file::command_range::RAW_SIGNAL;
use crate::csv_file::{ColumnUnit, CsvSource};

/// The reading of a CSV file's columns (all `None` for a TSP/1 recording).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ColumnsRead {
    /// Per channel, the column, its unit and the factor to canonical units (the command's: to
    /// throttle 0..1), by key (`throttle`, `thrust`, `torque`, `rpm`, ...).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub units: Option<BTreeMap<String, ColumnUnit>>,
    /// The raw command values taken as throttle 0 and 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input_range: Option<[f64; 2]>,
    /// Where `input_range` came from: `"header: µs"`, `"values: 0..1"`,
    /// `"values: 0..2047 (DShot/raw ESC)"`, `"--esc-us"`, `"--input-range"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input_range_from: Option<String>,
}

impl ColumnsRead {
    /// Of a CSV file's source (`None`: a recording, nothing to say).
    pub fn of(csv: Option<&CsvSource>) -> ColumnsRead {
        let Some(csv) = csv else {
            return ColumnsRead::default();
        };
        ColumnsRead {
            units: Some(csv.units.clone()),
            input_range: csv.input_range.as_ref().map(|r| [r.raw_min, r.raw_max]),
            input_range_from: csv.input_range.as_ref().map(|r| r.from.clone()),
        }
    }

    /// The command's scale in words: `"1000..2000 taken as throttle 0..1 (header: µs)"`, or
    /// that a signal in its own units was taken as it is; `None` without a range.
    pub fn input_range_line(&self) -> Option<String> {
        match (self.input_range, self.input_range_from.as_deref()) {
            (Some(_), Some(from)) if from == RAW_SIGNAL => {
                Some(format!("taken as it is, factor 1 ({from})"))
            }
            (Some([lo, hi]), Some(from)) => {
                Some(format!("{lo}..{hi} taken as throttle 0..1 ({from})"))
            }
            _ => None,
        }
    }

    /// Every channel but the time and the command, with its column, unit and factor:
    /// `"thrust from Thrust (gf) in gf (x0.00980665)"`, joined by `"; "`; `None` when none.
    pub fn units_line(&self) -> Option<String> {
        let text: Vec<String> = self
            .units
            .iter()
            .flatten()
            .filter(|(key, _)| *key != "time" && *key != "throttle")
            .map(|(key, u)| format!("{key} from {} in {} (x{})", u.column, u.unit, u.factor))
            .collect();
        (!text.is_empty()).then(|| text.join("; "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lines_name_the_scale_and_every_converted_channel() {
        let range = |r: [f64; 2], from: &str| ColumnsRead {
            input_range: Some(r),
            input_range_from: Some(from.into()),
            ..ColumnsRead::default()
        };
        assert_eq!(
            range([1000.0, 2000.0], "header: µs")
                .input_range_line()
                .as_deref(),
            Some("1000..2000 taken as throttle 0..1 (header: µs)")
        );
        assert_eq!(
            range([0.0, 1.0], RAW_SIGNAL).input_range_line(),
            Some(format!("taken as it is, factor 1 ({RAW_SIGNAL})"))
        );
        assert_eq!(ColumnsRead::default().input_range_line(), None);
        let unit = |column: &str, unit: &str, factor: f64| ColumnUnit {
            column: column.into(),
            unit: unit.into(),
            factor,
            zero: 0.0,
        };
        let mut m = BTreeMap::new();
        m.insert("time".to_string(), unit("Time (s)", "s", 1.0));
        m.insert("throttle".to_string(), unit("ESC", "µs", 0.001));
        let mut read = ColumnsRead {
            units: Some(m.clone()),
            ..ColumnsRead::default()
        };
        assert_eq!(read.units_line(), None);
        m.insert("thrust".to_string(), unit("Thrust (gf)", "gf", 0.00980665));
        m.insert("rpm".to_string(), unit("RPM", "rev/min", 1.0));
        read.units = Some(m);
        assert_eq!(
            read.units_line().as_deref(),
            Some("rpm from RPM in rev/min (x1); thrust from Thrust (gf) in gf (x0.00980665)")
        );
    }
}
