//! Orderly shutdown on Ctrl-C / SIGTERM.
//!
//! The first SIGINT or SIGTERM sets a flag that the sampler and the worker poll: the sampler
//! sends STOP until it is acknowledged (at most `daemon.stop_timeout_ms`), the worker flushes
//! every output and publishes the final stats line, and the process exits 0. A second signal
//! exits at once with 128 + its number, as a shell reports a process killed by it (SIGINT:
//! 130, SIGTERM: 143), for an operator who does not want to wait: STOP is not waited for and no
//! stats line is written, but nothing already published is lost (stdout and the file are
//! flushed per line; `tests/daemon/daemon_e2e.rs` checks it through the binary).
//!
//! **Before the run starts** (loading, opening the port, the outputs, reading a replay's
//! input: anything that may block, as opening a FIFO does until its other end appears) nothing
//! commands the motor yet, so the first signal ends the process at once, with a message and
//! 128 + its number; [`Shutdown::begin_run`] (called by the runner as it starts the threads)
//! switches to the graceful stop above.
//!
//! The handler is process-wide, installed once with `sigaction` (it only stores to atomics and
//! calls `_exit`, both async-signal-safe); [`Shutdown::manual`] gives the same flag without a
//! handler, for tests and in-process runs.

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
/// The run has started: a first signal asks for a graceful stop (before, it exits).
static RUNNING: AtomicBool = AtomicBool::new(false);

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
        let s = GLOBAL.get_or_init(Shutdown::default).clone();
        for sig in [libc::SIGINT, libc::SIGTERM] {
            // SAFETY: a zeroed sigaction with a handler that only touches atomics and calls
            // `_exit` (async-signal-safe); the mask is emptied by sigemptyset.
            let r = unsafe {
                let mut action: libc::sigaction = std::mem::zeroed();
                action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
                action.sa_flags = libc::SA_RESTART;
                libc::sigemptyset(&mut action.sa_mask);
                libc::sigaction(sig, &action, std::ptr::null_mut())
            };
            if r != 0 {
                return Err(DaemonError::Signal(std::io::Error::last_os_error()));
            }
        }
        Ok(s)
    }

    /// The run starts (the threads that command the motor): from now on the first signal
    /// asks for a graceful stop instead of ending the process.
    pub fn begin_run(&self) {
        RUNNING.store(true, Ordering::SeqCst);
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

/// The process-wide handler: before the run, the first signal exits at once; then the first
/// signal asks for a stop, a second one exits at once with 128 + its number.
extern "C" fn on_signal(sig: libc::c_int) {
    if !RUNNING.load(Ordering::SeqCst) {
        const MSG: &[u8] = b"propid: stopped by a signal before the run started\n";
        // SAFETY: `write` and `_exit` are async-signal-safe; MSG is a valid buffer.
        unsafe {
            libc::write(2, MSG.as_ptr().cast(), MSG.len());
            libc::_exit(128 + sig)
        };
    }
    if SIGNALS.fetch_add(1, Ordering::SeqCst) >= 1 {
        // SAFETY: `_exit` is async-signal-safe; the operator insists.
        unsafe { libc::_exit(128 + sig) };
    }
    if let Some(s) = GLOBAL.get() {
        s.request();
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
