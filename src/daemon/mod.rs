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
//!  Publisher ─────── JSON lines to stdout, a file, a UNIX socket, the web page, MQTT
//! ```
//!
//! Replay runs the same sampler (without commands) and the same worker on a recording, so a live
//! run and the replay of its recording publish the same model lines.

pub mod config;
pub mod http;
pub mod identify;
pub mod mqtt;
pub mod plan;
pub mod publish;
pub mod recorder;
pub mod runner;
pub mod sampler;
pub mod shutdown;
pub mod source;
pub mod wire;
pub mod worker;

pub use propid_link::{csv_link, tracker};
#[cfg(test)]
use propid_session::fixtures;
pub use propid_session::{item, line, live, quality, stats};

/// The worker's window ([`propid_session::window`]) and its size from the configuration.
pub mod window {
    mod sizing;

    pub use propid_session::window::*;
    pub use sizing::{plan_samples, window_capacity, PLAN_MAX_SAMPLES, PLAN_RATE_HZ};
}

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
    /// An output (stdout, the recording) failed while the run went on; reported at the end.
    #[error("write error: {sink}: {source}")]
    Output {
        /// Which output: `stdout` or the recording's path.
        sink: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The experiment plan ended on a fault (device reset, watchdog trip, refused command) and
    /// the run stopped by itself: the warning line published before says which.
    #[error("the experiment plan ended on a fault (see the warning line); the run stopped")]
    PlanHalted,
    /// A line could not be serialised (a bug: every published type serialises).
    #[error("publish: cannot serialise a line: {0}")]
    Serialize(#[source] serde_json::Error),
    /// The signal handler could not be installed.
    #[error("cannot install the signal handler: {0}")]
    Signal(#[source] std::io::Error),
    /// The device stopped answering commands.
    #[error("link failed: {link} stopped acknowledging commands")]
    LinkFailed {
        /// The link, as its source describes itself.
        link: String,
    },
    /// The identification workspace could not be set up.
    #[error("identification: {0}")]
    Identify(#[source] propid_numerics::IdentError),
    /// A thread of the daemon panicked (a bug).
    #[error("internal error: the {thread} thread panicked")]
    ThreadPanicked {
        /// Which thread: `sampler` or `worker`.
        thread: &'static str,
    },
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The messages a user sees stay what they were when the causes were strings.
    #[test]
    fn errors_keep_their_messages_and_their_causes() {
        let e = DaemonError::LinkFailed {
            link: "/dev/ttyACM0".into(),
        };
        assert_eq!(
            e.to_string(),
            "link failed: /dev/ttyACM0 stopped acknowledging commands"
        );
        let e = DaemonError::ThreadPanicked { thread: "worker" };
        assert_eq!(e.to_string(), "internal error: the worker thread panicked");
        let mut cfg = Config {
            experiment: toml::from_str("levels = []").unwrap(),
            ..Config::default()
        };
        let e = plan::from_config(&cfg).err().unwrap();
        assert!(matches!(e, DaemonError::Config(ConfigError::Experiment(_))));
        assert_eq!(
            e.to_string(),
            "config [experiment]: experiment key `levels.len()` = 0: an integer in 1..=32"
        );
        cfg.experiment = toml::from_str("levels = \"x\"").unwrap();
        let e = plan::from_config(&cfg).err().unwrap();
        assert!(
            matches!(&e, DaemonError::Config(ConfigError::Parse { origin, .. }) if origin == "[experiment]")
        );
        assert!(std::error::Error::source(&e).is_some());
        let e = source::RecordingSource::open(std::path::Path::new("/nonexistent/rec.tsp"), 64)
            .err()
            .unwrap();
        assert_eq!(
            e.to_string(),
            "cannot open /nonexistent/rec.tsp: No such file or directory (os error 2)"
        );
    }
}
