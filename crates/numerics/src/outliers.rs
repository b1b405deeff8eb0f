//! Isolated outlier samples of a measured channel: found, so that they can be left out (marked
//! missing, never replaced by a guess) and counted.
//!
//! A load cell's ADC glitch or a corrupted value that passed the link's checksum is one sample
//! far off the curve its neighbours lie on. Left in, one such sample dominates the pulse
//! ensemble's lag it falls on (10 N in a 5.4 N record made the SVD fail; 8 N gave fn = NaN),
//! since ERA fits the Markov parameters in the least-squares sense.
//!
//! # The rule (a Hampel identifier on the second difference)
//!
//! For each sample `k` whose neighbours are measured, the residual from the line through its
//! neighbours is
//!
//! $$ r_k = y_k - \tfrac12 (y_{k-1} + y_{k+1}) $$
//!
//! (white noise of standard deviation `σ_y` gives `r` of standard deviation `σ_y √1.5`; a
//! smooth response gives `−ÿ Δt²/2`, small and slowly varying). Its robust scale is
//! `σ_r = 1.4826 · MAD(r)` (the median absolute deviation, unaffected by a few outliers;
//! Hampel 1974), or `1.2533 ·` the mean absolute deviation when the MAD is 0 (a quantised
//! channel that mostly holds one value). Sample `k` is an **isolated outlier** when
//!
//! 1. it stands out of the noise: `|r_k| > OUTLIER_SIGMAS · max(σ_r, σ_loc, δ)`
//!    ([`OUTLIER_SIGMAS`] = 10: a Gaussian false alarm has a probability of ~10⁻²³ per
//!    sample). `σ_loc = 1.4826 · median |r_j|` over the [`LOCAL_HALF_WIDTH`] = 8 samples either
//!    side, the three around `k` excepted (the Hampel filter's local scale): inside an
//!    oscillation or a fast transient every residual is large, so none is an outlier. `δ` is
//!    the channel's resolution, the smallest non-zero step between neighbours, so that a load
//!    cell flickering by one count is never an outlier;
//! 2. it is a spike, not an edge or a corner: its neighbours agree with each other,
//!    `|y_{k+1} − y_{k−1}| ≤ NEIGHBOUR_AGREEMENT · |r_k|` ([`NEIGHBOUR_AGREEMENT`] = ½). One
//!    wrong sample of height `h` gives `|r_k| = h` between neighbours that differ by the noise
//!    only; a step of the response (`|y_{k+1} − y_{k−1}| = h`, `|r| = h/2`) or the corner where
//!    a response starts rising after its dead time (`|r| = slope/2`, neighbours a slope apart)
//!    never passes, however large; and
//! 3. the command does not change from `k − 2` to `k + 2` ([`COMMAND_GUARD`]): a command
//!    pulse and the first samples of its response (a direct feed-through makes a one-sample
//!    pulse look like a spike) are never outliers.
//!
//! Only single samples are found: two adjacent wrong samples are not isolated and stay in.
//! The first and last samples, and samples next to a missing one, are never judged.

/// Residuals larger than this many robust standard deviations are outliers.
pub const OUTLIER_SIGMAS: f64 = 10.0;
/// Samples either side of `k` whose residuals give the local scale.
pub const LOCAL_HALF_WIDTH: usize = 8;
/// A spike's neighbours differ by at most this fraction of its residual.
pub const NEIGHBOUR_AGREEMENT: f64 = 0.5;
/// Samples either side of a command change that are never judged.
pub const COMMAND_GUARD: usize = 2;

/// Consistency factor of the MAD for Gaussian data (σ ≈ 1.4826 · MAD; the one copy: the
/// start-up rule and ingest's step finder use it too).
pub const MAD_TO_SD: f64 = 1.4826;
/// Consistency factor of the mean absolute deviation for Gaussian data (`√(π/2)`).
const MEAN_AD_TO_SD: f64 = 1.2533;

