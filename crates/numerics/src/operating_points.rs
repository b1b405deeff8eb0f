//! Operating points: one model per level of a staircase (or per stretch of a ramp), published as
//! a table — the gain schedule a flight-controller designer needs.
//!
//! Segmentation (one input):
//! - **Piecewise-constant input** (a staircase with or without pulses): a *level* is a run of
//!   constant input longer than `max_pulse_width` samples (shorter runs are pulses, or the ramp
//!   into the next level, and belong to the level before them). A level is identified from its
//!   own samples when they hold pulses (pulse path); otherwise by OKID over the segment from the
//!   second half of level `i−1` (so the step into level `i` is in it, with the system at rest
//!   before it) to the end of level `i`. The first level has no step into it and is only
//!   identified when it holds pulses. In a pulse experiment (some level holds pulses), levels
//!   without pulses are listed in `skipped` and not identified.
//! - **Ramp** (the input is strongly correlated with time, |r| > 0.9): [`RAMP_WINDOWS`] windows
//!   of equal length, each at the mean input over it.
//! - Anything else is one operating point: the model of the whole record says it all, the
//!   table stays empty.
//!
//! Each segment is identified by [`identify_any`] (pulse path when it holds clean pulses, OKID
//! otherwise). A segment the data does not support (too short, no excitation, no model) is
//! listed in `skipped` with the reason, never silently dropped.

use serde::Serialize;

use super::identify::{identify_any, identify_okid, AnyInput, AnyModel, PathTaken};
use super::okid::OkidOptions;
use super::report::Gain;
use super::workspace::IdentOptions;

/// Windows a ramp is cut into.
pub const RAMP_WINDOWS: usize = 4;

/// Options of [`operating_points`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpOptions {
    /// Shortest segment identified, samples.
    pub min_samples: usize,
    /// Widest pulse, samples (longer runs are levels).
    pub max_pulse_width: usize,
}

impl Default for OpOptions {
    fn default() -> Self {
        Self {
            min_samples: 40,
            max_pulse_width: 32,
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
    let (kind, segments) = if super::identify::is_piecewise_constant(u) {
        ("staircase", staircase(u, opts.max_pulse_width))
    } else if is_ramp(u) {
        ("ramp", ramp(u))
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
    let with_pulses: Vec<bool> = segments
        .iter()
        .map(|seg| has_pulses(input, seg, opts.max_pulse_width))
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
) -> Result<AnyModel, super::identify::AnyError> {
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

/// Levels of a piecewise-constant input: runs longer than `max_pulse`.
fn staircase(u: &[f64], max_pulse: usize) -> Vec<Segment> {
    let mut runs: Vec<(usize, usize, f64)> = Vec::new();
    let mut start = 0;
    for k in 1..=u.len() {
        let end = k == u.len() || (u[k] - u[start]).abs() > 1e-9 && u[k].is_finite();
        if end {
            if k - start > max_pulse {
                match runs.last_mut() {
                    Some(last) if (last.2 - u[start]).abs() <= 1e-9 => last.1 = k,
                    _ => runs.push((start, k, u[start])),
                }
            } else if let Some(last) = runs.last_mut() {
                last.1 = k;
            }
            start = k;
        }
    }
    let mut segs = Vec::with_capacity(runs.len());
    for (i, &(own, to, level)) in runs.iter().enumerate() {
        let from = if i == 0 {
            own
        } else {
            let prev = runs[i - 1];
            prev.0 + (prev.1 - prev.0) / 2
        };
        segs.push(Segment {
            from,
            own,
            to,
            level,
        });
    }
    segs
}

/// True when the level's own samples (`seg.own .. seg.to`) hold pulses: device pulse starts
/// there with the level just before them, or (without device events) a run of at most
/// `max_pulse` samples with the level on both sides.
fn has_pulses(input: &AnyInput<'_>, seg: &Segment, max_pulse: usize) -> bool {
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9;
    let r = seg.own..seg.to;
    let u = input.u[0];
    if let Some(starts) = input.pulse_starts.filter(|s| !s.is_empty()) {
        return starts
            .iter()
            .any(|&k| k > 0 && r.contains(&k) && same(u[k - 1], seg.level));
    }
    let u = &u[r];
    let mut k = 1;
    while k < u.len() {
        if same(u[k - 1], seg.level) && !same(u[k], seg.level) {
            let w = u[k..].iter().take_while(|v| !same(**v, seg.level)).count();
            if w <= max_pulse && k + w < u.len() && u[k..k + w].iter().all(|v| same(*v, u[k])) {
                return true;
            }
            k += w.max(1);
        } else {
            k += 1;
        }
    }
    false
}

/// True when the input follows time closely (|Pearson r| > 0.9).
fn is_ramp(u: &[f64]) -> bool {
    let pts: Vec<(f64, f64)> = u
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .map(|(k, v)| (k as f64, *v))
        .collect();
    let n = pts.len() as f64;
    if n < 8.0 {
        return false;
    }
    let (mt, mu) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
    let (mut stt, mut suu, mut stu) = (0.0, 0.0, 0.0);
    for (t, v) in &pts {
        stt += (t - mt) * (t - mt);
        suu += (v - mu) * (v - mu);
        stu += (t - mt) * (v - mu);
    }
    suu > 0.0 && (stu / (stt * suu).sqrt()).abs() > 0.9
}

/// [`RAMP_WINDOWS`] equal windows at their mean input.
fn ramp(u: &[f64]) -> Vec<Segment> {
    let w = u.len() / RAMP_WINDOWS;
    (0..RAMP_WINDOWS)
        .map(|i| {
            let (from, to) = (
                i * w,
                if i + 1 == RAMP_WINDOWS {
                    u.len()
                } else {
                    (i + 1) * w
                },
            );
            let vals = u[from..to].iter().filter(|v| v.is_finite());
            let (s, c) = vals.fold((0.0, 0usize), |a, v| (a.0 + v, a.1 + 1));
            Segment {
                from,
                own: from,
                to,
                level: s / c.max(1) as f64,
            }
        })
        .collect()
}
