//! How a CSV file's columns were read, in words: the lines `identify`'s and `diagnose`'s
//! summaries print under the file's name (one wording for both).

use std::collections::BTreeMap;

use crate::ingest::csv_file::command_range::RAW_SIGNAL;
use crate::ingest::csv_file::ColumnUnit;

/// The command's scale: `"1000..2000 taken as throttle 0..1 (header: µs)"`, or that a signal in
/// its own units was taken as it is; `None` without a range.
pub fn input_range(range: Option<[f64; 2]>, from: Option<&str>) -> Option<String> {
    match (range, from) {
        (Some(_), Some(from)) if from == RAW_SIGNAL => {
            Some(format!("taken as it is, factor 1 ({from})"))
        }
        (Some([lo, hi]), Some(from)) => Some(format!("{lo}..{hi} taken as throttle 0..1 ({from})")),
        _ => None,
    }
}

/// Every channel but the time and the command, with its column, unit and factor to canonical
/// units: `"thrust from Thrust (gf) in gf (x0.00980665)"`, joined by `"; "`; `None` when none.
pub fn units(units: &BTreeMap<String, ColumnUnit>) -> Option<String> {
    let text: Vec<String> = units
        .iter()
        .filter(|(key, _)| *key != "time" && *key != "throttle")
        .map(|(key, u)| format!("{key} from {} in {} (x{})", u.column, u.unit, u.factor))
        .collect();
    (!text.is_empty()).then(|| text.join("; "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lines_name_the_scale_and_every_converted_channel() {
        assert_eq!(
            input_range(Some([1000.0, 2000.0]), Some("header: µs")).as_deref(),
            Some("1000..2000 taken as throttle 0..1 (header: µs)")
        );
        assert_eq!(
            input_range(Some([0.0, 1.0]), Some(RAW_SIGNAL)).as_deref(),
            Some(format!("taken as it is, factor 1 ({RAW_SIGNAL})").as_str())
        );
        assert_eq!(input_range(None, None), None);
        let unit = |column: &str, unit: &str, factor: f64| ColumnUnit {
            column: column.into(),
            unit: unit.into(),
            factor,
            zero: 0.0,
        };
        let mut m = BTreeMap::new();
        m.insert("time".to_string(), unit("Time (s)", "s", 1.0));
        m.insert("throttle".to_string(), unit("ESC", "µs", 0.001));
        assert_eq!(units(&m), None);
        m.insert("thrust".to_string(), unit("Thrust (gf)", "gf", 0.00980665));
        m.insert("rpm".to_string(), unit("RPM", "rev/min", 1.0));
        assert_eq!(
            units(&m).as_deref(),
            Some("rpm from RPM in rev/min (x1); thrust from Thrust (gf) in gf (x0.00980665)")
        );
    }
}
