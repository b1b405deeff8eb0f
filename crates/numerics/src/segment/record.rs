//! The rules over a whole record: pulses, levels, and what kind of command it is.

use super::classify::{Decision, PulseClassifier, PulseRun};
use super::runs::{run_end, Command, Run, Runs};
use super::SegmentRules;

/// The pulses of a record, in order: exactly the [`Decision::Pulse`]s of a
/// [`PulseClassifier`] fed the record. Allocation-free.
#[derive(Debug, Clone)]
pub struct Pulses<'a> {
    cmd: Command<'a>,
    classifier: PulseClassifier,
}

impl<'a> Pulses<'a> {
    /// The pulses of `cmd` under `rules`.
    pub fn new(cmd: Command<'a>, rules: &SegmentRules) -> Self {
        Self {
            cmd,
            classifier: PulseClassifier::new(*rules),
        }
    }
}

impl Iterator for Pulses<'_> {
    type Item = PulseRun;

    fn next(&mut self) -> Option<PulseRun> {
        while self.classifier.samples() < self.cmd.len() {
            let k = self.classifier.samples();
            let v = self.cmd.value(k).unwrap_or(f64::NAN);
            if let Decision::Pulse(p) = self.classifier.push(v) {
                return Some(p);
            }
        }
        None
    }
}

/// The pulses of `cmd` (see [`Pulses`]).
pub fn pulses<'a>(cmd: Command<'a>, rules: &SegmentRules) -> Pulses<'a> {
    Pulses::new(cmd, rules)
}

/// The pulse starting at `s` if there is one there by the same rule (for a pulse start a
/// device reported): `s` measured and not at the level of the last measured value before it,
/// the run from `s` at most [`SegmentRules::max_pulse_samples`] long, and the first measured
/// sample after it back at that level.
pub fn pulse_at(cmd: &Command<'_>, s: usize, rules: &SegmentRules) -> Option<PulseRun> {
    if s == 0 || s >= cmd.len() {
        return None;
    }
    let level = cmd.level_at(s - 1);
    let value = cmd.level_at(s);
    if !level.is_finite() || rules.same(level, value) {
        return None;
    }
    let back = run_end(cmd, s, rules);
    let width = back - s;
    if width > rules.max_pulse_samples || back >= cmd.len() || !rules.same(cmd.u[back], level) {
        return None;
    }
    Some(PulseRun {
        start: s,
        width,
        amplitude: value - level,
        level,
        before_start: super::runs::run_start(cmd, s - 1, rules),
    })
}

/// One level of a staircase: from the first sample of a run longer than
/// [`SegmentRules::max_pulse_samples`] to the start of the next level at another value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    /// First sample at the level.
    pub start: usize,
    /// One past its last sample: shorter runs after it (its pulses, the ramp or the steps to
    /// the next level) and later runs at the same value belong to it.
    pub end: usize,
    /// The value held.
    pub value: f64,
}

/// The levels of `cmd`, in order. Short runs before the first level belong to none.
pub fn levels(cmd: Command<'_>, rules: &SegmentRules) -> Vec<Level> {
    let mut out: Vec<Level> = Vec::new();
    for run in Runs::new(cmd, rules) {
        let last = out.last_mut();
        if run.len() > rules.max_pulse_samples {
            match last {
                Some(l) if rules.same(l.value, run.value) => l.end = run.end,
                _ => out.push(Level {
                    start: run.start,
                    end: run.end,
                    value: run.value,
                }),
            }
        } else if let Some(l) = last {
            l.end = run.end;
        }
    }
    out
}

/// True when at most [`SegmentRules::max_change_fraction`] of the samples start a new run: a
/// staircase, with or without pulses (the ramps between its levels included).
pub fn is_piecewise_constant(cmd: Command<'_>, rules: &SegmentRules) -> bool {
    let changes = Runs::new(cmd, rules).count().saturating_sub(1);
    changes as f64 <= rules.max_change_fraction * cmd.len() as f64
}

/// True when at least [`SegmentRules::min_level_fraction`] of the samples lie in runs longer
/// than [`SegmentRules::max_pulse_samples`]: flat levels joined by ramps (or steps), possibly
/// with pulses on them.
pub fn is_ramped_staircase(cmd: Command<'_>, rules: &SegmentRules) -> bool {
    let flat: usize = Runs::new(cmd, rules)
        .filter(|r| r.len() > rules.max_pulse_samples)
        .map(|r| r.len())
        .sum();
    !cmd.is_empty() && flat as f64 >= rules.min_level_fraction * cmd.len() as f64
}

