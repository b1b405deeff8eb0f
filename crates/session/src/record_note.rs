//! What the raw recording (the daemon's recorder thread) reports to the worker, published as
//! a line: a file opened, a write failed, received bytes dropped.

use std::io;
use std::path::Path;
use std::sync::Arc;

/// What the recording reports to the worker, published as a line.
#[derive(Debug, Clone)]
pub enum RecordNote {
    /// A file was opened: a `recording` event line.
    File {
        /// The file's path.
        path: Arc<Path>,
    },
    /// Writing failed; the recording is over: an `output_failed` warning line.
    Failed {
        /// The file's path.
        path: Arc<Path>,
        /// The OS error.
        error: Arc<io::Error>,
    },
    /// The recording fell behind and received bytes were dropped (counted in
    /// `record_bytes_dropped`): an `output_failed` warning line, once per run.
    Dropped {
        /// The file being written.
        path: Arc<Path>,
    },
}

/// The text of the `output_failed` warning of [`RecordNote::Dropped`].
pub const DROPPED_MESSAGE: &str =
    "the recording fell behind (its reader or disk is too slow): received bytes dropped, counted in record_bytes_dropped";

/// Notes compare by path and, for a failure, by the error's kind and text.
impl PartialEq for RecordNote {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (RecordNote::File { path: a }, RecordNote::File { path: b }) => a == b,
            (RecordNote::Dropped { path: a }, RecordNote::Dropped { path: b }) => a == b,
            (
                RecordNote::Failed { path: a, error: x },
                RecordNote::Failed { path: b, error: y },
            ) => a == b && x.kind() == y.kind() && x.to_string() == y.to_string(),
            _ => false,
        }
    }
}
