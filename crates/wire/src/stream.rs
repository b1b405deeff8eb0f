//! A stream of decoded frames (or CSV rows) into samples: the 32-bit device counters unwrapped
//! ([`clock`]), CSV rows given sample indices ([`place`], [`csv_stream`], with [`boot`]),
//! every sample placed at its index with gaps, duplicates, segments and events
//! ([`assemble::SampleAssembler`]), and the growing record ([`assemble::RecordBuilder`]).
//! The daemon's live tracker and file ingest use the same code, so a recording replayed and
//! the same recording identified place every sample identically.

pub mod assemble;
pub mod boot;
pub mod clock;
pub mod csv_stream;
mod error;
pub mod place;

pub use assemble::{
    AssembleOptions, AssembleStats, Assembled, BuildStats, HelloEffect, RecordBuilder,
    SampleAssembler, SegmentCause,
};
pub use csv_stream::{CsvFact, CsvStream, CsvStreamStats};
pub use error::IngestError;
pub use place::{Placed, Placement, RowPlacer};
