//! The output's reading at zero command: a load cell not tared, a torque cell's zero, an
//! electronic speed controller's own current. A power law `k·max(u − u₀, 0)^e` and the expo
//! blend both pass through zero below the dead band, so a reading of `c ≠ 0` there bends both
//! to fit it: 30 gf on a 900 gf·u² propeller (levels 0, 0.2 … 0.9, 0.5, 0) turns `e = 2.00`
//! from throttle 0 into `e = 4.76` from throttle −0.88 and the expo `a` from 1.00 to 0.88
//! (−30 gf: `e = 1.58` from 0.16, `a = 1.13`); an ESC's 0.3 A at rest turns `I = 0.3 + 20·u³`
//! into `e = 9.7 ± 9.3` (the tests check these figures).
//!
//! **When a reading is taken.** Only a level held at zero command (throttle ≤ [`AT_ZERO`]: the
//! scale's zero, 1000 µs, 0 %, DShot 48, never the lowest level a record happens to hold)
//! measures it: there the command cannot move the output, whatever it reads. `c` is the
//! sample-weighted mean of those levels. It is taken when the map with it fits the levels
//! significantly better than the map through zero: with `S₃` the squared error of the power
//! law on the levels as read (3 parameters) and `S₄` that of `c` plus the power law on the
//! levels less `c` (4), both weighted as the power law is fitted ([`super::power_weights`]),
//! `F = (S₃ − S₄) / (S₄ / (n − 4))` above the 1 % point of Fisher's `F(1, n − 4)` (an
//! extra-sum-of-squares test; Bates & Watts 1988, §3.5), with at least [`MIN_LEVELS`] levels. A small reading the levels cannot tell from the map's misfit is not
//! taken: the curves then stay fitted to the levels as read.
//!
//! Its standard error is that of the mean of the zero-command levels' means (their spread
//! over the visits), or the pooled samples' when it was held once: `std / √samples`.

use serde::Serialize;

use super::{fit_power_law, power_weights, Level, PowerLaw};

/// Throttle at or below which a level is held at zero command.
pub const AT_ZERO: f64 = 0.01;

/// Fewest levels for the test: four parameters and one degree of freedom left (a five-level
/// staircase from zero command; its 1 % point, 4052, takes only an offset the power law then
/// fits almost exactly).
pub const MIN_LEVELS: usize = 5;

/// The output's reading at zero command, taken out of the map's curves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ZeroOffset {
    /// The reading, the output's unit: `power` and `expo` describe the output above it.
    pub value: f64,
    /// Its standard error.
    pub sd: f64,
    /// How many held levels were at zero command.
    pub levels: usize,
    /// The extra-sum-of-squares `F` of taking it (see the module doc).
    pub f: f64,
}

/// The 1 % point of `F(1, d)` (Fisher's tables), the next smaller tabulated `d` for others
/// (a stricter point), `None` below `d = 1`.
fn f_critical_1pct(d: usize) -> Option<f64> {
    const TABLE: [(usize, f64); 16] = [
        (1, 4052.2),
        (2, 98.50),
        (3, 34.12),
        (4, 21.20),
        (5, 16.26),
        (6, 13.75),
        (7, 12.25),
        (8, 11.26),
        (9, 10.56),
        (10, 10.04),
        (12, 9.33),
        (15, 8.68),
        (20, 8.10),
        (30, 7.56),
        (60, 7.08),
        (120, 6.85),
    ];
    TABLE.iter().rev().find(|(n, _)| *n <= d).map(|(_, f)| *f)
}

/// Squared error of `law` (plus `offset`) on the levels, weighted as the power law is fitted
/// (`w`: [`super::power_weights`] of the levels as read, the same for both maps).
fn sse(levels: &[Level], w: &[f64], law: &PowerLaw, offset: f64) -> f64 {
    levels
        .iter()
        .zip(w)
        .map(|(l, w)| w * (l.mean - offset - law.predict(l.throttle)).powi(2))
        .sum()
}

/// The levels with `offset` taken from their means.
pub fn shifted(levels: &[Level], offset: f64) -> Vec<Level> {
    levels
        .iter()
        .map(|l| Level {
            mean: l.mean - offset,
            ..*l
        })
        .collect()
}

