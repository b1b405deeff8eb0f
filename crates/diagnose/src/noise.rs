//! The noise floor of a record, measured from the data itself (issue 11): how small a residual any
//! model of this output can honestly reach.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/noise.rs`.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use propid_numerics::outliers::is_reading;
use propid_numerics::segment::{holds, Command, SegmentRules};

/// Fewest pooled second differences for the hold estimate.
pub const MIN_HOLD_SAMPLES: usize = 30;
/// Order of the fallback ARX fit.
pub const ARX_ORDER: usize = 8;
/// `Φ⁻¹(3/4)`: median of `|N(0, 1)|`.
const MAD_NORMAL: f64 = 0.674_489_750_196_081_7;

/// Where the floor was measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum FloorSource {
    /// Second differences of the output inside the command's steady holds.
    #[serde(rename = "steady holds")]
    SteadyHolds,
    /// One-step residual of an order-8 ARX fit.
    #[serde(rename = "high-order fit")]
    HighOrderFit,
}

/// The noise floor (`"noise_floor"` of `diagnose --json`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NoiseFloor {
    /// Noise RMS, output units.
    pub rms: f64,
    /// How it was measured.
    pub from: FloorSource,
    /// Samples it rests on (second differences, or ARX rows).
    pub samples: usize,
}

/// The noise floor of output `y` (`NaN` = missing) driven by `u`; `interpolated[k]` marks a
/// sample the reader interpolated between the output's readings (empty: every sample a
/// reading: a sparse channel, refreshed on fewer rows than the record has, is measured on its
/// own readings); `rules` are the segmentation's at the record's rate (its holds).
pub fn noise_floor(
    u: &[f64],
    y: &[f64],
    interpolated: &[bool],
    rules: &SegmentRules,
) -> Option<NoiseFloor> {
    measure(u, y, interpolated, rules).ok()
}

/// [`noise_floor`], or why none could be measured: the holds' reason and the high-order
/// fit's, in words (what the verdict says instead of a ratio).
pub fn measure(
    u: &[f64],
    y: &[f64],
    interpolated: &[bool],
    rules: &SegmentRules,
) -> Result<NoiseFloor, String> {
    let holds_why = match hold_differences(u, y, interpolated, rules) {
        Ok(d) => match floor_of(d) {
            Ok(f) => return Ok(f),
            Err(why) => why,
        },
        Err(why) => why,
    };
    from_arx(u, y, interpolated)
        .filter(|f| f.rms > 0.0)
        .ok_or_else(|| {
            format!(
                "{holds_why}; and the order-{ARX_ORDER} fit of the output's readings found no \
             usable one-step residual (too few complete rows, or none left over)"
            )
        })
}

/// The steady-hold estimate (see the module doc), `None` below [`MIN_HOLD_SAMPLES`].
pub fn from_holds(
    u: &[f64],
    y: &[f64],
    interpolated: &[bool],
    rules: &SegmentRules,
) -> Option<NoiseFloor> {
    floor_of(hold_differences(u, y, interpolated, rules).ok()?).ok()
}

/// The floor from the pooled absolute second differences `d` of the holds' readings, or why
/// there is none.
fn floor_of(mut d: Vec<f64>) -> Result<NoiseFloor, String> {
    d.sort_by(f64::total_cmp);
    let m = d.len();
    let median = if m % 2 == 1 {
        d[m / 2]
    } else {
        0.5 * (d[m / 2 - 1] + d[m / 2])
    };
    // A quantised output that rests on one code in most holds has median 0: no estimate.
    if median > 0.0 {
        Ok(NoiseFloor {
            rms: median / (MAD_NORMAL * 6f64.sqrt()),
            from: FloorSource::SteadyHolds,
            samples: m,
        })
    } else {
        Err(format!(
            "the output rests on one value in most of its {m} steady readings in the holds \
             (its noise is below its resolution)"
        ))
    }
}

