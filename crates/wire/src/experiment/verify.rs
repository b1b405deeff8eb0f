//! A stand that lies: its samples checked against what the plan commanded.
//!
//! An ACK says a command was taken, not that it was done; the SAMPLEs say what the device
//! applied. The plan holds the two against each other and stops a stand whose samples
//! contradict its ACKs (each a notice, a STOP, the plan over; the daemon exits 8):
//!
//! - **Throttle mismatch** ([`Notice::ThrottleMismatch`]): the applied throttle (every
//!   SAMPLE's `throttle`) outside the *commanded envelope* by more than
//!   [`THROTTLE_TOLERANCE`] for longer than [`THROTTLE_MISMATCH_MS`] (host clock). The envelope
//!   is what the plan may have the motor at: while ramping and settling, anything between the
//!   previous level and the new one; while pulsing, the level ± the largest pulse amplitude
//!   (and, until the level has shown in a sample, the previous level too: a stand that has not
//!   moved is the next rule's); while ramping down, 0..the last level. Before ARM's ACK and
//!   after DISARM nothing is commanded and nothing is checked.
//! - **Commands not executed** ([`Notice::CommandsNotExecuted`]): judged when a pulse's
//!   spacing ends (the response has had `pulse_spacing_ms`), with at least
//!   [`MIN_SAMPLES_TO_JUDGE`] samples since the pulse: the operating point must have appeared
//!   in a sample (a throttle within the tolerance of it, off pulse), and of the pulses fired,
//!   [`PULSES_UNSEEN_LIMIT`] in a row may not pass without a sign (a SAMPLE with IMPULSE_ACTIVE
//!   or the device's EVENT IMPULSE_START). A throttle off the envelope at that moment is left
//!   to the mismatch rule (the stand moved, wrongly). One pulse lost with its sample and its event on a
//!   bad link is not a lie; three in a row is.
//! - **Sample rate** ([`Notice::RateMismatch`], [`Experiment::sample_rate_disagrees`]): the
//!   caller measures the rate (the wire crate's `SampleAssembler`, the one clock rule) and says
//!   when it disagrees with the HELLO's, from which the plan sizes its pulses.
//! - **Safety limits** ([`Experiment::set_limits`]): every sample held to `[limits]`
//!   (`limits.rs`); a breach ends the plan for good.
//!
//! The BUSY bound (an IMPULSE answered BUSY is tried again 20 ms later, at most `max_retries`
//! times and for one `pulse_spacing_ms`) lives with the ACK handling in `plan.rs`.

use super::limits::{LimitGuard, Limits, LimitsError};
use super::plan::{Experiment, Notice, Phase};
use super::stand_check::{
    MIN_SAMPLES_TO_JUDGE, PULSES_UNSEEN_LIMIT, THROTTLE_MISMATCH_MS, THROTTLE_TOLERANCE,
};
use crate::protocol::{Message, Sample, SampleFlags};

impl Experiment {
    /// The throttle range (fractions) the plan may have the motor at now, if it commands one.
    fn envelope(&self) -> Option<(f64, f64)> {
        if self.phase == Phase::Program {
            return Some(self.program_envelope());
        }
        if self.phase == Phase::RampDown && self.cfg.kind != super::Kind::Pulses {
            let hi = self.program.iter().map(|s| s.level).fold(0.0, f64::max);
            return Some((0.0, hi));
        }
        let level = self.cfg.levels.get(self.level_idx).copied()?;
        let span = |a: f64, b: f64| (a.min(b), a.max(b));
        match self.phase {
            Phase::Ramping | Phase::Settling => Some(span(self.from_level, level)),
            Phase::Pulsing => {
                let up = self
                    .cfg
                    .pulse_amplitudes
                    .iter()
                    .copied()
                    .fold(0.0, f64::max);
                let down = if self.cfg.alternate_sign { up } else { 0.0 };
                let (lo, hi) = (level - down, level + up);
                if self.check.level_seen {
                    Some((lo, hi))
                } else {
                    Some((lo.min(self.from_level), hi.max(self.from_level)))
                }
            }
            Phase::RampDown => Some((0.0, level)),
            _ => None,
        }
    }

    /// While a set-point program runs: a chirp's whole band (`level ± chirp_amplitude`, and
    /// the ramp to the level from 0), else anything between the set-point before the last one
    /// sent and the one in flight or next (the device ramps from where it was).
    fn program_envelope(&self) -> (f64, f64) {
        if self.cfg.kind == super::Kind::Chirp {
            let (lo, hi) = self.cfg.envelope();
            return if self.check.level_seen {
                (lo, hi)
            } else {
                (0.0f64.min(lo), hi)
            };
        }
        let i = self.level_idx.min(self.program.len() - 1);
        let first = i.saturating_sub(2);
        let mut lo = self.program[first..=i]
            .iter()
            .map(|s| s.level)
            .fold(f64::INFINITY, f64::min);
        let mut hi = self.program[first..=i]
            .iter()
            .map(|s| s.level)
            .fold(0.0, f64::max);
        if i < 2 {
            lo = lo.min(0.0); // from the motor at rest
        }
        hi = hi.max(lo);
        (lo, hi)
    }