/// The isolated outliers of `y` (sample indices, ascending). `missing` (empty: none) marks
/// samples that are not measured; `command` (empty: none) is the input whose changes and their
/// first response samples are never judged. Allocates its scratch; see [`find_outliers`] to
/// reuse one.
pub fn isolated_outliers(y: &[f64], missing: &[bool], command: &[f64]) -> Vec<usize> {
    let mut scratch = OutlierScratch::with_capacity(y.len());
    find_outliers(y, missing, command, &mut scratch).to_vec()
}

/// Whether sample `k` of a channel is one of its readings: not marked in `interpolated` (true
/// where a reader filled the value in between two readings; empty: every sample a reading,
/// `Channel::interpolated` of the wire record).
pub fn is_reading(interpolated: &[bool], k: usize) -> bool {
    !interpolated.get(k).copied().unwrap_or(false)
}

/// [`isolated_outliers`] of a channel read at some of its samples only: `interpolated[k]` is
/// true where a reader filled the value in between two of the channel's readings (a load cell
/// written on one row in ten; empty: every sample a reading). An interpolated sample lies on
/// the line through its neighbours (`r = 0`): pooled with the readings, the robust scale would
/// be that zero and every reading's own noise would stand out as a spike. The rule therefore
/// judges the readings as the sequence they are, the command taken at the same samples (its
/// guard then spans [`COMMAND_GUARD`] readings either side). A reading found is returned with
/// the interpolated samples between it and its neighbouring readings, which were carried from
/// it; indices ascending.
pub fn isolated_outliers_of_readings(
    y: &[f64],
    missing: &[bool],
    command: &[f64],
    interpolated: &[bool],
) -> Vec<usize> {
    if !interpolated.contains(&true) {
        return isolated_outliers(y, missing, command);
    }
    let at: Vec<usize> = (0..y.len())
        .filter(|&k| is_reading(interpolated, k))
        .collect();
    let ys: Vec<f64> = at.iter().map(|&k| y[k]).collect();
    let ms: Vec<bool> = if missing.is_empty() {
        Vec::new()
    } else {
        at.iter()
            .map(|&k| missing.get(k).copied().unwrap_or(false))
            .collect()
    };
    let cs: Vec<f64> = if command.is_empty() {
        Vec::new()
    } else {
        at.iter()
            .map(|&k| command.get(k).copied().unwrap_or(f64::NAN))
            .collect()
    };
    let mut out = Vec::new();
    for j in isolated_outliers(&ys, &ms, &cs) {
        // Never the first or last reading (the rule does not judge them), so both exist.
        out.extend(at[j - 1] + 1..at[j + 1]);
    }
    out
}

/// The buffers [`find_outliers`] works in: allocated once for records of up to `capacity`
/// samples (the daemon's window), so that judging a window allocates nothing.
#[derive(Debug, Clone, Default)]
pub struct OutlierScratch {
    /// `r[k]` (NaN where not judged).
    r: Vec<f64>,
    /// Values whose median is taken.
    sel: Vec<f64>,
    /// Their deviations from it.
    dev: Vec<f64>,
    /// The command guard.
    guard: Vec<bool>,
    /// The outliers found.
    found: Vec<usize>,
}

impl OutlierScratch {
    /// Scratch for records of up to `capacity` samples (a longer one only reallocates).
    pub fn with_capacity(capacity: usize) -> OutlierScratch {
        OutlierScratch {
            r: Vec::with_capacity(capacity),
            sel: Vec::with_capacity(capacity),
            dev: Vec::with_capacity(capacity),
            guard: Vec::with_capacity(capacity),
            found: Vec::with_capacity(capacity),
        }
    }
}

