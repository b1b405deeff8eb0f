//! Segmentation: where the levels, steps, ramps and pulses of a command (throttle) sequence
//! are. The one owner of that question: identification, operating points, `diagnose`'s report
//! and the daemon's CSV link all ask here, with one set of thresholds, [`SegmentRules`].
//!
//! # The rules
//!
//! Two values are the **same level** when they differ by at most
//! [`SegmentRules::level_tolerance`]. A missing sample (not measured, or NaN) carries the last
//! measured value and never starts anything.
//!
//! - **Run**: from a measured sample, every following sample at the same level as that first
//!   one; the next measured sample that is not starts the next run ([`Runs`]). Missing samples
//!   belong to the run they fall in; missing samples at the record's start to the first run.
//! - **Pulse**: a run of `1 ..= max_pulse_samples` samples (at most [`MAX_PULSE_S`] long too,
//!   for a record of known rate: [`SegmentRules::at_rate`]) whose value is not the same level
//!   as the last measured value `L` before it, followed by a measured sample at `L` again. The
//!   run that starts there (back at the level) is not itself a pulse. Its amplitude is the
//!   run's value minus `L` ([`PulseRun`]). A run that changes level and does not come back in
//!   time is a **step** (held longer than `max_pulse_samples`) or part of a **ramp**.
//! - **Level**: a run longer than `max_pulse_samples`. The shorter runs after it (its pulses,
//!   the ramp or steps to the next level) and a later run at the same value belong to it
//!   ([`levels`]); the **step** into a level is where it starts.
//! - **Kind of command**: *piecewise constant* when at most
//!   [`SegmentRules::max_change_fraction`] of the samples start a run; a *ramped staircase*
//!   when at least [`SegmentRules::min_level_fraction`] of them lie in levels; a *ramp* when
//!   the value follows time (`|r| > ramp_min_correlation`), cut into
//!   [`SegmentRules::ramp_windows`] windows ([`ramp_windows`]).
//! - **Hold**: a run longer than `max_pulse_samples` (the command steady: [`holds`]); a clean
//!   **step** is one hold followed at once by another ([`steps`]), the input of the step
//!   figures (`step_response`) and the static map (`static_map`).
//!
//! Pulses are decided one sample at a time by [`PulseClassifier`] (fixed memory, no
//! allocation, at most `max_pulse_samples` samples held): the daemon's CSV link feeds it live,
//! and [`pulses`] is the same classifier run over a record, so both give the same answer on the
//! same sequence. [`pulse_at`] checks a pulse start a device reported by the same rule.
//!
//! Steps found from the *response* when no command was logged keep their own method (the
//! application's `ingest::steps`); its thresholds are [`SegmentRules::response`].

mod classify;
mod record;
mod rules;
mod runs;

#[cfg(test)]
mod tests;

pub use classify::{Decision, PulseClassifier, PulseRun};
pub use record::{
    holds, is_piecewise_constant, is_ramp, is_ramped_staircase, levels, pulse_at, pulses,
    ramp_windows, steps, Level, Pulses, Step,
};
pub use rules::{ResponseStepRules, SegmentRules, MAX_PULSE_S};
pub use runs::{run_end, run_start, Command, Run, Runs};
