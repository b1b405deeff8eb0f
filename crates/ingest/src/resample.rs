//! Irregular timestamps onto a uniform grid, each channel at its own rate, with the jitter
//! measured and reported.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/ingest/src/resample.rs`.

use propid_numerics::segment::SegmentRules;
use serde::Serialize;

use super::coarse_clock::{self, CoarseClock};

/// How regular the timestamps were and what was done about it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Jitter {
    /// Grid period used, seconds.
    pub dt_s: f64,
    /// Median spacing of the kept rows, seconds.
    pub median_dt_s: f64,
    /// 5th percentile of the spacings, seconds.
    pub p5_dt_s: f64,
    /// 95th percentile of the spacings, seconds.
    pub p95_dt_s: f64,
    /// Largest spacing, seconds.
    pub max_dt_s: f64,
    /// RMS of (spacing − grid period), seconds.
    pub rms_jitter_s: f64,
    /// Rows dropped because their time did not increase.
    pub non_increasing: usize,
    /// True when the rows were interpolated onto the grid.
    pub resampled: bool,
    /// Grid points marked missing (gaps wider than 1.5 periods).
    pub gap_samples: usize,
    /// The rows are a table of steady states, every channel held from row to row (module
    /// documentation, step 6; omitted when false).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub steady_rows: bool,
    /// The stamps were coarser than the rows and each tick's rows were spread over it (module
    /// documentation, step 0; omitted otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coarse_clock: Option<CoarseClock>,
}

/// Why the timestamps cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResampleError {
    /// Fewer than two rows with increasing, finite times.
    #[error("fewer than two rows with increasing, finite timestamps")]
    TooFewTimes,
    /// The given rate is not a finite positive number.
    #[error("sample rate must be a finite number > 0, got {0}")]
    BadRate(f64),
    /// The rate would put more grid points on the record than [`MAX_GRID_POINTS`].
    #[error(
        "sample rate {fs_hz:e} Hz would need {points:.3e} grid points over the record (at most \
         {limit}): give a rate close to the logging rate"
    )]
    TooManyPoints {
        /// The rate, Hz (given with --fs, or from the median spacing).
        fs_hz: f64,
        /// Grid points it would need.
        points: f64,
        /// The bound.
        limit: usize,
    },
}

/// Most grid points a resampled record may have (2^24, about 4.7 hours at 1 kHz; 128 MiB per
/// channel of f64).
pub const MAX_GRID_POINTS: usize = 1 << 24;

/// Uniformly sampled channels, the rows' gaps and how each channel was carried, as
/// [`to_uniform`] made them.
#[derive(Debug, Clone, PartialEq)]
pub struct Uniform {
    /// Time of the first grid point, seconds.
    pub t0_s: f64,
    /// One vector per input channel, on the grid; NaN where that channel has no value.
    pub channels: Vec<Vec<f64>>,
    /// Per channel, in the order of `channels`: true at the grid points filled by
    /// interpolation across the channel's own empty cells (not one of its readings; counted in
    /// [`Carried::bridged`]).
    pub bridged: Vec<Vec<bool>>,
    /// Grid points in a gap of the rows themselves (no row near: a logging pause).
    pub missing: Vec<bool>,
    /// How each channel was carried onto the grid, in the order of `channels`.
    pub carried: Vec<Carried>,
    /// The timing report.
    pub jitter: Jitter,
}

/// How one channel was carried onto the grid (module documentation, steps 4 and 5).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Carried {
    /// Its own samples: kept rows whose cell holds a number.
    pub values: usize,
    /// Its own period (median spacing of its own samples), s; `None` with fewer than two.
    pub own_dt_s: Option<f64>,
    /// Grid points filled by interpolation across cells left empty.
    pub bridged: usize,
    /// Grid points left NaN (in a gap of this channel, or outside its first and last sample).
    pub missing: usize,
    /// Rows each reading was repeated for, when the channel was written as a held last reading
    /// ([`super::held`]): its repeats were read as cells not updated (omitted otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub held_rows: Option<usize>,
    /// Empty cells of the command that took the last command written (a command logged on its
    /// changes only, [`super::held::hold_command`]; omitted when 0).
    #[serde(skip_serializing_if = "is_zero_usize")]
    pub command_held: usize,
    /// Rows the exporter had interpolated between the channel's readings, values kept and
    /// marked as not read ([`super::interpolated`]; omitted when 0).
    #[serde(skip_serializing_if = "is_zero_usize")]
    pub interpolated_rows: usize,
}