/// [`isolated_outliers`] in caller-provided scratch: the same rule, the same indices
/// (ascending), returned as a slice of `scratch`; no allocation when `y` fits its capacity.
pub fn find_outliers<'s>(
    y: &[f64],
    missing: &[bool],
    command: &[f64],
    scratch: &'s mut OutlierScratch,
) -> &'s [usize] {
    let n = y.len();
    let OutlierScratch {
        r,
        sel,
        dev,
        guard,
        found,
    } = scratch;
    found.clear();
    let measured = |k: usize| y[k].is_finite() && !missing.get(k).copied().unwrap_or(false);
    // r[k] for 1 <= k < n-1 with all three samples measured, NaN otherwise
    r.clear();
    r.extend((0..n).map(|k| {
        if k == 0 || k + 1 >= n || !(measured(k - 1) && measured(k) && measured(k + 1)) {
            f64::NAN
        } else {
            y[k] - 0.5 * (y[k - 1] + y[k + 1])
        }
    }));
    let Some(sigma) = robust_sd(r, sel, dev) else {
        return found;
    };
    let sigma = sigma.max(resolution(y));
    command_changes(command, n, guard);
    for k in 1..n.saturating_sub(1) {
        let rk = r[k].abs();
        if rk.is_finite()
            && rk > OUTLIER_SIGMAS * sigma
            && (y[k + 1] - y[k - 1]).abs() <= NEIGHBOUR_AGREEMENT * rk
            && !guard[k]
            && rk > OUTLIER_SIGMAS * local_sd(r, k, sel)
        {
            found.push(k);
        }
    }
    found
}

/// `1.4826 · median |r_j|` for the finite `r_j`, `j` within [`LOCAL_HALF_WIDTH`] of `k` but
/// not `k − 1 ..= k + 1` (0 when there is none); `v` is scratch.
fn local_sd(r: &[f64], k: usize, v: &mut Vec<f64>) -> f64 {
    let lo = k.saturating_sub(LOCAL_HALF_WIDTH);
    let hi = (k + LOCAL_HALF_WIDTH).min(r.len() - 1);
    v.clear();
    v.extend(
        (lo..=hi)
            .filter(|&j| j + 1 < k || j > k + 1)
            .map(|j| r[j].abs())
            .filter(|x| x.is_finite()),
    );
    if v.is_empty() {
        return 0.0;
    }
    MAD_TO_SD * median(v)
}

/// Robust standard deviation of the finite values of `r`: `1.4826 · MAD`, or `1.2533 ·` the
/// mean absolute deviation from the median when the MAD is 0; `None` when that is 0 too or
/// fewer than 8 values are finite (nothing to judge against). `v`, `dev` are scratch.
fn robust_sd(r: &[f64], v: &mut Vec<f64>, dev: &mut Vec<f64>) -> Option<f64> {
    v.clear();
    v.extend(r.iter().copied().filter(|x| x.is_finite()));
    if v.len() < 8 {
        return None;
    }
    let med = median(v);
    dev.clear();
    dev.extend(v.iter().map(|x| (x - med).abs()));
    let mad = MAD_TO_SD * median(dev);
    let sd = if mad > 0.0 {
        mad
    } else {
        MEAN_AD_TO_SD * dev.iter().sum::<f64>() / dev.len() as f64
    };
    (sd.is_finite() && sd > 0.0).then_some(sd)
}

/// The smallest non-zero `|y_k − y_{k−1}|` (0 when there is none).
pub(crate) fn resolution(y: &[f64]) -> f64 {
    let d = y
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| d.is_finite() && *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if d.is_finite() {
        d
    } else {
        0.0
    }
}

/// Median (reorders `v` in place, without allocating; `v` not empty).
pub(crate) fn median(v: &mut [f64]) -> f64 {
    let m = v.len() / 2;
    let odd = v.len() % 2 == 1;
    let (below, mid, _) = v.select_nth_unstable_by(m, f64::total_cmp);
    let mid = *mid;
    if odd {
        mid
    } else {
        // the largest of the lower half
        let lower = below.iter().copied().max_by(f64::total_cmp).unwrap_or(mid);
        0.5 * (lower + mid)
    }
}

