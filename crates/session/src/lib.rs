//! The daemon's live session without I/O, threads or sockets: what the worker decides and what
//! it publishes, on items handed to it (`src/daemon` holds the threads and the sinks).
//!
//! - [`item`]: the items the sampler hands the worker (samples, gaps, events, notices).
//! - [`window`]: the fixed-size window per operating point, and when to identify.
//! - [`identify`]: the [`identify::Identifier`] seam to the core, and why a window gave no model.
//! - [`quality`]: whether a window's model may be published as a model.
//! - [`line`], [`live`], [`stats`]: the typed published lines (stdout, file, socket, MQTT; the
//!   web page's own) and the run's counters.
//! - [`record_note`]: what the raw recording reports to the worker.
//! - [`topics`]: the MQTT topic names.

pub mod identify;
pub mod item;
pub mod line;
pub mod live;
pub mod quality;
pub mod record_note;
pub mod stats;
pub mod topics;
pub mod window;

#[doc(hidden)]
pub mod fixtures;
