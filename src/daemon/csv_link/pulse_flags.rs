//! Pulse flags for CSV rows, which carry none.
//!
//! A binary SAMPLE says which samples a device-timed pulse covered (IMPULSE_ACTIVE); the worker
//! takes rising edges of that flag as pulse starts. A CSV bench only shows the throttle it
//! applied, so the same facts are read off the throttle column with one rule:
//!
//! > An **excursion** is a run of samples whose throttle differs from the held level by more
//! > than the level tolerance. If the throttle comes back to the level within
//! > `max_pulse_samples` samples, the excursion was a **pulse**: its samples get IMPULSE_ACTIVE.
//! > Otherwise it was a **level change** (a step or a ramp): its samples pass unflagged and the
//! > last of them is the new held level.
//!
//! This needs a look-ahead of at most `max_pulse_samples`, so samples are held in a delay line
//! of that fixed capacity while an excursion is open (a pulse of one sample period — the
//! Kronecker delta of the ERA derivation — delays its own sample by one row). A delay line is
//! the price of the missing flag: the worker's windows then see exactly what a binary stand
//! would have flagged, so a CSV bench is identified by the same code path.
//!
//! Within the tolerance the held level follows the throttle (slow drift is not an excursion).

use propid_wire::protocol::message::{Sample, SampleFlags};

/// Flags pulses in a stream of samples (see the module documentation). Allocation-free after
/// [`PulseFlagger::new`].
#[derive(Debug, Clone)]
pub struct PulseFlagger {
    tolerance_raw: u16,
    level: Option<u16>,
    open: Vec<Sample>,
    cap: usize,
    pulses: u64,
}

impl PulseFlagger {
    /// `tolerance` as a throttle fraction (0..1), `max_pulse_samples` the longest pulse (≥ 1).
    pub fn new(tolerance: f64, max_pulse_samples: usize) -> Self {
        let cap = max_pulse_samples.max(1);
        Self {
            tolerance_raw: (tolerance * 10_000.0).round().clamp(0.0, 10_000.0) as u16,
            level: None,
            open: Vec::with_capacity(cap),
            cap,
            pulses: 0,
        }
    }

    /// Pulses found so far.
    pub fn pulses(&self) -> u64 {
        self.pulses
    }

    fn near(&self, a: u16, b: u16) -> bool {
        a.abs_diff(b) <= self.tolerance_raw
    }

    /// One sample in; samples out in order, once their excursion (if any) is decided.
    pub fn push(&mut self, s: Sample, emit: &mut impl FnMut(Sample)) {
        let Some(level) = self.level else {
            self.level = Some(s.throttle);
            return emit(s);
        };
        if self.near(s.throttle, level) {
            if !self.open.is_empty() {
                self.pulses += 1;
                for mut p in self.open.drain(..) {
                    p.flags.0 |= SampleFlags::IMPULSE_ACTIVE.0;
                    emit(p);
                }
            }
            self.level = Some(s.throttle);
            return emit(s);
        }
        if self.open.len() == self.cap {
            self.close_as_level_change(emit);
            return self.push(s, emit);
        }
        self.open.push(s);
    }

    /// Releases an open excursion as a level change (end of input, a new boot, a gap too long
    /// to tell): a pulse cannot be confirmed without its end.
    pub fn flush(&mut self, emit: &mut impl FnMut(Sample)) {
        if !self.open.is_empty() {
            self.close_as_level_change(emit);
        }
    }

    /// Forgets the held level (a new boot).
    pub fn restart(&mut self, emit: &mut impl FnMut(Sample)) {
        self.flush(emit);
        self.level = None;
    }

    fn close_as_level_change(&mut self, emit: &mut impl FnMut(Sample)) {
        self.level = self.open.last().map(|s| s.throttle);
        for p in self.open.drain(..) {
            emit(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(throttles: &[u16], cap: usize) -> (Vec<(u16, bool)>, u64) {
        let mut f = PulseFlagger::new(0.005, cap);
        let mut out = Vec::new();
        let mut emit = |s: Sample| {
            out.push((s.throttle, s.flags.contains(SampleFlags::IMPULSE_ACTIVE)));
        };
        for (k, &t) in throttles.iter().enumerate() {
            let s = Sample {
                sample_index: k as u32,
                throttle: t,
                ..Sample::default()
            };
            f.push(s, &mut emit);
        }
        f.flush(&mut emit);
        (out, f.pulses())
    }

    #[test]
    fn one_sample_pulses_of_either_sign_are_flagged_exactly() {
        let t = [
            3000, 3000, 3500, 3000, 3000, 2500, 3000, 3000, 4000, 4000, 3000,
        ];
        let (out, pulses) = run(&t, 8);
        assert_eq!(pulses, 3);
        let flagged: Vec<bool> = out.iter().map(|o| o.1).collect();
        let want = [
            false, false, true, false, false, true, false, false, true, true, false,
        ];
        assert_eq!(flagged, want);
        // order and values kept
        assert_eq!(out.iter().map(|o| o.0).collect::<Vec<_>>(), t);
    }

    #[test]
    fn a_step_and_a_ramp_are_level_changes_not_pulses() {
        let mut t = vec![3000u16; 5];
        t.extend(std::iter::repeat_n(4500, 20)); // step
        t.extend((0..30).map(|k| 4500 + 50 * k)); // ramp
        t.extend(std::iter::repeat_n(6000, 10));
        let (out, pulses) = run(&t, 8);
        assert_eq!(pulses, 0);
        assert!(out.iter().all(|o| !o.1));
        assert_eq!(out.len(), t.len());
    }

    #[test]
    fn drift_within_tolerance_is_followed_and_an_open_pulse_at_the_end_is_not_claimed() {
        let t: Vec<u16> = (0..40).map(|k| 3000 + k * 10).chain([5000]).collect();
        let (out, pulses) = run(&t, 8);
        assert_eq!(pulses, 0);
        assert_eq!(out.len(), 41);
        assert!(out.iter().all(|o| !o.1));
    }
}
