//! Which pulses: the segmentation's (or the device's pulse starts, checked by the same rule),
//! each with its baseline and response windows, and the common length `L` that decides which
//! are kept.

use super::{contributes, missing, Pulse, PulseEnsemble, PulseInput, MAX_BASELINE};
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
        // L maximises (pulses with window >= L) * L over the lengths at least half the pulses
        // reach: many pulses and a long response, never one long response instead of many (a
        // pulse fired late, e.g. its command re-sent after a lost ACK, has a long window; it
        // would otherwise leave every other pulse out).
        let need = pulses.iter().filter(|p| p.kept).count().div_ceil(2);
        let mut len = 0;
        let mut best = 0;
        for cand in pulses
            .iter()
            .filter(|p| p.kept)
            .map(|p| p.window.min(self.max_samples))
        {
            let reach = pulses.iter().filter(|p| p.kept && p.window >= cand).count();
            if reach < need {
                continue;
            }
            let score = reach * cand;
            if score > best || (score == best && cand > len) {
                (best, len) = (score, cand);
            }
        }
        for p in pulses.iter_mut() {
            // Holes are no reason to leave a pulse out (the average is per lag), an
            // unmeasured baseline is: the response has no reference.
            let no_base = (p.base_start..p.start).all(|k| missing(input, k));
            // A missing sample inside the pulse carries the pulse level: its width (the
            // input) is not known.
            let no_input = (p.start..p.start + p.width).any(|k| missing(input, k));
            if p.kept && (p.window < len || no_base || no_input) {
                p.kept = false;
            }
            if p.kept {
                let window = p.start..p.start + len;
                p.missing = window.clone().filter(|&k| missing(input, k)).count();
                p.first_missing = window
                    .clone()
                    .position(|k| missing(input, k))
                    .unwrap_or(len);
            }
        }
        self.kept = pulses.iter().filter(|p| p.kept).count();
        // Per-lag count of the pulses measured there; the common length stops before the
        // first lag that none has (nothing is interpolated).
        let mut end = len;
        for k in 0..len {
            let c = pulses
                .iter()
                .filter(|p| p.kept && contributes(input, p, k))
                .count();
            self.lag_count[k] = c;
            if c == 0 {
                end = k;
                break;
            }
        }
        if end < len {
            for p in pulses.iter_mut().filter(|p| p.kept) {
                p.missing = (p.start..p.start + end)
                    .filter(|&k| missing(input, k))
                    .count();
                p.first_missing = p.first_missing.min(end);
            }
        }
        if end == 0 {
            // Not even lag 0 is measured in any pulse: nothing to average.
            pulses.iter_mut().for_each(|p| p.kept = false);
            self.kept = 0;
        }
        self.len = if self.kept > 0 { end } else { 0 };
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
        missing: 0,
        first_missing: 0,
    }
}
