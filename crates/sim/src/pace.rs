//! Pacing: a pty does not pace, so the simulated stand keeps its own time on a monotonic clock.
//! The firmware schedules sample `k` at `k·period` after boot (computed from `k`, never by adding
//! periods to the last wake-up), and the runner hands it the elapsed time: a late wake-up emits
//! every sample that became due, so the stream catches up without drift.

use std::time::{Duration, Instant};

/// A monotonic device clock: microseconds since it was started.
#[derive(Debug, Clone, Copy)]
pub struct MonoClock {
    start: Instant,
}

impl MonoClock {
    /// A clock at zero now.
    pub fn start() -> Self {
        MonoClock {
            start: Instant::now(),
        }
    }

    /// Microseconds since the start.
    pub fn now_us(&self) -> u64 {
        self.start.elapsed().as_micros() as u64
    }

    /// Time from now until `deadline_us` (zero when it has passed).
    pub fn until(&self, deadline_us: u64) -> Duration {
        Duration::from_micros(deadline_us.saturating_sub(self.now_us()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clock_is_monotonic_and_until_saturates() {
        let c = MonoClock::start();
        let a = c.now_us();
        std::thread::sleep(Duration::from_millis(2));
        let b = c.now_us();
        assert!(b >= a + 2000, "{a} {b}");
        assert_eq!(c.until(a), Duration::ZERO);
        assert!(c.until(b + 1_000_000) > Duration::from_millis(900));
    }
}