/// For `skip_serializing_if`: a count of 0 (also the CSV report's).
pub(crate) fn is_zero_usize(v: &usize) -> bool {
    *v == 0
}

/// Puts `channels` (one value per row, rows at times `t`; NaN = an empty cell) onto a uniform
/// grid, each channel from its own samples; `fs_hz` forces the rate; `held[i]` carries channel
/// `i` by holding its last sample (a command) instead of interpolating it (missing: false).
/// Rows with a non-finite time are dropped like non-increasing ones. See the module docs for
/// the method.
pub fn to_uniform(
    t: &[f64],
    channels: &[Vec<f64>],
    fs_hz: Option<f64>,
    held: &[bool],
) -> Result<Uniform, ResampleError> {
    if let Some(fs) = fs_hz {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(ResampleError::BadRate(fs));
        }
    }
    let spread = coarse_clock::spread(t);
    let t: &[f64] = spread.as_ref().map_or(t, |s| &s.0);
    let keep = increasing_rows(t);
    if keep.len() < 2 {
        return Err(ResampleError::TooFewTimes);
    }
    let times: Vec<f64> = keep.iter().map(|&i| t[i]).collect();
    let mut diffs: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let dt = fs_hz.map_or_else(|| percentile(&mut diffs, 0.5), |fs| 1.0 / fs);
    let jitter_rms =
        (diffs.iter().map(|d| (d - dt) * (d - dt)).sum::<f64>() / diffs.len() as f64).sqrt();
    let max_dev = diffs.iter().fold(0.0f64, |m, d| m.max((d - dt).abs()));
    let mut jitter = Jitter {
        dt_s: dt,
        median_dt_s: percentile(&mut diffs, 0.5),
        p5_dt_s: percentile(&mut diffs, 0.05),
        p95_dt_s: percentile(&mut diffs, 0.95),
        max_dt_s: percentile(&mut diffs, 1.0),
        rms_jitter_s: jitter_rms,
        non_increasing: t.len() - keep.len(),
        resampled: false,
        gap_samples: 0,
        // A held channel is a command: the segmentation's one choice of rules for it.
        steady_rows: SegmentRules::for_record(dt, held.contains(&true)).samples_are_steady(),
        coarse_clock: spread.as_ref().map(|s| s.1),
    };
    // The channels' values on the kept rows (the channels themselves when every row is kept:
    // no copy).
    let copied: Vec<Vec<f64>>;
    let kept: &[Vec<f64>] = if keep.len() == t.len() {
        channels
    } else {
        copied = channels
            .iter()
            .map(|c| keep.iter().map(|&i| c[i]).collect())
            .collect();
        &copied
    };
    let grid = if max_dev <= 0.1 * dt {
        Grid::Rows
    } else {
        // Bound the grid before allocating it: a rate far above the logging rate (`--fs 1e300`)
        // would otherwise overflow the length or exhaust memory.
        // A table of steady states keeps its last row: the grid reaches past it (step 6).
        let span = (times[times.len() - 1] - times[0]) / dt;
        let points = if jitter.steady_rows {
            span.ceil()
        } else {
            span.floor()
        } + 1.0;
        let limit = MAX_GRID_POINTS;
        if !(points.is_finite() && points <= limit as f64) {
            return Err(ResampleError::TooManyPoints {
                fs_hz: fs_hz.unwrap_or(1.0 / dt),
                points,
                limit,
            });
        }
        Grid::Uniform(points as usize)
    };
    let all_rows: Vec<usize> = (0..times.len()).collect();
    // A table of steady states holds every channel and has no gap (step 6).
    let steady = jitter.steady_rows;
    let (_, missing) = carry(
        &times,
        &all_rows,
        (&[], Carry::Interpolate, steady),
        grid,
        dt,
    );
    if let Grid::Uniform(_) = grid {
        jitter.resampled = true;
        jitter.gap_samples = missing.iter().filter(|m| **m).count();
    }
    let mut out = Vec::with_capacity(kept.len());
    let mut carried = Vec::with_capacity(kept.len());
    let mut bridged = Vec::with_capacity(kept.len());
    for (i, c) in kept.iter().enumerate() {
        let own: Vec<usize> = (0..c.len()).filter(|&i| c[i].is_finite()).collect();
        let how = match held.get(i) {
            Some(true) => Carry::Hold,
            _ if steady => Carry::Hold,
            _ => Carry::Interpolate,
        };
        let (values, lost) = carry(&times, &own, (c, how, steady), grid, dt);
        let mask = bridged_points(&times, &own, &values, grid, dt);
        carried.push(Carried {
            values: own.len(),
            own_dt_s: own_period(&times, &own),
            bridged: mask.iter().filter(|b| **b).count(),
            missing: lost.iter().filter(|m| **m).count(),
            held_rows: None,
            command_held: 0,
            interpolated_rows: 0,
        });
        out.push(values);
        bridged.push(mask);
    }
    Ok(Uniform {
        t0_s: times[0],
        channels: out,
        bridged,
        missing,
        carried,
        jitter,
    })
}

