//! Bytes and files into [`Record`](crate::record::Record)s.
//!
//! - [`tsp`]: a TSP/1 recording (the raw bytes a stand sent, binary or CSV, detected
//!   automatically) into a record: [`tsp::read_record`].
//! - [`assemble`]: the streaming part the daemon reuses: sample-index gaps, the device clock,
//!   segments and events ([`SampleAssembler`]), and the growing record ([`RecordBuilder`]).
//! - [`clock`]: unwrapping the 32-bit device counters.
//! - [`csv_file`]: CSV files (exported stand logs, benchmark archives) with column choice,
//!   [`resample`] for irregular timestamps, and [`steps`] found from a response-only record.

pub mod assemble;
pub mod clock;
pub mod csv_file;
pub mod resample;
pub mod steps;
pub mod tsp;

pub use assemble::{
    AssembleOptions, AssembleStats, Assembled, BuildStats, RecordBuilder, SampleAssembler,
};
pub use tsp::{read_record, read_record_with, IngestOptions, IngestStats};

use crate::protocol::csv_columns::ConvError;

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
