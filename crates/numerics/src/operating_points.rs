//! Operating points: one model per level of a staircase (or per stretch of a ramp), published as
//! a table — the gain schedule a flight-controller designer needs.
//!
//! Segmentation (one input; the levels, pulses and ramps are those of [`crate::segment`], under
//! [`OpOptions::segment`]):
//! - **Piecewise-constant input** (a staircase with or without pulses): one segment per
//!   [level](crate::segment::levels) (the shorter runs after a level, its pulses or the ramp
//!   into the next one, belong to it). A level is identified from its
//!   own samples when they hold pulses (pulse path); otherwise by OKID over the segment from the
//!   second half of level `i−1` (so the step into level `i` is in it, with the system at rest
//!   before it) to the end of level `i`. The first level has no step into it and is only
//!   identified when it holds pulses. In a pulse experiment (some level holds pulses), levels
//!   without pulses are listed in `skipped` and not identified.
//! - **Ramp** (the input follows time, [`crate::segment::is_ramp`]): the windows of equal length
//!   of [`crate::segment::ramp_windows`], each at the mean input over it.
//! - Anything else is one operating point: the model of the whole record says it all, the
//!   table stays empty.
//!
//! Each segment is identified by [`identify_any`] (pulse path when it holds clean pulses, OKID
//! otherwise). A segment the data does not support (too short, no excitation, no model) is
//! listed in `skipped` with the reason, never silently dropped.

use serde::Serialize;

use super::okid::select::{identify_any, identify_okid, AnyInput, AnyModel, PathTaken};
use super::okid::OkidOptions;
use super::report::Gain;
use super::segment::{self, Command, Level, PulseRun, SegmentRules};
use super::workspace::IdentOptions;

/// Options of [`operating_points`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpOptions {
    /// Shortest segment identified, samples.
    pub min_samples: usize,
    /// Where the levels, pulses and ramps are.
    pub segment: SegmentRules,
}

impl Default for OpOptions {
    fn default() -> Self {
        Self {
            min_samples: 40,
            segment: SegmentRules::DEFAULT,
        }
    }
}

/// One row of the gain schedule.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OperatingPoint {
    /// Input level (throttle fraction, or the input's own unit).
    pub level: f64,
    /// Start of the segment identified, seconds from the record start.
    pub start_s: f64,
    /// Samples in the segment.
    pub samples: usize,
    /// Path taken for this segment.
    pub path: PathTaken,
    /// Model order.
    pub order: usize,
    /// Natural frequency, Hz.
    #[serde(with = "super::nullable::num")]
    pub fn_hz: f64,
    /// Damping ratio.
    #[serde(with = "super::nullable::num")]
    pub zeta: f64,
    /// Time constants of the real poles, s.
    #[serde(with = "super::nullable::vec")]
    pub time_constants_s: Vec<f64>,
    /// Small-signal gain, output units per input unit.
    pub dc_gain: Gain,
}

/// A level that could not be identified, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SkippedPoint {
    /// Input level.
    pub level: f64,
    /// Why.
    pub reason: String,
}

/// The gain schedule.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct OpTable {
    /// `"staircase"`, `"ramp"` or `"single"`.
    pub kind: &'static str,
    /// Identified levels, in record order.
    pub points: Vec<OperatingPoint>,
    /// Levels the data did not support.
    pub skipped: Vec<SkippedPoint>,
}

/// A segment: sample range, the start of the level's own samples, and the level.
struct Segment {
    from: usize,
    own: usize,
    to: usize,
    level: f64,
}

/// Identifies one model per operating point of `input` (see the module docs).
pub fn operating_points(input: &AnyInput<'_>, ident: &IdentOptions, opts: &OpOptions) -> OpTable {
    let Some(u) = input.u.first().filter(|_| input.u.len() == 1) else {
        return OpTable::single();
    };
    let cmd = Command::with_missing(u, input.missing);
    let rules = &opts.segment;
    let (kind, segments) = if segment::is_piecewise_constant(cmd, rules) {
        ("staircase", staircase(&segment::levels(cmd, rules)))
    } else if segment::is_ramp(cmd, rules) {
        ("ramp", ramp(&segment::ramp_windows(cmd, rules)))
    } else {
        ("single", Vec::new())
    };
    if segments.len() < 2 {
        return OpTable::single();
    }
    let ident = IdentOptions {
        jackknife: false,
        ..*ident
    };
    let mut table = OpTable {
        kind,
        ..OpTable::default()
    };
    // A pulse experiment (some level holds pulses): a level without pulses (rest before the
    // first ramp, after the last) is not an operating point of it, whatever OKID would make of
    // the ramp into it.
    let pulses: Vec<PulseRun> = segment::pulses(cmd, rules).collect();
    let with_pulses: Vec<bool> = segments
        .iter()
        .map(|seg| has_pulses(input, seg, &pulses, rules))
        .collect();
    let pulse_experiment = with_pulses.iter().any(|&b| b);
    for (seg, pulses) in segments.iter().zip(with_pulses) {
        if pulse_experiment && !pulses {
            table.skipped.push(SkippedPoint {
                level: seg.level,
                reason: "no pulses at this level (pulse experiment)".into(),
            });
            continue;
        }
        match identify_segment(input, seg, &ident, opts) {
            Ok(p) => table.points.push(p),
            Err(reason) => table.skipped.push(SkippedPoint {
                level: seg.level,
                reason,
            }),
        }
    }
    table
}