/// True when the command follows time: Pearson `|r|` of (sample index, measured value) above
/// [`SegmentRules::ramp_min_correlation`], over at least [`SegmentRules::ramp_min_samples`]
/// measured samples.
pub fn is_ramp(cmd: Command<'_>, rules: &SegmentRules) -> bool {
    let pts = || (0..cmd.len()).filter_map(|k| cmd.value(k).map(|v| (k as f64, v)));
    let n = pts().count();
    if n < rules.ramp_min_samples.max(1) {
        return false;
    }
    let n = n as f64;
    let (mt, mu) = pts().fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
    let (mut stt, mut suu, mut stu) = (0.0, 0.0, 0.0);
    for (t, v) in pts() {
        stt += (t - mt) * (t - mt);
        suu += (v - mu) * (v - mu);
        stu += (t - mt) * (v - mu);
    }
    suu > 0.0 && (stu / (stt * suu).sqrt()).abs() > rules.ramp_min_correlation
}

/// A ramp cut into [`SegmentRules::ramp_windows`] windows of equal length (the last one takes
/// the remainder), each at the mean of its measured values (0 when it has none).
pub fn ramp_windows(cmd: Command<'_>, rules: &SegmentRules) -> Vec<Level> {
    let parts = rules.ramp_windows.max(1);
    let w = cmd.len() / parts;
    (0..parts)
        .map(|i| {
            let (start, end) = (
                i * w,
                if i + 1 == parts {
                    cmd.len()
                } else {
                    (i + 1) * w
                },
            );
            let (s, c) = (start..end)
                .filter_map(|k| cmd.value(k))
                .fold((0.0, 0usize), |a, v| (a.0 + v, a.1 + 1));
            Level {
                start,
                end,
                value: s / c.max(1) as f64,
            }
        })
        .collect()
}

/// A clean command step: a held level (a run longer than
/// [`SegmentRules::max_pulse_samples`]) followed by another held level, at once or through at
/// most [`SegmentRules::max_step_transition_samples`] samples strictly between the two levels
/// and in order (an interpolated or slewed step, never a ramp or a pulse).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// First sample of the level before the step.
    pub before_start: usize,
    /// First sample that left the level before (the first with the new command when the step
    /// is clean, the first transition sample otherwise).
    pub at: usize,
    /// One past the last sample of the level after the step (where its run ends).
    pub after_end: usize,
    /// Command before.
    pub from: f64,
    /// Command after.
    pub to: f64,
}

/// The holds of `cmd`: its runs longer than [`SegmentRules::max_pulse_samples`], where the
/// command is steady (a staircase's levels, the settled part of a pulse experiment's level
/// before its first pulse, each stretch between a random-step sequence's changes).
pub fn holds<'a>(cmd: Command<'a>, rules: &'a SegmentRules) -> impl Iterator<Item = Run> + 'a {
    Runs::new(cmd, rules).filter(|r| r.len() > rules.max_pulse_samples)
}

/// The clean steps of `cmd` (see [`Step`]), in order.
pub fn steps(cmd: Command<'_>, rules: &SegmentRules) -> Vec<Step> {
    let mut out = Vec::new();
    // The last hold, and the short runs seen since it (count, last value, still in order).
    let mut prev: Option<Run> = None;
    let mut between: Vec<Run> = Vec::new();
    for run in Runs::new(cmd, rules) {
        if run.len() <= rules.max_pulse_samples {
            between.push(run);
            continue;
        }
        if let Some(p) = prev {
            let (lo, hi) = (p.value.min(run.value), p.value.max(run.value));
            let inside = between.iter().all(|r| r.value > lo && r.value < hi);
            let ordered = between
                .windows(2)
                .all(|w| (w[1].value - w[0].value) * (run.value - p.value) > 0.0);
            let samples: usize = between.iter().map(Run::len).sum();
            if inside && ordered && samples <= rules.max_step_transition_samples {
                out.push(Step {
                    before_start: p.start,
                    at: between.first().map_or(run.start, |r| r.start),
                    after_end: run.end,
                    from: p.value,
                    to: run.value,
                });
            }
        }
        prev = Some(run);
        between.clear();
    }
    out
}
