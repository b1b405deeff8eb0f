//! Bytes and files into [`Record`](propid_wire::record::Record)s.
//!
//! - [`tsp`]: a TSP/1 recording (the raw bytes a stand sent, binary or CSV, detected
//!   automatically) into a record: [`tsp::read_record`].
//! - [`assemble`]: the streaming part the daemon reuses: sample-index gaps, the device clock,
//!   segments and events ([`SampleAssembler`]), and the growing record ([`RecordBuilder`]).
//! - [`clock`]: unwrapping the 32-bit device counters.
//! - [`columns_read`]: what a CSV file's columns were read as (`source` of identify and
//!   diagnose).
//! - [`load`]: the one loader of `identify` and `diagnose`: a file's bytes into the channels
//!   asked for, the format detected (a TSP/1 recording or stream, any other CSV file).
//! - [`csv_file`]: CSV files (exported stand logs, benchmark archives) with column choice,
//!   [`held`] for a slow sensor written on every row as its last reading, [`interpolated`] for
//!   one the exporter interpolated onto every row, [`gaps`] for a channel's missing samples, [`resample`] for
//!   irregular timestamps ([`coarse_clock`] for stamps coarser than the rows), and [`steps`] found from a response-only record.
//! - [`window`]: a binary recording longer than the identification window read in bounded
//!   memory (two passes: the span with the command's most moves, then its rows).

pub mod coarse_clock;
pub mod columns_read;
pub mod csv_file;
pub mod gaps;
pub mod held;
pub mod interpolated;
pub mod load;
pub mod resample;
pub mod steps;
pub mod tsp;
pub mod window;

pub use propid_wire::stream::{assemble, clock, IngestError};
pub use propid_wire::stream::{
    AssembleOptions, AssembleStats, Assembled, BuildStats, RecordBuilder, SampleAssembler,
};
pub use tsp::{read_record, read_record_with, BinaryReader, IngestOptions, IngestStats};
