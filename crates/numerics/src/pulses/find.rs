//! Which pulses: the segmentation's (or the device's pulse starts, checked by the same rule),
//! each with its baseline and response windows, and the common length `L` that decides which
//! are kept.

use super::{missing, Pulse, PulseEnsemble, PulseInput, MAX_BASELINE};
use crate::segment::{self, Command, PulseRun, SegmentRules};
use crate::IdentError;

impl PulseEnsemble {
    pub(super) fn find(
        &mut self,
        input: &PulseInput<'_>,
        max_width: usize,
    ) -> Result<(), IdentError> {
        let rules = SegmentRules {
            max_pulse_samples: max_width,
            ..SegmentRules::DEFAULT
        };
        let cmd = Command::with_missing(input.u, input.missing);
        match input.pulse_starts {
            Some(starts) if !starts.is_empty() => {
                for &s in starts {
                    match segment::pulse_at(&cmd, s, &rules) {
                        Some(p) => self.push(pulse(&cmd, &p, &rules))?,
                        // A device pulse we cannot use is still a pulse: count it.
                        None => self.push(Pulse {
                            start: s,
                            ..Pulse::default()
                        })?,
                    }
                }
            }
            _ => {
                for p in segment::pulses(cmd, &rules) {
                    self.push(pulse(&cmd, &p, &rules))?;
                }
            }
        }
        Ok(())
    }

    fn push(&mut self, p: Pulse) -> Result<(), IdentError> {
        if self.count == self.pulses.len() {
            return Err(IdentError::LimitsExceeded {
                what: "pulses",
                value: self.count + 1,
                limit: self.pulses.len(),
            });
        }
        self.pulses[self.count] = p;
        self.count += 1;
        Ok(())
    }

    pub(super) fn choose_length(&mut self, input: &PulseInput<'_>) {
        let pulses = &mut self.pulses[..self.count];
        // L maximises (pulses with window >= L) * L: many pulses and a long response.
        let mut len = 0;
        let mut best = 0;
        for cand in pulses
            .iter()
            .filter(|p| p.kept)
            .map(|p| p.window.min(self.max_samples))
        {
            let score = pulses.iter().filter(|p| p.kept && p.window >= cand).count() * cand;
            if score > best || (score == best && cand > len) {
                (best, len) = (score, cand);
            }
        }
        for p in pulses.iter_mut() {
            let gap = (p.base_start..p.start + len).any(|k| missing(input, k));
            if p.kept && (p.window < len || gap) {
                p.kept = false;
            }
        }
        self.kept = pulses.iter().filter(|p| p.kept).count();
        self.len = if self.kept > 0 { len } else { 0 };
    }
}

/// A pulse of the segmentation with its response window (to the end of the run it returns
/// into) and its baseline window (the last half, at most [`MAX_BASELINE`] samples, of the run
/// before it).
fn pulse(cmd: &Command<'_>, p: &PulseRun, rules: &SegmentRules) -> Pulse {
    let back = p.start + p.width;
    let base_len = p.start - p.before_start;
    let nb = base_len.div_ceil(2).clamp(1, MAX_BASELINE);
    Pulse {
        start: p.start,
        width: p.width,
        amplitude: p.amplitude,
        base_start: p.start - nb,
        window: segment::run_end(cmd, back, rules) - p.start,
        kept: true,
    }
}
