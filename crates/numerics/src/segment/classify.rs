//! The pulse rule, one sample at a time: what a live stream and a whole record both use.

use super::runs::{OpenRun, RunTracker, Seen};
use super::SegmentRules;

/// One pulse: a run of `width` samples at `level + amplitude` between two samples at `level`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseRun {
    /// First sample of the pulse.
    pub start: usize,
    /// Samples from `start` to the sample back at the level (missing ones included).
    pub width: usize,
    /// The pulse's value minus the level (negative for a dip).
    pub amplitude: f64,
    /// The level: the last measured value before the pulse.
    pub level: f64,
    /// First sample of the run before the pulse (its [`Run::lead`](super::Run::lead)).
    pub before_start: usize,
}

/// What a sample decided (see [`PulseClassifier::push`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Decision {
    /// Nothing is held and this sample is not in a possible pulse: pass it on.
    Pass,
    /// This sample may belong to a pulse: hold it (after any held before it).
    Hold,
    /// The held samples are not a pulse: pass them on unmarked; then hold this sample
    /// (`hold`) or pass it on.
    Release {
        /// Whether this sample starts a new possible pulse.
        hold: bool,
    },
    /// The held samples are this pulse: pass them on marked; then pass this sample on (it is
    /// back at the level).
    Pulse(PulseRun),
}

/// The pulse rule of [`super`] as a stream: one command value in, a [`Decision`] out. Fixed
/// memory, no allocation. At most [`SegmentRules::max_pulse_samples`] samples are ever held,
/// and a held sample is decided by the sample after the longest pulse at the latest.
#[derive(Debug, Clone)]
pub struct PulseClassifier {
    rules: SegmentRules,
    runs: RunTracker,
    /// The run in progress may still turn out to be a pulse (its samples are held).
    candidate: bool,
}

impl PulseClassifier {
    /// A classifier with nothing seen yet.
    pub fn new(rules: SegmentRules) -> Self {
        Self {
            runs: RunTracker::new(&rules),
            rules,
            candidate: false,
        }
    }

    /// The rules it applies.
    pub fn rules(&self) -> &SegmentRules {
        &self.rules
    }

    /// Samples pushed since [`new`](Self::new) or [`restart`](Self::restart) (the index the
    /// next one gets in [`PulseRun::start`]).
    pub fn samples(&self) -> usize {
        self.runs.next
    }

    /// One sample in: its command value, NaN when it is missing (a missing sample joins the
    /// run it falls in).
    pub fn push(&mut self, v: f64) -> Decision {
        let k = self.runs.next;
        match self.runs.push(v.is_finite().then_some(v)) {
            Seen::First => Decision::Pass,
            Seen::Missing | Seen::Same => {
                if !self.candidate {
                    Decision::Pass
                } else if self.runs.run_len() > self.rules.max_pulse_samples {
                    self.candidate = false;
                    Decision::Release { hold: false }
                } else {
                    Decision::Hold
                }
            }
            Seen::NewRun { ended, before } => self.new_run(k, v, ended, before),
        }
    }

    /// A run starts at `k` with value `v`: the end of a possible pulse, the start of one, or
    /// both.
    fn new_run(&mut self, k: usize, v: f64, ended: OpenRun, before: Option<OpenRun>) -> Decision {
        let was_candidate = self.candidate;
        let pulse = match before {
            Some(b) if was_candidate && self.rules.same(v, b.last) => Some(PulseRun {
                start: ended.start,
                width: k - ended.start,
                amplitude: ended.value - b.last,
                level: b.last,
                before_start: b.lead,
            }),
            _ => None,
        };
        // The run back at the level after a pulse is not a pulse; any other run is one if it
        // leaves the value just before it and comes back within the limit.
        self.candidate =
            pulse.is_none() && self.rules.max_pulse_samples > 0 && !self.rules.same(v, ended.last);
        match pulse {
            Some(p) => Decision::Pulse(p),
            None if was_candidate => Decision::Release {
                hold: self.candidate,
            },
            None if self.candidate => Decision::Hold,
            None => Decision::Pass,
        }
    }

    /// No more samples for now (end of the record, or a gap too long to bridge): a possible
    /// pulse cannot be confirmed without its end. Returns true when held samples are to be
    /// passed on unmarked. The runs are kept: a sample pushed later continues them.
    pub fn flush(&mut self) -> bool {
        std::mem::take(&mut self.candidate)
    }

    /// Forgets everything (a new boot: the next sample is a first sample again).
    pub fn restart(&mut self) {
        *self = Self::new(self.rules);
    }
}