/// The zero-command reading of `levels` when the levels show it (see the module doc), else
/// `None`: no level at zero command, fewer than [`MIN_LEVELS`] levels, or no significant gain.
pub fn zero_offset(levels: &[Level]) -> Option<ZeroOffset> {
    let levels: Vec<Level> = levels
        .iter()
        .filter(|l| l.throttle.is_finite() && l.mean.is_finite())
        .copied()
        .collect();
    let n = levels.len();
    let zero: Vec<&Level> = levels.iter().filter(|l| l.throttle <= AT_ZERO).collect();
    if zero.is_empty() || n < MIN_LEVELS {
        return None;
    }
    let weight: usize = zero.iter().map(|l| l.samples.max(1)).sum();
    let c = zero
        .iter()
        .map(|l| l.mean * l.samples.max(1) as f64)
        .sum::<f64>()
        / weight as f64;
    let w = power_weights(&levels.iter().map(|l| l.mean).collect::<Vec<_>>());
    let through_zero = fit_power_law(&levels)?;
    let s3 = sse(&levels, &w, &through_zero, 0.0);
    let above = fit_power_law(&shifted(&levels, c))?;
    let s4 = sse(&levels, &w, &above, c);
    let scale: f64 = levels
        .iter()
        .zip(&w)
        .map(|(l, w)| w * l.mean * l.mean)
        .sum();
    let d = n - 4;
    let f = (s3 - s4) / (s4 / d as f64).max(1e-24 * scale);
    // NaN (no misfit either way) is no evidence.
    if f.is_nan() || f <= f_critical_1pct(d)? {
        return None;
    }
    let sd = match zero.len() {
        1 => zero[0].std / (zero[0].samples.max(1) as f64).sqrt(),
        m => {
            let mean = zero.iter().map(|l| l.mean).sum::<f64>() / m as f64;
            let var = zero.iter().map(|l| (l.mean - mean).powi(2)).sum::<f64>() / (m - 1) as f64;
            (var / m as f64).sqrt()
        }
    };
    Some(ZeroOffset {
        value: c,
        sd,
        levels: zero.len(),
        f,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lv(throttle: f64, mean: f64) -> Level {
        Level {
            throttle,
            mean,
            std: 0.01,
            samples: 100,
        }
    }

    /// A staircase 0, 0.2 … 0.9, back to 0.5 and 0 of `900 gf · u²` in newtons plus `offset`,
    /// each level off by a deterministic ±0.3 % of its thrust (a real stand's repeatability).
    fn staircase(offset: f64) -> Vec<Level> {
        [0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.5, 0.0]
            .iter()
            .enumerate()
            .map(|(i, &u)| {
                let t = 8.826 * u * u;
                let wobble = if i % 2 == 0 { 0.003 } else { -0.003 };
                lv(u, t * (1.0 + wobble) + offset)
            })
            .collect()
    }

    #[test]
    fn an_untared_load_cell_is_read_at_zero_command_and_taken_out_of_the_map() {
        for offset in [0.294, -0.294, 0.05] {
            let l = staircase(offset);
            let z = zero_offset(&l).unwrap_or_else(|| panic!("offset {offset} not taken"));
            assert!((z.value - offset).abs() < 1e-9, "{z:?}");
            assert_eq!(z.levels, 2);
            let p = fit_power_law(&shifted(&l, z.value)).unwrap();
            assert!((p.exponent - 2.0).abs() < 0.03, "offset {offset}: {p:?}");
            assert!(p.u0.abs() < 0.01, "offset {offset}: {p:?}");
            // Read as it is, the same map bends (the module doc's figures).
            let bent = fit_power_law(&l).unwrap();
            assert!(
                (bent.exponent - 2.0).abs() > 0.1,
                "offset {offset}: {bent:?}"
            );
        }
    }

    #[test]
    fn the_bends_the_module_doc_quotes_are_the_fits_through_zero() {
        // Exact levels 0, 0.2 … 0.9, 0.5, 0 of 900 gf·u² ± 30 gf, fitted through zero.
        let exact = |offset: f64| -> Vec<Level> {
            [0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.5, 0.0]
                .iter()
                .map(|&u| lv(u, 8.826 * u * u + offset))
                .collect()
        };
        for (offset, e, u0, a) in [(0.294, 4.76, -0.88, 0.88), (-0.294, 1.58, 0.16, 1.13)] {
            let (p, x) = (
                fit_power_law(&exact(offset)).unwrap(),
                super::super::fit_expo(&exact(offset)).unwrap(),
            );
            assert!((p.exponent - e).abs() < 0.01, "{offset}: {p:?}");
            assert!((p.u0 - u0).abs() < 0.01, "{offset}: {p:?}");
            assert!((x.a - a).abs() < 0.01, "{offset}: {x:?}");
        }
        let idle: Vec<Level> = [0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
            .iter()
            .map(|&u| lv(u, 0.3 + 20.0 * u * u * u))
            .collect();
        let p = fit_power_law(&idle).unwrap();
        assert!((p.exponent - 9.7).abs() < 0.05, "{p:?}");
        assert!(
            (p.uncertainty.unwrap().exponent - 9.3).abs() < 0.05,
            "{p:?}"
        );
    }

    #[test]
    fn a_reversed_cell_not_tared_is_read_the_same_way_round() {
        let l: Vec<Level> = staircase(0.294)
            .iter()
            .map(|l| Level {
                mean: -l.mean,
                ..*l
            })
            .collect();
        let z = zero_offset(&l).unwrap();
        assert!((z.value + 0.294).abs() < 1e-9, "{z:?}");
        let p = fit_power_law(&shifted(&l, z.value)).unwrap();
        assert!(p.k < 0.0 && (p.exponent - 2.0).abs() < 0.03, "{p:?}");
    }

    #[test]
    fn a_tared_cell_or_one_without_a_zero_level_keeps_the_map_through_zero() {
        assert_eq!(zero_offset(&staircase(0.0)), None);
        // 0.1 % of full thrust is 2.5 % of the lowest level, beyond the levels' own ±0.3 %
        // misfit: taken (the warning weighs its share of full thrust, not this test).
        assert!(zero_offset(&staircase(0.009)).is_some());
        // Within that misfit it is not: 0.01 % of full thrust, 0.2 % of the lowest level.
        assert_eq!(zero_offset(&staircase(0.0007)), None);
        // No level at zero command: the lowest level (0.2) is not a zero.
        let no_zero: Vec<Level> = staircase(0.294)
            .into_iter()
            .filter(|l| l.throttle > 0.0)
            .collect();
        assert_eq!(zero_offset(&no_zero), None);
        // Too few levels to test.
        assert_eq!(zero_offset(&staircase(0.294)[..4]), None);
    }

    #[test]
    fn a_five_level_staircase_shows_a_large_offset_and_not_a_real_curves_misfit() {
        // 0, 0.2, 0.4, 0.6, 0.8: one degree of freedom left, Fisher's 1 % point 4052.
        let five = |offset: f64, bend: f64| -> Vec<Level> {
            [0.0, 0.2, 0.4, 0.6, 0.8]
                .iter()
                .map(|&u| lv(u, 8.826 * u * u * (1.0 - bend * u * u) + offset))
                .collect()
        };
        let z = zero_offset(&five(0.294, 0.0)).unwrap();
        assert!((z.value - 0.294).abs() < 1e-9, "{z:?}");
        // A curve that rolls off at the top (no power law) and a small reading: not taken.
        assert_eq!(zero_offset(&five(0.02, 0.3)), None);
    }

    #[test]
    fn an_escs_idle_current_is_its_zero_reading() {
        let l: Vec<Level> = [0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
            .iter()
            .map(|&u| lv(u, 0.3 + 20.0 * u * u * u))
            .collect();
        let z = zero_offset(&l).unwrap();
        assert!((z.value - 0.3).abs() < 1e-12);
        let p = fit_power_law(&shifted(&l, z.value)).unwrap();
        assert!(
            (p.exponent - 3.0).abs() < 1e-3 && (p.k - 20.0).abs() < 0.05,
            "{p:?}"
        );
    }

    #[test]
    fn the_critical_points_are_fishers() {
        assert_eq!(f_critical_1pct(0), None);
        assert_eq!(f_critical_1pct(1), Some(4052.2));
        assert_eq!(f_critical_1pct(2), Some(98.50));
        assert_eq!(f_critical_1pct(11), Some(10.04));
        assert_eq!(f_critical_1pct(1000), Some(6.85));
    }
}
