//! A stream of decoded frames into samples: the 32-bit device counters unwrapped
//! ([`clock`]), every sample placed at its index with gaps, duplicates, segments and events
//! ([`assemble::SampleAssembler`]), and the growing record ([`assemble::RecordBuilder`]).
//! The daemon's live tracker and file ingest use the same code, so a recording replayed and
//! the same recording identified place every sample identically.

pub mod assemble;
pub mod clock;
mod error;

pub use assemble::{
    AssembleOptions, AssembleStats, Assembled, BuildStats, RecordBuilder, SampleAssembler,
};
pub use error::IngestError;
