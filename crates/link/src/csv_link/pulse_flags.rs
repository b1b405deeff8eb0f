//! Pulse flags for CSV rows, which carry none.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/link/src/csv_link/pulse_flags.rs`.

use propid_numerics::segment::{Decision, PulseClassifier, SegmentRules};
use propid_wire::protocol::message::{Sample, SampleFlags, THROTTLE_FULL_SCALE};

/// Flags pulses in a stream of samples (see the module documentation). Allocation-free after
/// [`PulseFlagger::new`].
#[derive(Debug, Clone)]
pub struct PulseFlagger {
    classifier: PulseClassifier,
    open: Vec<Sample>,
    pulses: u64,
}

impl PulseFlagger {
    /// `rules` with the level tolerance as a throttle fraction (0..1) and the longest pulse
    /// (at least 1) in samples.
    pub fn new(rules: SegmentRules) -> Self {
        let scale = f64::from(THROTTLE_FULL_SCALE);
        let steps = (rules.level_tolerance * scale).round().clamp(0.0, scale) as u16;
        let rules = SegmentRules {
            level_tolerance: f64::from(steps),
            max_pulse_samples: rules.max_pulse_samples.max(1),
            ..rules
        };
        Self {
            classifier: PulseClassifier::new(rules),
            open: Vec::with_capacity(rules.max_pulse_samples),
            pulses: 0,
        }
    }

    /// Pulses found so far.
    pub fn pulses(&self) -> u64 {
        self.pulses
    }

    /// One sample in; samples out in order, once their run (if it may be a pulse) is decided.
    pub fn push(&mut self, s: Sample, emit: &mut impl FnMut(Sample)) {
        match self.classifier.push(f64::from(s.throttle)) {
            Decision::Pass => emit(s),
            Decision::Hold => self.open.push(s),
            Decision::Release { hold } => {
                self.release(emit);
                if hold {
                    self.open.push(s);
                } else {
                    emit(s);
                }
            }
            Decision::Pulse(_) => {
                self.pulses += 1;
                for mut p in self.open.drain(..) {
                    p.flags.0 |= SampleFlags::IMPULSE_ACTIVE.0;
                    emit(p);
                }
                emit(s);
            }
        }
    }

    /// Releases held samples unflagged (end of input, a new boot, a gap too long to tell): a
    /// pulse cannot be confirmed without its end.
    pub fn flush(&mut self, emit: &mut impl FnMut(Sample)) {
        if self.classifier.flush() {
            self.release(emit);
        }
    }

    /// Forgets the held level (a new boot).
    pub fn restart(&mut self, emit: &mut impl FnMut(Sample)) {
        self.flush(emit);
        self.classifier.restart();
    }

    fn release(&mut self, emit: &mut impl FnMut(Sample)) {
        for p in self.open.drain(..) {
            emit(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(throttles: &[u16], cap: usize) -> (Vec<(u16, bool)>, u64) {
        let mut f = PulseFlagger::new(SegmentRules {
            max_pulse_samples: cap,
            ..SegmentRules::CSV_BENCH
        });
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

    #[test]
    fn the_flags_are_the_pulses_a_recorded_file_is_segmented_into() {
        // wobble of ±10 steps (within the 0.005 tolerance), pulses of both signs and widths,
        // a pulse right after a step, two values in a row (not one flat pulse), a ramp
        let mut t: Vec<u16> = Vec::new();
        for (v, n) in [
            (3000, 30),
            (3300, 1),
            (3000, 20),
            (2700, 4),
            (3000, 20),
            (4000, 3),
            (3700, 2),
            (4000, 70),
            (4500, 1),
            (4000, 30),
            (4300, 2),
            (4600, 2),
            (4000, 30),
        ] {
            t.extend(std::iter::repeat_n(v, n));
        }
        t.extend((0..40).map(|k| 4000 + 60 * k));
        for (k, v) in t.iter_mut().enumerate() {
            *v = (i32::from(*v) + [0, 10, -10, 5][k % 4]) as u16;
        }
        let (out, pulses) = run(&t, 64);
        let u: Vec<f64> = t.iter().map(|&v| f64::from(v) / 10_000.0).collect();
        let rules = SegmentRules::CSV_BENCH;
        let offline: Vec<_> =
            propid_numerics::segment::pulses(propid_numerics::segment::Command::new(&u), &rules)
                .collect();
        assert_eq!(pulses, 4);
        assert_eq!(offline.len(), 4);
        let flagged: Vec<bool> = out.iter().map(|o| o.1).collect();
        let want: Vec<bool> = (0..t.len())
            .map(|k| {
                offline
                    .iter()
                    .any(|p| (p.start..p.start + p.width).contains(&k))
            })
            .collect();
        assert_eq!(flagged, want);
    }
}