/// The grid: the kept rows as they are, or `n` points `t_0 + k·dt`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Grid {
    Rows,
    Uniform(usize),
}

impl Grid {
    fn len(self, rows: usize) -> usize {
        match self {
            Grid::Rows => rows,
            Grid::Uniform(n) => n,
        }
    }

    fn time(self, times: &[f64], k: usize, dt: f64) -> f64 {
        match self {
            Grid::Rows => times[k],
            Grid::Uniform(_) => times[0] + k as f64 * dt,
        }
    }
}

/// How a channel's values between its own samples are carried onto the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Carry {
    /// Linearly interpolated (a measured signal: module documentation, step 4).
    Interpolate,
    /// The last own sample at or before the grid time (a command: the ESC holds the last
    /// command until the next; between two commands no third was ever sent).
    Hold,
}

/// One channel onto the grid from its own samples `own` (indices into the kept rows `times`,
/// ascending; values in `c`, or `c` empty for the rows' own gap mask alone), carried `how`,
/// across every spacing when `steady` (no gap: step 6): the values and the grid points in a
/// gap. Steps 4 and 5 of the module documentation; a channel whose every row is its own gives
/// exactly the rows (on the rows' grid) or their interpolation (or hold).
fn carry(
    times: &[f64],
    own: &[usize],
    (c, how, steady): (&[f64], Carry, bool),
    grid: Grid,
    dt: f64,
) -> (Vec<f64>, Vec<bool>) {
    let n = grid.len(times.len());
    let bound = match steady {
        true => f64::INFINITY,
        false => 1.5 * dt.max(own_period(times, own).unwrap_or(dt)),
    };
    let mut values = Vec::with_capacity(if c.is_empty() { 0 } else { n });
    let mut gap = vec![true; n];
    let value = |i: usize| c.get(i).copied().unwrap_or(0.0);
    // (own[j], own[j + 1]) brackets the grid time, as far as the channel's span allows.
    let mut j = 0;
    for (k, in_gap) in gap.iter_mut().enumerate() {
        let tk = grid.time(times, k, dt);
        while j + 2 < own.len() && times[own[j + 1]] <= tk {
            j += 1;
        }
        let v = if grid == Grid::Rows && own.binary_search(&k).is_ok() {
            // On one of its own samples: the sample itself.
            Some(value(k))
        } else if own.len() < 2 {
            None
        } else {
            let (a, b) = (own[j], own[j + 1]);
            let (ta, tb) = (times[a], times[b]);
            // A steady row stands until the next, the last for one grid period (step 6).
            let after = if steady { dt } else { 1e-9 * dt };
            let outside = ta - tk > 1e-9 * dt || tk - tb > after;
            let in_own_gap = tb - ta > bound && (tk - ta).min(tb - tk) > 0.75 * dt;
            (!outside && !in_own_gap).then(|| match how {
                Carry::Interpolate => {
                    let w = ((tk - ta) / (tb - ta)).clamp(0.0, 1.0);
                    value(a) + w * (value(b) - value(a))
                }
                Carry::Hold if tb - tk <= 1e-9 * dt => value(b),
                Carry::Hold => value(a),
            })
        };
        *in_gap = v.is_none();
        if !c.is_empty() {
            values.push(v.unwrap_or(f64::NAN));
        }
    }
    (values, gap)
}