/// `guard[k]` (resized to `n`): the command changes between `k − COMMAND_GUARD` and
/// `k + COMMAND_GUARD`.
fn command_changes(command: &[f64], n: usize, guard: &mut Vec<bool>) {
    guard.clear();
    guard.resize(n, false);
    let changed = |j: usize| {
        j >= 1
            && j < command.len()
            && command[j].to_bits() != command[j - 1].to_bits()
            && !(command[j].is_nan() && command[j - 1].is_nan())
    };
    for j in (1..command.len().min(n)).filter(|&j| changed(j)) {
        let lo = j.saturating_sub(COMMAND_GUARD + 1);
        let hi = (j + COMMAND_GUARD).min(n - 1);
        guard[lo..=hi].iter_mut().for_each(|g| *g = true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_testkit::{add_noise, throttle, Plant};

    /// A 1 kHz pulse record at 5.4 N (the plant of issue 12: fn 12 Hz, ζ 0.7, 12 N/throttle),
    /// 0.01 N noise, one-sample pulses every 250 samples.
    fn record(n: usize) -> (Vec<f64>, Vec<f64>) {
        let pulses: Vec<_> = (0..n / 250 - 1)
            .map(|i| (200 + 250 * i, 1, if i % 2 == 0 { 0.1 } else { -0.1 }))
            .collect();
        let u = throttle(n, &[(0, 0.45)], &pulses);
        let plant = Plant::new(12.0, 0.7, 12.0, 0.001);
        let mut y = plant.simulate(&u, 5.4).remove(0);
        add_noise(&mut y, 0.01, 3);
        (u, y)
    }

    #[test]
    fn a_clean_record_has_none() {
        let (u, y) = record(4000);
        assert_eq!(isolated_outliers(&y, &[], &u), Vec::<usize>::new());
        // nor without the command to guard its pulses
        assert_eq!(isolated_outliers(&y, &[], &[]), Vec::<usize>::new());
    }

    #[test]
    fn a_single_wrong_sample_is_found_wherever_it_is() {
        let (u, y) = record(4000);
        for (at, value) in [
            (1337, 10.0),
            (1337, 8.0),
            (1, 5.5),
            (3998, 0.0),
            (2000, 5.6),
        ] {
            let mut bad = y.clone();
            bad[at] = value;
            assert_eq!(
                isolated_outliers(&bad, &[], &u),
                vec![at],
                "{value} at {at}"
            );
        }
        // several, apart
        let mut bad = y.clone();
        bad[500] = 9.0;
        bad[2600] = -3.0;
        assert_eq!(isolated_outliers(&bad, &[], &u), vec![500, 2600]);
    }

    #[test]
    fn steps_pulses_and_missing_samples_are_not_outliers() {
        // a noiseless step of the command and of the response (the response is a ramp-free
        // jump of 5 N: an edge, not a spike)
        let mut y = vec![1.0; 400];
        y[200..].iter_mut().for_each(|v| *v = 6.0);
        add_noise(&mut y, 0.01, 9);
        assert!(isolated_outliers(&y, &[], &[]).is_empty());
        // a direct feed-through makes the response of a one-sample pulse a spike: guarded by
        // the command
        let (u, mut y) = record(1000);
        y[450] += 3.0; // the pulse at 450 seen through D
        assert!(isolated_outliers(&y, &[], &u).is_empty());
        // a missing sample (NaN, marked) next to a value is never judged, nor the NaN itself
        let (u, mut y) = record(1000);
        let mut missing = vec![false; y.len()];
        y[600] = f64::NAN;
        missing[600] = true;
        assert!(isolated_outliers(&y, &missing, &u).is_empty());
    }

    #[test]
    fn corners_and_oscillations_are_not_outliers() {
        // a step response after a dead time, sampled coarsely (a bench log at 45 Hz): the
        // corner where it starts rising has one large residual, but its neighbours are a
        // slope apart (measured on vanderploeg 90PERCENT: 0.014, 0.031, 0.381, 0.621)
        let mut y = vec![0.02; 60];
        let rise = [0.031, 0.381, 0.621, 0.685, 0.702, 0.703];
        for (k, v) in rise.iter().enumerate() {
            y[30 + k] = *v;
        }
        y[36..].iter_mut().for_each(|v| *v = 0.703);
        add_noise(&mut y, 0.004, 5);
        assert!(isolated_outliers(&y, &[], &[]).is_empty());
        // a disturbance at a quarter of the sample rate: every peak stands out of its two
        // agreeing neighbours, as does every other peak (the local scale)
        let mut y = vec![1.0; 400];
        for (k, v) in y.iter_mut().enumerate() {
            *v += 0.5 * (std::f64::consts::FRAC_PI_2 * k as f64).sin();
        }
        add_noise(&mut y, 0.01, 6);
        assert!(isolated_outliers(&y, &[], &[]).is_empty());
    }

    #[test]
    fn reused_scratch_finds_the_same_outliers_without_growing() {
        let (u, y) = record(4000);
        let mut scratch = OutlierScratch::with_capacity(4000);
        let cap = scratch.r.capacity();
        for (at, value) in [(1337, 10.0), (2000, 5.6), (0, 0.0)] {
            let mut bad = y.clone();
            bad[at] = value;
            // a shorter record after a longer one, and the same again
            for n in [4000, 2500, 4000] {
                let want = isolated_outliers(&bad[..n], &[], &u[..n]);
                assert_eq!(
                    find_outliers(&bad[..n], &[], &u[..n], &mut scratch),
                    &want[..]
                );
            }
        }
        assert_eq!(scratch.r.capacity(), cap);
        // the median without sorting: odd, even, repeated values
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut [1.0, 1.0, 5.0, 1.0]), 1.0);
    }

    #[test]
    fn two_adjacent_wrong_samples_are_not_isolated() {
        let (u, mut y) = record(2000);
        y[700] = 10.0;
        y[701] = 10.0;
        assert!(isolated_outliers(&y, &[], &u).is_empty());
    }

    #[test]
    fn a_quantised_channel_still_has_a_scale() {
        // a load cell at 0.1 N resolution holding 5.4 N, with a few quantum flickers
        let mut y = vec![5.4; 1000];
        for k in (0..1000).step_by(37) {
            y[k] = 5.5;
        }
        y[333] = 9.0;
        assert_eq!(isolated_outliers(&y, &[], &[]), vec![333]);
        // a constant channel: nothing to judge against
        assert!(isolated_outliers(&[5.4; 100], &[], &[]).is_empty());
    }

    #[test]
    fn a_channel_read_every_tenth_sample_is_judged_at_its_readings() {
        // The pulse record read every 10 samples, interpolated between: pooled, the
        // interpolated samples' zero residuals make readings' noise look like spikes.
        let (u, y) = record(4000);
        let interpolated: Vec<bool> = (0..4000).map(|k| k % 10 != 0).collect();
        let lined: Vec<f64> = (0..4000)
            .map(|k| {
                let (a, f) = (k - k % 10, (k % 10) as f64 / 10.0);
                let b = (a + 10).min(3990);
                y[a] + f * (y[b] - y[a])
            })
            .collect();
        let pooled = isolated_outliers(&lined, &[], &u);
        assert!(
            pooled.len() > 5,
            "the pooled rule flags readings: {pooled:?}"
        );
        assert!(isolated_outliers_of_readings(&lined, &[], &u, &interpolated).is_empty());
        // A wrong reading is found, with the samples carried from it.
        let mut bad = lined.clone();
        bad[1330] = 10.0;
        for k in 1321..1330 {
            bad[k] = lined[1320] + (k - 1320) as f64 / 10.0 * (10.0 - lined[1320]);
        }
        for k in 1331..1340 {
            bad[k] = 10.0 + (k - 1330) as f64 / 10.0 * (lined[1340] - 10.0);
        }
        let found = isolated_outliers_of_readings(&bad, &[], &u, &interpolated);
        assert_eq!(found, (1321..1340).collect::<Vec<_>>());
        // Every sample a reading: the rule as it is.
        assert_eq!(
            isolated_outliers_of_readings(&y, &[], &u, &[]),
            isolated_outliers(&y, &[], &u)
        );
    }
}
