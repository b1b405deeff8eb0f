//! Irregular timestamps onto a uniform grid, with the jitter measured and reported.
//!
//! Logged timestamps from hobby firmware and PC-side stand software are rarely uniform: host
//! arrival times come in USB bursts (three rows 1 ms apart, then a 40 ms pause), exporters write
//! duplicate times, and rows go missing. The identification core needs `t_k = t_0 + k·dt`.
//!
//! Method (documented because results depend on it):
//! 1. Rows whose time is not strictly after the previous kept row (duplicates, steps back) are
//!    dropped and counted ([`Jitter::non_increasing`]).
//! 2. The grid period is `1/fs` when the rate is given, otherwise the **median** spacing of the
//!    kept rows (robust to bursts and gaps).
//! 3. If every spacing is within 10 % of that period (`max |Δt_i − dt| ≤ 0.1 dt`), the rows are
//!    taken as they are ([`Jitter::resampled`] = false): re-interpolating near-uniform data would
//!    only low-pass it.
//! 4. Otherwise each grid point `t_0 + k·dt` takes the **linear interpolation** between the two
//!    rows around it. Linear interpolation is a two-tap FIR whose gain at frequency `f` is
//!    between 1 and `sinc²(f·Δ)` for the local row spacing `Δ`; for the slow dynamics of a motor
//!    (a few Hz at 50 Hz logging) this is a small, bounded attenuation, and unlike a higher-order
//!    interpolant it never overshoots at a step.
//! 5. A grid point with no row within `1.5·dt` on *both* sides of the interval that holds it
//!    (a logging gap) is not bridged: it is marked missing and set to NaN.
//!
//! The jitter (median, 5th and 95th percentile and largest spacing, RMS deviation from the grid
//! period) is reported so that the user can judge the timing of the source.

use serde::Serialize;

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

/// Uniformly sampled channels and the missing mask that came out of [`to_uniform`].
#[derive(Debug, Clone, PartialEq)]
pub struct Uniform {
    /// Time of the first grid point, seconds.
    pub t0_s: f64,
    /// One vector per input channel, on the grid.
    pub channels: Vec<Vec<f64>>,
    /// Grid points with no data.
    pub missing: Vec<bool>,
    /// The timing report.
    pub jitter: Jitter,
}

/// Puts `channels` (one value per row, rows at times `t`) onto a uniform grid; `fs_hz` forces the
/// rate. Rows with a non-finite time are dropped like non-increasing ones. A NaN in a channel
/// stays NaN where it is used. See the module docs for the method.
pub fn to_uniform(
    t: &[f64],
    channels: &[Vec<f64>],
    fs_hz: Option<f64>,
) -> Result<Uniform, ResampleError> {
    if let Some(fs) = fs_hz {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(ResampleError::BadRate(fs));
        }
    }
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
    };
    let rows = |c: &Vec<f64>| keep.iter().map(|&i| c[i]).collect::<Vec<f64>>();
    if max_dev <= 0.1 * dt {
        return Ok(Uniform {
            t0_s: times[0],
            channels: channels.iter().map(rows).collect(),
            missing: vec![false; times.len()],
            jitter,
        });
    }
    // Bound the grid before allocating it: a rate far above the logging rate (`--fs 1e300`)
    // would otherwise overflow the length or exhaust memory.
    let points = ((times[times.len() - 1] - times[0]) / dt).floor() + 1.0;
    let limit = MAX_GRID_POINTS;
    if !(points.is_finite() && points <= limit as f64) {
        return Err(ResampleError::TooManyPoints {
            fs_hz: fs_hz.unwrap_or(1.0 / dt),
            points,
            limit,
        });
    }
    let kept: Vec<Vec<f64>> = channels.iter().map(rows).collect();
    let n = points as usize;
    let mut out = vec![Vec::with_capacity(n); kept.len()];
    let mut missing = vec![false; n];
    let mut j = 0;
    for (k, miss) in missing.iter_mut().enumerate() {
        let tk = times[0] + k as f64 * dt;
        while j + 2 < times.len() && times[j + 1] <= tk {
            j += 1;
        }
        let (ta, tb) = (times[j], times[j + 1]);
        let w = ((tk - ta) / (tb - ta)).clamp(0.0, 1.0);
        *miss = tb - ta > 1.5 * dt && (tk - ta).min(tb - tk) > 0.75 * dt;
        for (o, c) in out.iter_mut().zip(&kept) {
            o.push(if *miss {
                f64::NAN
            } else {
                c[j] + w * (c[j + 1] - c[j])
            });
        }
    }
    jitter.resampled = true;
    jitter.gap_samples = missing.iter().filter(|m| **m).count();
    Ok(Uniform {
        t0_s: times[0],
        channels: out,
        missing,
        jitter,
    })
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
        let u = to_uniform(&t, std::slice::from_ref(&y), None).unwrap();
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
        let u = to_uniform(&t, &[y], Some(50.0)).unwrap();
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
    fn duplicates_are_dropped_and_gaps_marked() {
        let mut t: Vec<f64> = (0..50).map(|k| 0.01 * k as f64).collect();
        t.insert(10, t[9]);
        t.retain(|&x| !(0.2..0.3).contains(&x));
        let y = vec![1.0; t.len()];
        let u = to_uniform(&t, &[y], None).unwrap();
        assert_eq!(u.jitter.non_increasing, 1);
        assert!(u.jitter.resampled);
        assert!(u.jitter.gap_samples >= 8, "{}", u.jitter.gap_samples);
        assert!(u.channels[0][25].is_nan() && u.missing[25]);
    }

    #[test]
    fn a_rate_far_above_the_logging_rate_is_refused() {
        let t = [0.0, 0.01, 0.03, 0.04];
        let y = vec![0.0; 4];
        let e = to_uniform(&t, std::slice::from_ref(&y), Some(1e300)).unwrap_err();
        assert!(matches!(e, ResampleError::TooManyPoints { fs_hz, .. } if fs_hz == 1e300));
        assert!(e.to_string().contains("1e300"), "{e}");
        assert!(to_uniform(&t, &[y], Some(1e3)).is_ok());
    }

    #[test]
    fn bad_times_and_rates_are_errors() {
        assert_eq!(
            to_uniform(&[1.0, 1.0], &[vec![0.0, 0.0]], None),
            Err(ResampleError::TooFewTimes)
        );
        assert!(matches!(
            to_uniform(&[0.0, 1.0], &[], Some(f64::NAN)),
            Err(ResampleError::BadRate(_))
        ));
    }
}