/// A channel's own period: the median spacing of its own samples (`None` with fewer than two).
fn own_period(times: &[f64], own: &[usize]) -> Option<f64> {
    let mut d: Vec<f64> = own.windows(2).map(|w| times[w[1]] - times[w[0]]).collect();
    (!d.is_empty()).then(|| percentile(&mut d, 0.5))
}

/// The grid points whose value was interpolated between two own samples with an empty cell
/// between them (true there): the channel's values that are not its readings.
fn bridged_points(times: &[f64], own: &[usize], values: &[f64], grid: Grid, dt: f64) -> Vec<bool> {
    let mut j = 0;
    let mut mask = vec![false; values.len()];
    for (k, (v, b)) in values.iter().zip(mask.iter_mut()).enumerate() {
        let tk = grid.time(times, k, dt);
        while j + 2 < own.len() && times[own[j + 1]] <= tk {
            j += 1;
        }
        let on_own = grid == Grid::Rows && own.binary_search(&k).is_ok();
        *b = v.is_finite() && !on_own && own.len() >= 2 && own[j + 1] - own[j] > 1;
    }
    mask
}

/// Indices of the rows whose time is finite and strictly after the last kept one.
fn increasing_rows(t: &[f64]) -> Vec<usize> {
    let mut keep = Vec::with_capacity(t.len());
    let mut last = f64::NEG_INFINITY;
    for (i, &ti) in t.iter().enumerate() {
        if ti.is_finite() && ti > last {
            keep.push(i);
            last = ti;
        }
    }
    keep
}

