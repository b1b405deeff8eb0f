//! When the scheduled link faults fall due (`hangup_every_s`, `reset_every_s`), and how long a
//! hang-up waits for the host to read what is already on the wire.

use std::time::{Duration, Instant};

use crate::config::SimConfig;

/// Longest wait at a hang-up for the host to read what is already on the wire.
pub const DRAIN_MAX: Duration = Duration::from_secs(1);

/// Least time after the last write before the slave's empty queue is believed: the kernel moves
/// what the master wrote to the slave's queue a little later (a work item), and FIONREAD does
/// not count it until then.
pub(super) const DRAIN_SETTLE: Duration = Duration::from_millis(20);

/// Wait at a hang-up for the host to read the wire when the slave's queue cannot be measured.
pub(super) const DRAIN_BLIND: Duration = Duration::from_millis(100);

/// The scheduled hang-ups and resets (`hangup_every_s`, `reset_every_s`), on the run's clock.
pub(super) struct Schedule {
    every: [Option<Duration>; 2],
    next: [Option<Instant>; 2],
}

impl Schedule {
    pub(super) const HANGUP: usize = 0;
    pub(super) const RESET: usize = 1;

    pub(super) fn new(cfg: &SimConfig, started: Instant) -> Schedule {
        let every = [cfg.faults.hangup_every_s, cfg.faults.reset_every_s]
            .map(|s| (s > 0.0).then(|| Duration::from_secs_f64(s)));
        Schedule {
            every,
            next: every.map(|e| e.map(|e| started + e)),
        }
    }

    /// Whether fault `which` falls due now; it is rescheduled either way. `live`: a host has
    /// the port open and faults are on (else the one due is skipped).
    pub(super) fn due(&mut self, which: usize, now: Instant, live: bool) -> bool {
        match (self.next[which], self.every[which]) {
            (Some(t), Some(e)) if now >= t => {
                self.next[which] = Some(now + e);
                live
            }
            _ => false,
        }
    }
}
