//! Command levels a record visits more than once: whether the stand repeats itself.
//!
//! A staircase up and down, or random steps, holds some commands twice or more. A stand that
//! repeats itself gives each of them the same steady level on every visit, to within the
//! output's noise. When the later visits differ — a load cell whose zero creeps or warms up, a
//! motor or a battery that heats, a propeller that loosened — the static map holds only to
//! that difference, whatever its fitted uncertainty says.
//!
//! For every command held more than once (two levels are the same command by the
//! segmentation's own rule, [`SegmentRules::same`]), in the order of the levels (the record's):
//! the means of its visits and `shift = last − first`. Only held levels count: a ramp's windows
//! met again on the way down differ by the response's lag, not by the stand.
//! [`not_repeatable`] names the largest shift when it is beyond both the noise ([`NOISE_FACTOR`]
//! times the larger standard deviation of the two visits' samples) and [`MIN_SHARE`] of the map's full
//! scale (the largest `|mean|`).

use serde::Serialize;

use super::{finite, Level};
use crate::segment::SegmentRules;

/// Smallest shift, as a share of the map's full scale, called not repeatable.
pub const MIN_SHARE: f64 = 0.02;

/// Smallest shift, in standard deviations of a visit's samples, called not repeatable.
pub const NOISE_FACTOR: f64 = 3.0;

/// One command held more than once.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Repeat {
    /// The command, throttle 0..1.
    pub throttle: f64,
    /// The steady mean of each visit, in the record's order.
    pub means: Vec<f64>,
    /// The last visit's mean minus the first's.
    pub shift: f64,
    /// The larger standard deviation of the first and the last visit's samples.
    #[serde(skip)]
    pub noise: f64,
}

/// The commands of `levels` (the steady levels of holds) held more than once, the same
/// command by `rules` (see the module doc), in order of first visit.
pub fn repeats(levels: &[Level], rules: &SegmentRules) -> Vec<Repeat> {
    let same = |a: f64, b: f64| rules.same(a, b);
    let lv: Vec<&Level> = finite(levels).collect();
    let mut out: Vec<Repeat> = Vec::new();
    for (i, l) in lv.iter().enumerate() {
        if lv[..i].iter().any(|e| same(e.throttle, l.throttle)) {
            continue;
        }
        let visits: Vec<&&Level> = lv[i..]
            .iter()
            .filter(|e| same(e.throttle, l.throttle))
            .collect();
        if let (Some(first), Some(last), true) = (visits.first(), visits.last(), visits.len() > 1) {
            out.push(Repeat {
                throttle: l.throttle,
                means: visits.iter().map(|e| e.mean).collect(),
                shift: last.mean - first.mean,
                noise: first.std.max(last.std),
            });
        }
    }
    out
}

/// The repeat with the largest `|shift|` when it is beyond the noise and [`MIN_SHARE`] of the
/// full scale of `levels` (see the module doc), with that share.
pub fn not_repeatable<'a>(levels: &[Level], repeats: &'a [Repeat]) -> Option<(&'a Repeat, f64)> {
    let full = finite(levels).map(|l| l.mean.abs()).fold(0.0, f64::max);
    let r = repeats
        .iter()
        .max_by(|a, b| a.shift.abs().total_cmp(&b.shift.abs()))?;
    let share = r.shift.abs() / full;
    (full > 0.0 && share > MIN_SHARE && r.shift.abs() > NOISE_FACTOR * r.noise)
        .then_some((r, share))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lv(throttle: f64, mean: f64, std: f64) -> Level {
        Level {
            throttle,
            mean,
            std,
            samples: 50,
        }
    }

    #[test]
    fn a_staircase_up_and_down_pairs_its_levels() {
        // Up 0 → 0.6, down again; the way down 0.3 N lower (a load cell's zero moved).
        let up = [0.0, 0.2, 0.4, 0.6];
        let map = |u: f64| 10.0 * u * u;
        let mut levels: Vec<Level> = up.iter().map(|&u| lv(u, map(u), 0.02)).collect();
        levels.extend(up.iter().rev().skip(1).map(|&u| lv(u, map(u) - 0.3, 0.02)));
        let r = repeats(&levels, &SegmentRules::DEFAULT);
        let at: Vec<f64> = r.iter().map(|r| r.throttle).collect();
        assert_eq!(at, [0.0, 0.2, 0.4]);
        assert!(r
            .iter()
            .all(|r| (r.shift + 0.3).abs() < 1e-12 && r.means.len() == 2));
        let (worst, share) = not_repeatable(&levels, &r).unwrap();
        assert!((worst.shift + 0.3).abs() < 1e-12);
        assert!((share - 0.3 / 3.6).abs() < 1e-12, "{share}");
        // Within the noise, or under 2 % of full scale: repeatable.
        let noisy: Vec<Level> = levels.iter().map(|l| lv(l.throttle, l.mean, 0.2)).collect();
        assert!(not_repeatable(&noisy, &repeats(&noisy, &SegmentRules::DEFAULT)).is_none());
        let tiny: Vec<Level> = up
            .iter()
            .chain(up.iter().rev())
            .enumerate()
            .map(|(i, &u)| lv(u, 100.0 * map(u) + 0.01 * i as f64, 0.0))
            .collect();
        assert!(not_repeatable(&tiny, &repeats(&tiny, &SegmentRules::DEFAULT)).is_none());
    }

    #[test]
    fn a_record_that_never_returns_has_no_repeats() {
        let levels = [lv(0.2, 1.0, 0.0), lv(0.4, 2.0, 0.0), lv(0.6, 3.0, 0.0)];
        assert!(repeats(&levels, &SegmentRules::DEFAULT).is_empty());
        assert!(not_repeatable(&levels, &[]).is_none());
    }
}