/// The absolute second differences of consecutive readings of `y` inside the command's holds
/// (at least [`MIN_HOLD_SAMPLES`]), or why there are too few.
fn hold_differences(
    u: &[f64],
    y: &[f64],
    interpolated: &[bool],
    rules: &SegmentRules,
) -> Result<Vec<f64>, String> {
    let n = u.len().min(y.len());
    let mut d: Vec<f64> = Vec::new();
    let mut runs = 0usize;
    for run in holds(Command::new(&u[..n]), rules) {
        runs += 1;
        // Consecutive readings of the hold, a missing sample breaking the chain.
        let mut chain = [f64::NAN; 3];
        let mut len = 0usize;
        for (k, &v) in y.iter().enumerate().take(run.end).skip(run.start) {
            if !v.is_finite() {
                len = 0;
            } else if is_reading(interpolated, k) {
                chain = [chain[1], chain[2], v];
                len += 1;
                if len >= 3 {
                    d.push((chain[2] - 2.0 * chain[1] + chain[0]).abs());
                }
            }
        }
    }
    if runs == 0 {
        return Err("the command holds no level long enough to read the noise in".into());
    }
    if d.len() < MIN_HOLD_SAMPLES {
        return Err(format!(
            "the command's {runs} holds give {} second differences of the output's readings \
             (fewer than {MIN_HOLD_SAMPLES})",
            d.len()
        ));
    }
    Ok(d)
}

