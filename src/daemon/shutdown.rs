//! Orderly shutdown on Ctrl-C / SIGTERM.
//!
//! The first SIGINT or SIGTERM sets a flag that the sampler and the worker poll: the sampler
//! sends STOP until it is acknowledged (at most `daemon.stop_timeout_ms`), the worker flushes
//! every output and publishes the final stats line, and the process exits 0. A second signal
//! exits at once (status 130), for an operator who does not want to wait: STOP is not waited
//! for and no stats line is written, but nothing already published is lost (stdout and the
//! file are flushed per line; `tests/daemon_e2e.rs` checks it through the binary).
//!
//! The handler is process-wide (the `ctrlc` crate allows one per process); [`Shutdown::manual`]
//! gives the same flag without a handler, for tests and in-process runs.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, OnceLock};

use super::DaemonError;

/// A shared "please stop" flag.
#[derive(Debug, Clone, Default)]
pub struct Shutdown {
    flag: Arc<AtomicBool>,
}

/// The flag the process-wide signal handler sets (installed once).
static GLOBAL: OnceLock<Shutdown> = OnceLock::new();
/// Signals received so far.
static SIGNALS: AtomicU32 = AtomicU32::new(0);

impl Shutdown {
    /// A flag that only [`Shutdown::request`] sets.
    pub fn manual() -> Shutdown {
        Shutdown::default()
    }

    /// The flag set by SIGINT/SIGTERM; installs the handler on first use.
    pub fn install() -> Result<Shutdown, DaemonError> {
        if let Some(s) = GLOBAL.get() {
            return Ok(s.clone());
        }
        let s = Shutdown::default();
        let for_handler = s.clone();
        ctrlc::set_handler(move || {
            if SIGNALS.fetch_add(1, Ordering::SeqCst) >= 1 {
                // Second signal: the operator insists.
                std::process::exit(130);
            }
            for_handler.request();
        })
        .map_err(DaemonError::Signal)?;
        Ok(GLOBAL.get_or_init(|| s).clone())
    }

    /// Asks everything polling this flag to stop.
    pub fn request(&self) {
        self.flag.store(true, Ordering::SeqCst);
    }

    /// Whether a stop was requested.
    pub fn requested(&self) -> bool {
        self.flag.load(Ordering::SeqCst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_flag() {
        let a = Shutdown::manual();
        let b = a.clone();
        assert!(!b.requested());
        a.request();
        assert!(b.requested());
        assert!(!Shutdown::manual().requested());
    }
}
