//! What `propid identify` and `propid diagnose` print and draw: the JSON objects, the human
//! summaries, the Markdown pages and SVG figures of `--report`. The CLI (`src/cli`) reads the
//! files, runs the engines and writes what this crate renders.
//!
//! - [`identify`]: identify's view of a file, the stand's physics, its JSON and summary.
//! - [`diagnose`]: the Markdown page and SVG plots of `diagnose --report`.
//! - [`plot`]: SVG figures both reports draw (the stabilization diagram).
//! - [`columns_read`] (`propid_ingest`'s): what a CSV file's columns were read as (both
//!   commands' `source`).

pub use propid_ingest::columns_read;
pub mod diagnose;
pub mod identify;
pub mod kinds;
pub mod plot;