/// The high-order-fit estimate (see the module doc), over the output's readings and the input
/// at the same samples when some of the output was interpolated.
pub fn from_arx(u: &[f64], y: &[f64], interpolated: &[bool]) -> Option<NoiseFloor> {
    if interpolated.contains(&true) {
        let at = (0..u.len().min(y.len())).filter(|&k| is_reading(interpolated, k));
        let (u, y): (Vec<f64>, Vec<f64>) = at.map(|k| (u[k], y[k])).unzip();
        return from_arx(&u, &y, &[]);
    }
    let n = ARX_ORDER;
    let p = 2 * n + 1;
    let len = u.len().min(y.len());
    let rows: Vec<usize> = (n..len)
        .filter(|&k| (k - n..=k).all(|j| y[j].is_finite() && u[j].is_finite()))
        .collect();
    let m = rows.len();
    if m < 4 * p {
        return None;
    }
    // Centre and scale each column so the least squares are well conditioned.
    let yc = rows.iter().map(|&k| y[k]).sum::<f64>() / m as f64;
    let uc = rows.iter().map(|&k| u[k]).sum::<f64>() / m as f64;
    let phi = DMatrix::from_fn(m, p, |r, c| {
        let k = rows[r];
        if c < n {
            y[k - 1 - c] - yc
        } else if c < 2 * n {
            u[k - 1 - (c - n)] - uc
        } else {
            1.0
        }
    });
    let target = DVector::from_fn(m, |r, _| y[rows[r]] - yc);
    let svd = phi.clone().svd(true, true);
    let theta = svd.solve(&target, 1e-12).ok()?;
    let resid = target - phi * theta;
    let rms = (resid.norm_squared() / (m - p) as f64).sqrt();
    rms.is_finite().then_some(NoiseFloor {
        rms,
        from: FloorSource::HighOrderFit,
        samples: m,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_testkit::gaussian as noise;

    #[test]
    fn holds_measure_white_noise_under_steps_and_a_drift() {
        // A staircase with a first-order response and a linear drift, plus 0.02 of noise.
        let u: Vec<f64> = (0..3000).map(|k| [0.3, 0.6, 0.45][k / 1000]).collect();
        let e = noise(3000, 0.02, 1);
        let mut x = 0.0;
        let y: Vec<f64> = (0..3000)
            .map(|k| {
                x += 0.1 * (10.0 * u[k] - x);
                x + 0.001 * k as f64 + e[k]
            })
            .collect();
        let f = noise_floor(&u, &y, &[], &SegmentRules::DEFAULT).unwrap();
        assert_eq!(f.from, FloorSource::SteadyHolds);
        assert!((f.rms / 0.02 - 1.0).abs() < 0.1, "{f:?}");
        assert!(f.samples > 2900, "{f:?}");
    }

    #[test]
    fn without_holds_the_high_order_fit_measures_the_noise() {
        // A random input changing every sample: no holds.
        let u = noise(4000, 1.0, 2);
        let e = noise(4000, 0.05, 3);
        let mut x: [f64; 2] = [0.0, 0.0];
        let y: Vec<f64> = (0..4000usize)
            .map(|k| {
                let nx = 1.5 * x[0] - 0.7 * x[1] + 0.2 * u[k.saturating_sub(1)];
                x = [nx, x[0]];
                nx + e[k]
            })
            .collect();
        assert!(from_holds(&u, &y, &[], &SegmentRules::DEFAULT).is_none());
        let f = noise_floor(&u, &y, &[], &SegmentRules::DEFAULT).unwrap();
        assert_eq!(f.from, FloorSource::HighOrderFit);
        assert!((f.rms / 0.05 - 1.0).abs() < 0.2, "{f:?}");
    }

    #[test]
    fn a_sparse_channel_is_measured_at_its_readings_not_its_interpolation() {
        // Readings of 0.01 noise on two levels every 10 rows, linearly interpolated between
        // (as the loader carries a load cell read on one row in ten, and marks what it
        // interpolated): the floor is the readings' noise, not the interpolation's zero second
        // differences, which it would be without the mark.
        let u: Vec<f64> = (0..4000)
            .map(|k| if k < 2000 { 0.3 } else { 0.6 })
            .collect();
        let e = noise(401, 0.01, 5);
        let reading = |j: usize| if j * 10 <= 2000 { 1.0 } else { 2.0 } + e[j];
        let y: Vec<f64> = (0..4000)
            .map(|k| {
                let (j, f) = (k / 10, (k % 10) as f64 / 10.0);
                reading(j) + f * (reading(j + 1) - reading(j))
            })
            .collect();
        let interpolated: Vec<bool> = (0..4000).map(|k| k % 10 != 0).collect();
        let f = from_holds(&u, &y, &interpolated, &SegmentRules::DEFAULT).unwrap();
        assert!((f.rms / 0.01 - 1.0).abs() < 0.2, "{f:?}");
        assert!((300..420).contains(&f.samples), "{f:?}");
        let unmarked = from_holds(&u, &y, &[], &SegmentRules::DEFAULT).unwrap();
        assert!(unmarked.rms < 0.2 * 0.01, "{unmarked:?}");
        let arx = from_arx(&u, &y, &interpolated).unwrap();
        assert!(arx.samples < 400, "only the readings: {arx:?}");
        assert!((arx.rms / 0.01 - 1.0).abs() < 0.3, "{arx:?}");
    }

    #[test]
    fn a_quantised_output_read_on_every_row_counts_every_sample() {
        // Noise of 0.02 read in codes of 0.01: some triples are three codes in a row by
        // chance; they are readings like the others and all count.
        let u = vec![0.5; 3000];
        let y: Vec<f64> = noise(3000, 0.02, 6)
            .iter()
            .map(|e| (e / 0.01).round() * 0.01)
            .collect();
        let f = from_holds(&u, &y, &[], &SegmentRules::DEFAULT).unwrap();
        assert_eq!(f.samples, 2998, "every sample counts: {f:?}");
        assert!((f.rms / 0.02 - 1.0).abs() < 0.1, "{f:?}");
    }

    #[test]
    fn when_no_floor_can_be_measured_the_reason_is_given() {
        // A ramp (no hold) with too few samples for the high-order fit.
        let u: Vec<f64> = (0..40).map(|k| k as f64 * 0.01).collect();
        let why = measure(&u, &u, &[], &SegmentRules::DEFAULT).unwrap_err();
        assert!(why.contains("holds no level"), "{why}");
        assert!(why.contains("order-8 fit"), "{why}");
        // An output resting on one code in its holds.
        let u = vec![0.5; 400];
        let y = vec![1.0; 400];
        let why = measure(&u, &y, &[], &SegmentRules::DEFAULT).unwrap_err();
        assert!(why.contains("rests on one value"), "{why}");
    }

    #[test]
    fn missing_samples_are_skipped() {
        let u = vec![0.5; 500];
        let mut y = noise(500, 0.01, 4);
        for v in y.iter_mut().step_by(7) {
            *v = f64::NAN;
        }
        let f = noise_floor(&u, &y, &[], &SegmentRules::DEFAULT).unwrap();
        assert!(
            f.rms.is_finite() && (f.rms / 0.01 - 1.0).abs() < 0.2,
            "{f:?}"
        );
    }
}
