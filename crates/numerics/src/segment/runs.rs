//! Runs: the one partition of a command every other answer of [`super`] is built on.

use super::SegmentRules;

/// A command sequence, borrowed: one value per sample, and which samples were not measured.
#[derive(Debug, Clone, Copy)]
pub struct Command<'a> {
    /// The command (throttle fraction, or the input's own unit).
    pub u: &'a [f64],
    /// `missing[k]` marks sample `k` not measured; empty means none is. A non-finite value
    /// (NaN) is missing too.
    pub missing: &'a [bool],
}

impl<'a> Command<'a> {
    /// `u` with NaN where a sample is missing.
    pub fn new(u: &'a [f64]) -> Self {
        Self { u, missing: &[] }
    }

    /// `u` with an explicit missing mask (empty: none).
    pub fn with_missing(u: &'a [f64], missing: &'a [bool]) -> Self {
        Self { u, missing }
    }

    /// Samples.
    pub fn len(&self) -> usize {
        self.u.len()
    }

    /// True without samples.
    pub fn is_empty(&self) -> bool {
        self.u.is_empty()
    }

    /// The measured value at `k`, or `None` when it is missing (or past the end).
    pub fn value(&self, k: usize) -> Option<f64> {
        let v = *self.u.get(k)?;
        (v.is_finite() && !self.missing.get(k).copied().unwrap_or(false)).then_some(v)
    }

    /// The last measured value at or before `k` (missing samples carry it), NaN when none.
    pub fn level_at(&self, k: usize) -> f64 {
        (0..=k.min(self.len().saturating_sub(1)))
            .rev()
            .find_map(|j| self.value(j))
            .unwrap_or(f64::NAN)
    }
}

/// One run: the samples from `start` whose measured values stay within the level tolerance of
/// the first one (`value`), up to the next sample that does not (`end`). Missing samples
/// belong to the run they fall in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Run {
    /// First sample after the last measured sample of the run before (`start` unless
    /// samples were missing just before this run; 0 for the first run).
    pub lead: usize,
    /// First sample (measured; 0 for the first run, whose leading missing samples it holds).
    pub start: usize,
    /// One past the last sample (the next run's `start`, or the record's length).
    pub end: usize,
    /// The value the run holds (its first measured value).
    pub value: f64,
}

impl Run {
    /// Samples in the run.
    pub fn len(&self) -> usize {
        self.end - self.start
    }

    /// Never true for a run that was found (kept for the `len` convention).
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }
}

/// The run in progress of a [`RunTracker`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OpenRun {
    pub lead: usize,
    pub start: usize,
    /// First measured value (NaN until there is one).
    pub value: f64,
    /// Last measured value and where it was.
    pub last: f64,
    pub last_at: usize,
}

/// What one sample did to the runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Seen {
    /// Missing: it joins the run in progress.
    Missing,
    /// The first measured sample: it gives the first run its value.
    First,
    /// The same level as the run in progress.
    Same,
    /// A new run starts here; `ended` is the run that ended, `before` the one before it.
    NewRun {
        ended: OpenRun,
        before: Option<OpenRun>,
    },
}

/// Streaming run partition, fixed memory: one sample in, what it did out.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RunTracker {
    tol: f64,
    /// Samples seen (the index of the next one).
    pub next: usize,
    pub cur: OpenRun,
    pub prev: Option<OpenRun>,
}

impl RunTracker {
    pub fn new(rules: &SegmentRules) -> Self {
        Self {
            tol: rules.level_tolerance,
            next: 0,
            cur: OpenRun {
                lead: 0,
                start: 0,
                value: f64::NAN,
                last: f64::NAN,
                last_at: 0,
            },
            prev: None,
        }
    }

    /// Samples in the run in progress, the current one included.
    pub fn run_len(&self) -> usize {
        self.next - self.cur.start
    }

    /// Sample `next` in (`None`: missing).
    pub fn push(&mut self, v: Option<f64>) -> Seen {
        let k = self.next;
        self.next += 1;
        let Some(v) = v else {
            return Seen::Missing;
        };
        if self.cur.value.is_nan() {
            (self.cur.value, self.cur.last, self.cur.last_at) = (v, v, k);
            return Seen::First;
        }
        if (v - self.cur.value).abs() <= self.tol {
            (self.cur.last, self.cur.last_at) = (v, k);
            return Seen::Same;
        }
        let ended = self.cur;
        let before = self.prev.replace(ended);
        self.cur = OpenRun {
            lead: ended.last_at + 1,
            start: k,
            value: v,
            last: v,
            last_at: k,
        };
        Seen::NewRun { ended, before }
    }
}

/// The runs of a command, in order (none when no sample is measured). Allocation-free.
#[derive(Debug, Clone)]
pub struct Runs<'a> {
    cmd: Command<'a>,
    tracker: RunTracker,
    done: bool,
}

impl<'a> Runs<'a> {
    /// The runs of `cmd` under `rules`.
    pub fn new(cmd: Command<'a>, rules: &SegmentRules) -> Self {
        Self {
            cmd,
            tracker: RunTracker::new(rules),
            done: false,
        }
    }
}

impl Iterator for Runs<'_> {
    type Item = Run;

    fn next(&mut self) -> Option<Run> {
        if self.done {
            return None;
        }
        while self.tracker.next < self.cmd.len() {
            let k = self.tracker.next;
            if let Seen::NewRun { ended, .. } = self.tracker.push(self.cmd.value(k)) {
                return Some(Run {
                    lead: ended.lead,
                    start: ended.start,
                    end: k,
                    value: ended.value,
                });
            }
        }
        self.done = true;
        let cur = self.tracker.cur;
        (!cur.value.is_nan()).then_some(Run {
            lead: cur.lead,
            start: cur.start,
            end: self.cmd.len(),
            value: cur.value,
        })
    }
}

/// First measured sample after `from` that is not the same level as the value at `from`
/// (carried over missing samples): the end of the run from `from`, or the record's length.
pub fn run_end(cmd: &Command<'_>, from: usize, rules: &SegmentRules) -> usize {
    let lv = cmd.level_at(from);
    let mut k = from + 1;
    while k < cmd.len() && cmd.value(k).map_or(true, |v| rules.same(v, lv)) {
        k += 1;
    }
    k
}

/// First sample of the run that holds `at`, walking back over samples at the same level as
/// the value at `at` and over missing ones (so it is a run's [`Run::lead`]).
pub fn run_start(cmd: &Command<'_>, at: usize, rules: &SegmentRules) -> usize {
    let lv = cmd.level_at(at);
    let mut k = at;
    while k > 0 && cmd.value(k - 1).map_or(true, |v| rules.same(v, lv)) {
        k -= 1;
    }
    k
}