/// The `q`-quantile (0..1, nearest rank) of `v`; sorts `v` in place. `v` must not be empty.
fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    let idx = ((v.len() - 1) as f64 * q).round() as usize;
    v[idx]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_rows_pass_through_untouched() {
        let t: Vec<f64> = (0..100)
            .map(|k| 0.02 * k as f64 + 1e-4 * (k % 3) as f64)
            .collect();
        let y: Vec<f64> = (0..100).map(|k| k as f64).collect();
        let u = to_uniform(&t, std::slice::from_ref(&y), None, &[]).unwrap();
        assert!(!u.jitter.resampled);
        assert_eq!(u.channels[0], y);
        assert!((u.jitter.dt_s - 0.02).abs() < 2e-4);
    }

    #[test]
    fn bursts_are_interpolated_linearly() {
        // Rows in bursts (12 ms, 20 ms, 28 ms apart, as host arrival times come): mean period
        // 20 ms; a ramp must stay a ramp, and no gap is wide enough to be marked.
        let mut t = Vec::new();
        for b in 0..50 {
            for off in [0.0, 0.012, 0.032] {
                t.push(0.06 * b as f64 + off);
            }
        }
        let y: Vec<f64> = t.iter().map(|ti| 3.0 * ti + 1.0).collect();
        let u = to_uniform(&t, &[y], Some(50.0), &[]).unwrap();
        assert!(u.jitter.resampled);
        assert!((u.jitter.dt_s - 0.02).abs() < 1e-12);
        for (k, v) in u.channels[0].iter().enumerate() {
            if !u.missing[k] {
                let tk = u.t0_s + 0.02 * k as f64;
                assert!((v - (3.0 * tk + 1.0)).abs() < 1e-9);
            }
        }
        assert!((u.jitter.max_dt_s - 0.028).abs() < 1e-9);
        assert_eq!(u.jitter.gap_samples, 0);
    }

    #[test]
    fn a_table_of_steady_states_is_held_row_to_row_without_gaps() {
        // One row per command, 5 s apart and then further (a stand waiting to settle): every
        // grid point is a copy of one row, no level is lost to a gap, the last row is kept.
        let t = [0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 39.0, 54.0, 70.0];
        let cmd: Vec<f64> = (0..t.len()).map(|i| 0.1 * i as f64).collect();
        let y: Vec<f64> = cmd.iter().map(|u| 12.0 * u * u).collect();
        let u = to_uniform(&t, &[cmd.clone(), y.clone()], None, &[true, false]).unwrap();
        assert!(u.jitter.steady_rows && u.jitter.resampled);
        assert_eq!(u.jitter.gap_samples, 0);
        assert!(u.missing.iter().all(|m| !m));
        for k in 0..u.missing.len() {
            let tk = u.t0_s + u.jitter.dt_s * k as f64;
            let row = t.iter().rposition(|&ti| ti <= tk + 1e-9).unwrap();
            assert_eq!(u.channels[0][k], cmd[row], "{tk}");
            assert_eq!(u.channels[1][k], y[row], "{tk}");
        }
        let last = u.channels[1].last().unwrap();
        assert_eq!(*last, y[y.len() - 1]);
        // The same rows without a held command are a measured signal: interpolated, and the
        // spacings wider than 1.5 periods are gaps.
        let u = to_uniform(&t, &[y], None, &[false]).unwrap();
        assert!(!u.jitter.steady_rows);
        assert!(u.jitter.gap_samples > 0);
    }

    #[test]
    fn a_command_is_held_between_its_rows_and_never_takes_a_value_between_two() {
        // Rows in bursts; a command stepping 0.2 → 0.5 → 0.3 beside a measured ramp.
        let mut t = Vec::new();
        for b in 0..30 {
            for off in [0.0, 0.012, 0.032] {
                t.push(0.06 * b as f64 + off);
            }
        }
        let cmd: Vec<f64> = t
            .iter()
            .map(|&ti| match ti {
                x if x < 0.6 => 0.2,
                x if x < 1.2 => 0.5,
                _ => 0.3,
            })
            .collect();
        let y: Vec<f64> = t.iter().map(|ti| 3.0 * ti).collect();
        let u = to_uniform(&t, &[cmd.clone(), y], Some(50.0), &[true, false]).unwrap();
        assert!(u.jitter.resampled);
        for (k, v) in u.channels[0].iter().enumerate() {
            let tk = u.t0_s + 0.02 * k as f64;
            // The command in force at the grid time: the last row at or before it.
            let last = t.iter().rposition(|&ti| ti <= tk + 1e-12).unwrap();
            assert_eq!(*v, cmd[last], "{tk}");
        }
        // The measured channel beside it is still interpolated (the ramp stays a ramp).
        let tk = u.t0_s + 0.02;
        assert!((u.channels[1][1] - 3.0 * tk).abs() < 1e-9);
        // Interpolated, the same command takes values no one sent at the steps.
        let lin = to_uniform(&t, &[cmd], Some(50.0), &[]).unwrap();
        assert!(lin.channels[0]
            .iter()
            .any(|v| ![0.2, 0.5, 0.3].iter().any(|c| (v - c).abs() < 1e-12)));
    }

    #[test]
    fn duplicates_are_dropped_and_gaps_marked() {
        let mut t: Vec<f64> = (0..50).map(|k| 0.01 * k as f64).collect();
        t.insert(10, t[9]);
        t.retain(|&x| !(0.2..0.3).contains(&x));
        let y = vec![1.0; t.len()];
        let u = to_uniform(&t, &[y], None, &[]).unwrap();
        assert_eq!(u.jitter.non_increasing, 1);
        assert!(u.jitter.resampled);
        assert!(u.jitter.gap_samples >= 8, "{}", u.jitter.gap_samples);
        assert!(u.channels[0][25].is_nan() && u.missing[25]);
    }

    #[test]
    fn a_rate_far_above_the_logging_rate_is_refused() {
        let t = [0.0, 0.01, 0.03, 0.04];
        let y = vec![0.0; 4];
        let e = to_uniform(&t, std::slice::from_ref(&y), Some(1e300), &[]).unwrap_err();
        assert!(matches!(e, ResampleError::TooManyPoints { fs_hz, .. } if fs_hz == 1e300));
        assert!(e.to_string().contains("1e300"), "{e}");
        assert!(to_uniform(&t, &[y], Some(1e3), &[]).is_ok());
    }

    #[test]
    fn bad_times_and_rates_are_errors() {
        assert_eq!(
            to_uniform(&[1.0, 1.0], &[vec![0.0, 0.0]], None, &[]),
            Err(ResampleError::TooFewTimes)
        );
        assert!(matches!(
            to_uniform(&[0.0, 1.0], &[], Some(f64::NAN), &[]),
            Err(ResampleError::BadRate(_))
        ));
    }

    #[test]
    fn a_slow_channel_is_interpolated_between_its_own_samples() {
        // Rows every 10 ms; the load cell reports on one row in four, the command on each.
        let t: Vec<f64> = (0..41).map(|k| 0.01 * k as f64).collect();
        let cmd: Vec<f64> = (0..41).map(|k| k as f64).collect();
        let slow: Vec<f64> = (0..41)
            .map(|k| if k % 4 == 1 { 2.0 * t[k] } else { f64::NAN })
            .collect();
        let u = to_uniform(&t, &[cmd.clone(), slow], None, &[true, false]).unwrap();
        assert!(!u.jitter.resampled);
        assert_eq!(u.channels[0], cmd, "a full channel is the rows as they are");
        let y = &u.channels[1];
        assert!(y[0].is_nan(), "nothing before its first sample");
        assert!(
            y[38..].iter().all(|v| v.is_nan()),
            "nor after its last (row 37)"
        );
        for k in 1..=37 {
            assert!((y[k] - 2.0 * t[k]).abs() < 1e-12, "{k}: {}", y[k]);
        }
        let c = u.carried[1];
        assert_eq!(c.values, 10);
        assert!((c.own_dt_s.unwrap() - 0.04).abs() < 1e-12);
        assert_eq!(
            c.bridged,
            37 - 1 + 1 - 10,
            "every row between its own samples"
        );
        assert_eq!(c.missing, 1 + 3);
        assert_eq!(u.carried[0].bridged, 0);
        for (k, &b) in u.bridged[1].iter().enumerate() {
            let reading = k % 4 == 1 || !y[k].is_finite();
            assert_eq!(b, !reading, "{k}: the mask marks exactly what was bridged");
        }
        assert!(u.bridged[0].iter().all(|b| !b), "every row a reading");
        assert!(
            u.missing.iter().all(|m| !m),
            "the rows themselves have no gap"
        );
    }

    #[test]
    fn a_dropped_reading_of_a_full_rate_channel_stays_missing() {
        let t: Vec<f64> = (0..20).map(|k| 0.01 * k as f64).collect();
        let mut y: Vec<f64> = (0..20).map(|k| k as f64).collect();
        y[7] = f64::NAN;
        let u = to_uniform(&t, &[y], None, &[]).unwrap();
        let y = &u.channels[0];
        assert!(y[7].is_nan(), "two own periods apart: a gap, not bridged");
        assert_eq!((y[6], y[8]), (6.0, 8.0));
        assert_eq!(u.carried[0].missing, 1);
        assert_eq!(u.carried[0].bridged, 0);
    }

    #[test]
    fn channels_at_different_rates_on_a_resampled_grid() {
        // Irregular rows (12/20/28 ms); one channel on every row, one on every third.
        let mut t = Vec::new();
        for b in 0..40 {
            for off in [0.0, 0.012, 0.032] {
                t.push(0.06 * b as f64 + off);
            }
        }
        let full: Vec<f64> = t.iter().map(|ti| 5.0 * ti).collect();
        let third: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, ti)| if i % 3 == 0 { 1.0 - ti } else { f64::NAN })
            .collect();
        let u = to_uniform(&t, &[full, third], Some(50.0), &[]).unwrap();
        assert!(u.jitter.resampled);
        for (k, (a, b)) in u.channels[0].iter().zip(&u.channels[1]).enumerate() {
            let tk = u.t0_s + 0.02 * k as f64;
            assert!((a - 5.0 * tk).abs() < 1e-9);
            if tk <= 0.06 * 39.0 + 1e-9 {
                assert!((b - (1.0 - tk)).abs() < 1e-9, "{k}: {b}");
            } else {
                assert!(b.is_nan(), "after its last own sample");
            }
        }
        assert!((u.carried[1].own_dt_s.unwrap() - 0.06).abs() < 1e-9);
        assert!(u.carried[1].bridged > 0);
        assert_eq!(u.jitter.gap_samples, 0);
    }
}