    /// A SAMPLE at `now_us`: the applied throttle against the envelope, the level and pulse
    /// seen.
    pub(super) fn on_sample(&mut self, s: &Sample, now_us: u64) {
        if self.verifying.is_some() {
            return; // a reconnect: whether this is the same boot is not known yet
        }
        let Some((lo, hi)) = self.envelope() else {
            self.check.off_since = None;
            return;
        };
        let applied = s.throttle_fraction();
        let in_pulse = s.flags.contains(SampleFlags::IMPULSE_ACTIVE);
        if self.phase == Phase::Program && self.cfg.kind == super::Kind::Chirp {
            let (lo, hi) = self.cfg.envelope();
            if applied >= lo - THROTTLE_TOLERANCE && applied <= hi + THROTTLE_TOLERANCE {
                self.check.level_seen = true;
            }
        }
        if matches!(self.phase, Phase::Settling | Phase::Pulsing) {
            let level = self.cfg.levels[self.level_idx];
            if !in_pulse && (applied - level).abs() <= THROTTLE_TOLERANCE {
                self.check.level_seen = true;
            }
        }
        if self.phase == Phase::Pulsing {
            self.check.samples_since_pulse = self.check.samples_since_pulse.saturating_add(1);
            if in_pulse {
                self.check.pulse_shown = true;
            }
        }
        let off = applied < lo - THROTTLE_TOLERANCE || applied > hi + THROTTLE_TOLERANCE;
        if !off {
            self.check.off_since = None;
            return;
        }
        let since = *self.check.off_since.get_or_insert(now_us);
        let for_us = now_us.saturating_sub(since);
        if for_us > THROTTLE_MISMATCH_MS * 1000 {
            self.stand_fault(
                Notice::ThrottleMismatch {
                    commanded_min: lo,
                    commanded_max: hi,
                    applied,
                    for_ms: for_us / 1000,
                },
                now_us,
            );
        }
    }

    /// A pulse's spacing ended: did the samples show the level and the pulses? True when they
    /// did not (the plan is then over, [`Notice::CommandsNotExecuted`]).
    pub(super) fn stand_ignored_commands(&mut self, now_us: u64) -> bool {
        // a throttle off the envelope is the mismatch rule's (a stand that moved, wrongly)
        let off = self.check.off_since.is_some();
        if off || self.pulses == 0 || self.check.samples_since_pulse < MIN_SAMPLES_TO_JUDGE {
            return false;
        }
        let level = self.cfg.levels[self.level_idx];
        if !self.check.level_seen {
            let n = Notice::CommandsNotExecuted {
                command: "SET_THROTTLE",
                level,
            };
            self.stand_fault(n, now_us);
            return true;
        }
        if std::mem::take(&mut self.check.pulse_shown) {
            self.check.unseen_pulses = 0;
            return false;
        }
        self.check.unseen_pulses += 1;
        if self.check.unseen_pulses < PULSES_UNSEEN_LIMIT {
            return false;
        }
        let n = Notice::CommandsNotExecuted {
            command: "IMPULSE",
            level: level + self.cfg.pulse_delta(self.pulses - 1),
        };
        self.stand_fault(n, now_us);
        true
    }

    /// The caller measured the device's sample rate and finds it disagrees with the HELLO's
    /// (its rule: the wire crate's `SampleAssembler`): the plan sizes pulses from the HELLO's
    /// rate, so a stand that lies about it is stopped ([`Notice::RateMismatch`]). Nothing
    /// happens before ARM or once the plan is over.
    pub fn sample_rate_disagrees(&mut self, hello_hz: u16, measured_hz: f64, now_us: u64) {
        if self.phase.mid_plan() || self.phase == Phase::Handshake {
            self.stand_fault(
                Notice::RateMismatch {
                    hello_hz,
                    measured_hz,
                },
                now_us,
            );
        }
    }

    /// The stand contradicted the plan: the notice, the plan over, STOP (re-sent until
    /// acknowledged).
    fn stand_fault(&mut self, n: Notice, now_us: u64) {
        let armed = self.phase.mid_plan();
        self.halt(n);
        if armed {
            self.send(Message::Stop, now_us);
        }
    }
}

impl Experiment {
    /// Holds the stand to `limits` (validated by the caller, [`Limits::validate`]) from now on;
    /// refuses a plan that commands more than `max_throttle` ([`Limits::refuse_plan`]).
    pub fn set_limits(&mut self, limits: Limits) -> Result<(), LimitsError> {
        limits.validate()?;
        limits.refuse_plan(&self.cfg)?;
        self.limits = LimitGuard::new(limits);
        Ok(())
    }

    /// A SAMPLE against the limits (before anything else is made of it): a breach while the
    /// plan runs, or waits to re-arm, ends it for good with a STOP.
    pub(super) fn check_limits(&mut self, s: &Sample, now_us: u64) {
        let mut unchecked = Vec::new();
        let trip = self
            .limits
            .sample(s, &mut |which, why| unchecked.push((which, why)));
        for (which, why) in unchecked {
            self.notice(Notice::LimitUnchecked { which, why });
        }
        let running = !matches!(
            self.phase,
            Phase::Idle | Phase::Done | Phase::Stopping | Phase::Halted
        );
        let Some(t) = trip.filter(|_| running || self.rearm_pending) else {
            return;
        };
        // `halt` clears `rearm_pending`: nothing re-arms a plan a limit ended
        self.halt(Notice::LimitTripped {
            which: t.which,
            value: t.value,
            limit: t.limit,
        });
        self.send(Message::Stop, now_us);
    }
}

#[cfg(test)]
mod tests;
