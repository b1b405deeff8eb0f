//! Why bytes could not become a record.

use crate::protocol::csv::columns::ConvError;

/// Why bytes could not become a record.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IngestError {
    /// No bytes at all.
    #[error("the input is empty")]
    Empty,
    /// Bytes, but not one SAMPLE frame or data row in them.
    #[error("no samples in the input (no valid SAMPLE frame or CSV data row)")]
    NoSamples,
    /// The sample period cannot be known: no usable time column, no device clock span, no
    /// HELLO rate and no rate given.
    #[error(
        "no time base: the data has no usable time column or device clock and no rate was given"
    )]
    NoTimebase,
    /// The sample period came out non-positive or not finite.
    #[error("sample period {0} s is not a positive finite number")]
    BadSamplePeriod(f64),
    /// A CSV column needs an option to be converted (ESC range, motor poles).
    #[error("CSV column '{column}': {reason}")]
    NeedsOption {
        /// The column name as written.
        column: String,
        /// What is missing.
        reason: ConvError,
    },
    /// A given option is out of range.
    #[error("option {name} = {value} is out of range")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Its value.
        value: f64,
    },
}