impl OpTable {
    fn single() -> Self {
        Self {
            kind: "single",
            ..Self::default()
        }
    }
}

fn identify_segment(
    input: &AnyInput<'_>,
    seg: &Segment,
    ident: &IdentOptions,
    opts: &OpOptions,
) -> Result<OperatingPoint, String> {
    // Pulses of the level itself first (the pulse path, from the level's own samples only).
    if seg.own > seg.from && seg.to - seg.own >= opts.min_samples {
        if let Ok(m) = identify_range(input, seg.own..seg.to, ident, false) {
            if m.path == PathTaken::Pulse {
                return Ok(point(seg, seg.own, m, input.dt_s));
            }
        }
    }
    let n = seg.to - seg.from;
    if n < opts.min_samples {
        return Err(format!("only {n} samples (need {})", opts.min_samples));
    }
    let okid_only = seg.own > seg.from;
    let m = identify_range(input, seg.from..seg.to, ident, okid_only).map_err(|e| e.to_string())?;
    Ok(point(seg, seg.from, m, input.dt_s))
}

/// Identifies `input` over `r` (by [`identify_any`], or OKID only).
fn identify_range(
    input: &AnyInput<'_>,
    r: std::ops::Range<usize>,
    ident: &IdentOptions,
    okid_only: bool,
) -> Result<AnyModel, super::okid::select::AnyError> {
    let u = [&input.u[0][r.clone()]];
    let y: Vec<&[f64]> = input.y.iter().map(|c| &c[r.clone()]).collect();
    let starts: Option<Vec<usize>> = input.pulse_starts.map(|s| {
        s.iter()
            .filter(|&&k| r.contains(&k))
            .map(|k| k - r.start)
            .collect()
    });
    let missing = if input.missing.is_empty() {
        &[][..]
    } else {
        &input.missing[r]
    };
    let sub = AnyInput {
        dt_s: input.dt_s,
        u: &u,
        y: &y,
        missing,
        pulse_starts: starts.as_deref(),
    };
    if okid_only {
        identify_okid(&sub, ident, &OkidOptions::default())
    } else {
        identify_any(&sub, ident, &OkidOptions::default())
    }
}

fn point(seg: &Segment, from: usize, m: AnyModel, dt_s: f64) -> OperatingPoint {
    OperatingPoint {
        level: seg.level,
        start_s: from as f64 * dt_s,
        samples: seg.to - from,
        path: m.path,
        order: m.report.order,
        fn_hz: m.report.fn_hz,
        zeta: m.report.zeta,
        time_constants_s: m.report.time_constants_s,
        dc_gain: m.report.dc_gain,
    }
}

/// One segment per level: the level's own samples, from the second half of the level before
/// (so the step into it is in the segment, with the system at rest before it).
fn staircase(levels: &[Level]) -> Vec<Segment> {
    levels
        .iter()
        .enumerate()
        .map(|(i, l)| Segment {
            from: match i {
                0 => l.start,
                _ => levels[i - 1].start + (levels[i - 1].end - levels[i - 1].start) / 2,
            },
            own: l.start,
            to: l.end,
            level: l.value,
        })
        .collect()
}

/// True when the level's own samples (`seg.own .. seg.to`) hold pulses: device pulse starts
/// there with the level just before them, or (without device events) a pulse of
/// [`segment::pulses`] inside them, on the level.
fn has_pulses(
    input: &AnyInput<'_>,
    seg: &Segment,
    pulses: &[PulseRun],
    rules: &SegmentRules,
) -> bool {
    let r = seg.own..seg.to;
    if let Some(starts) = input.pulse_starts.filter(|s| !s.is_empty()) {
        let u = input.u[0];
        return starts
            .iter()
            .any(|&k| k > 0 && r.contains(&k) && rules.same(u[k - 1], seg.level));
    }
    pulses
        .iter()
        .any(|p| p.start > seg.own && p.start + p.width < seg.to && rules.same(p.level, seg.level))
}

/// One segment per ramp window, at its mean input.
fn ramp(windows: &[Level]) -> Vec<Segment> {
    windows
        .iter()
        .map(|w| Segment {
            from: w.start,
            own: w.start,
            to: w.end,
            level: w.value,
        })
        .collect()
}
