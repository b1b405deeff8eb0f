//! The daemon: sources, the sampler and worker threads, publishing, configuration, shutdown.
//!
//! ```text
//!  Source (serial / pty / recording)
//!     │ bytes
//!  sampler thread ── decodes TSP/1, unwraps the device clock, finds gaps and new boots,
//!     │              drives the experiment plan (commands, heartbeats), records raw bytes
//!     │ bounded queue (never blocks: a full queue is counted as an overflow)
//!  worker thread ─── fixed-size window per operating point, identifies after every K pulses
//!     │              with the core's workspace (no allocation per identification)
//!  Publisher ─────── JSON lines to stdout, a file, a UNIX socket
//! ```
//!
//! Replay runs the same sampler (without commands) and the same worker on a recording, so a live
//! run and the replay of its recording publish the same model lines.

pub mod config;
pub mod csv_link;
#[cfg(test)]
mod fixtures;
pub mod identify;
pub mod item;
pub mod line;
pub mod plan;
pub mod publish;
pub mod quality;
pub mod runner;
pub mod sampler;
pub mod shutdown;
pub mod source;
pub mod stats;
pub mod tracker;
pub mod window;
pub mod wire;
pub mod worker;

pub use config::{Config, ConfigError};
pub use publish::Publisher;
pub use shutdown::Shutdown;
pub use source::{Source, SourceError};

/// What can stop the daemon.
#[derive(Debug, thiserror::Error)]
pub enum DaemonError {
    /// The configuration was refused.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The source failed in a way reconnecting cannot fix.
    #[error(transparent)]
    Source(#[from] SourceError),
    /// A file or socket operation failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// A line could not be serialised (a bug: every published type serialises).
    #[error("publish: cannot serialise a line: {0}")]
    Serialize(#[source] serde_json::Error),
    /// The signal handler could not be installed.
    #[error("cannot install the signal handler: {0}")]
    Signal(String),
    /// The device stopped answering commands.
    #[error("link failed: {0}")]
    LinkFailed(String),
    /// The identification workspace could not be set up.
    #[error("identification: {0}")]
    Identify(String),
    /// A thread of the daemon panicked (a bug).
    #[error("internal error: {0}")]
    Internal(String),
}

impl DaemonError {
    /// An I/O error with what was being done.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        DaemonError::Io {
            context: context.into(),
            source,
        }
    }
}
