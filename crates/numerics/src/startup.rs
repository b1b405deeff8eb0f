//! A start-up transient: the first samples of a record, taken while the output still settles
//! under the first command level for a reason the command does not show (the motor spinning up
//! from rest or under an ESC's soft start, a load cell's tare settling), found so that they can
//! be left out (marked missing, never corrected) and said.
//!
//! Left in, such a decaying offset under the first pulses or the first step is fitted as if the
//! command had caused it: measured on a 12 Hz, ζ 0.7, 12 N/throttle plant at 1 kHz with pulses
//! from 0.2 s, a soft start reaching 80 % of the level at once and the rest with τ = 0.5 s gave a
//! DC gain 12 % low, a 1 N tare offset decaying with τ = 0.5 s a DC gain 11 % low, both with
//! exit 0; larger ones gave unstable poles or gains of either sign.
//!
//! # The rule (block medians of the first command level)
//!
//! The first level is the record's start up to the end of the first level of the command
//! ([`crate::segment::levels`]: pulses and short runs belong to it); it is judged only when the
//! record starts at it (within [`SegmentRules::max_pulse_samples`]): a record that starts with
//! a ramp or a step into its first level (the simulated stand's: idle, then a 0.5 s ramp) shows
//! the output following the command, which the model explains. It is cut into
//! [`BLOCKS`] blocks of `B = max(MIN_BLOCK, ⌊n/BLOCKS⌋)` samples; each block's output is summarised
//! by its median `m_j` (missing samples skipped; a block with fewer than half its samples
//! measured has none; the first block with a median stands for the start). Pulse responses and noise move the medians little; a settled output holds
//! them at one value. The **settled level** is `m̄ = median m_j` over the second half of the
//! blocks, its scatter `σ_m = 1.4826 · MAD` of those medians (floored at the channel's
//! resolution, the smallest non-zero step between neighbours: a quantised channel whose medians
//! all agree still has a scale). The first samples are a **start-up transient** when
//!
//! 1. the first block stands out: `|m_0 − m̄| > TRANSIENT_SIGMAS · σ_m` ([`TRANSIENT_SIGMAS`] = 8;
//!    a linear drift across the level reaches ≈ 4 by this measure and never passes), and
//! 2. it has settled by the middle of the level: from some block `j ≤ BLOCKS/2` on, every block
//!    of the first half is within `TRANSIENT_SIGMAS · σ_m` of `m̄`. The transient is the samples
//!    before block `j + 1` (one block of margin). An output that has not settled by then is not
//!    a start-up transient (a drift, or a level that is not a level): nothing is found.
//!
//! A level of fewer than `BLOCKS · MIN_BLOCK` samples (128) is not judged (too few blocks to
//! tell a settled level), nor a record without a command level. Blocks of [`MIN_BLOCK`] = 4
//! samples reach the first level of a staircase (1–6 s at 100 Hz), where a log started with the
//! throttle shows the motor spinning up from rest under it: measured on a first-order stand
//! (τ 80 ms) with a 200-sample first level, the diagnosis fitted 96 % and named no delay with
//! the spin-up in, 99.96 % and the delay without it. A long level's blocks are `n / 32` samples
//! as before.

use crate::outliers::{median, resolution, MAD_TO_SD};
use crate::segment::{levels, Command, SegmentRules};

/// Blocks the first level is cut into.
pub const BLOCKS: usize = 32;
/// Fewest samples in a block.
pub const MIN_BLOCK: usize = 4;
/// A first block farther than this many scatters from the settled level is a transient.
pub const TRANSIENT_SIGMAS: f64 = 8.0;

/// A start-up transient found ([`start_transient`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartTransient {
    /// Samples `0..end` are the transient.
    pub end: usize,
    /// The first block's median minus the settled level (output units).
    pub offset: f64,
}

/// The start-up transient of output `y` under command `u` (see the module doc), if any.
/// `missing` (empty: none) marks samples not measured; NaN outputs are missing too.
pub fn start_transient(
    y: &[f64],
    missing: &[bool],
    u: &[f64],
    rules: &SegmentRules,
) -> Option<StartTransient> {
    let cmd = Command::with_missing(u, missing);
    let first = levels(cmd, rules).into_iter().next()?;
    // the record must start at the level: before a ramp or a step into it the output follows
    // the command, which the model explains
    if first.start > rules.max_pulse_samples {
        return None;
    }
    let n = first.end.min(y.len());
    let block = MIN_BLOCK.max(n / BLOCKS);
    let blocks = n / block;
    if blocks < BLOCKS {
        return None;
    }
    let measured = |k: usize| y[k].is_finite() && !missing.get(k).copied().unwrap_or(false);
    let mut buf = Vec::with_capacity(block);
    let medians: Vec<f64> = (0..blocks)
        .map(|j| {
            buf.clear();
            buf.extend(
                (j * block..(j + 1) * block)
                    .filter(|&k| measured(k))
                    .map(|k| y[k]),
            );
            if 2 * buf.len() < block {
                f64::NAN
            } else {
                median(&mut buf)
            }
        })
        .collect();
    let half = blocks / 2;
    let mut settled: Vec<f64> = medians[half..]
        .iter()
        .copied()
        .filter(|m| m.is_finite())
        .collect();
    if settled.len() < BLOCKS / 4 {
        return None;
    }
    let level = median(&mut settled);
    let mut dev: Vec<f64> = settled.iter().map(|m| (m - level).abs()).collect();
    let scatter = (MAD_TO_SD * median(&mut dev)).max(resolution(&y[..n]));
    if !(scatter.is_finite() && scatter > 0.0) {
        return None;
    }
    let far = |m: f64| m.is_finite() && (m - level).abs() > TRANSIENT_SIGMAS * scatter;
    // the first block with a median (the record may start with missing samples)
    let m0 = medians.iter().copied().find(|m| m.is_finite())?;
    if !far(m0) {
        return None;
    }
    // the last block of the first half still far from the level; past the half: not settled
    let last_far = (0..=half).rev().find(|&j| far(medians[j]))?;
    if last_far >= half {
        return None;
    }
    Some(StartTransient {
        end: (last_far + 2) * block,
        offset: m0 - level,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_testkit::{add_noise, throttle, Plant};

    /// 4 s at 1 kHz of the plant (fn 12 Hz, ζ 0.7, 12 N/throttle) held at 0.45 with
    /// one-sample pulses every 250 samples from 0.2 s, 0.01 N noise, plus `offset(t)`.
    fn record(offset: impl Fn(f64) -> f64) -> (Vec<f64>, Vec<f64>) {
        let n = 4000;
        let pulses: Vec<_> = (0..15)
            .map(|i| (200 + 250 * i, 1, if i % 2 == 0 { 0.1 } else { -0.05 }))
            .collect();
        let u = throttle(n, &[(0, 0.45)], &pulses);
        let mut y = Plant::new(12.0, 0.7, 12.0, 0.001)
            .simulate(&u, 0.0)
            .remove(0);
        for (k, v) in y.iter_mut().enumerate() {
            *v += offset(k as f64 * 0.001);
        }
        add_noise(&mut y, 0.01, 4);
        (u, y)
    }

    fn find(y: &[f64], u: &[f64]) -> Option<StartTransient> {
        start_transient(y, &[], u, &SegmentRules::DEFAULT)
    }

    #[test]
    fn a_settled_record_has_none() {
        let (u, y) = record(|_| 0.0);
        assert_eq!(find(&y, &u), None);
        // nor a slow linear drift across the level (a battery sagging: 0.2 N over 4 s)
        let (u, y) = record(|t| -0.05 * t);
        assert_eq!(find(&y, &u), None);
    }

    #[test]
    fn a_decaying_offset_at_the_start_is_found_until_it_has_settled() {
        for (a, tau) in [(1.0, 0.5), (-1.0, 0.5), (0.3, 0.3), (-0.3, 0.3), (5.4, 0.1)] {
            let (u, y) = record(|t| a * (-t / tau).exp());
            let f = find(&y, &u).unwrap_or_else(|| panic!("{a} N, tau {tau}"));
            assert_eq!(f.offset.signum(), a.signum(), "{a} {tau}");
            // left out until what remains is within the scatter of the settled blocks' medians
            // (the pulse responses': 0.05 N here, 1 % of the level)
            let remains = a.abs() * (-(f.end as f64) * 0.001 / tau).exp();
            assert!(remains < 0.06, "{a} N, tau {tau}: {f:?} leaves {remains}");
            assert!(f.end <= 2000, "{a} N, tau {tau}: {f:?}");
        }
    }

    #[test]
    fn an_output_that_never_settles_or_a_short_level_is_not_judged() {
        // still decaying at the end of the level: not a start-up transient
        let (u, y) = record(|t| 2.0 * (-t / 3.0).exp());
        assert_eq!(find(&y, &u), None);
        // a level of 120 samples (fewer than 32 blocks of 4) before a step
        let (mut u, y) = record(|t| (-t / 0.02).exp());
        u[120..].iter_mut().for_each(|v| *v += 0.1);
        assert_eq!(find(&y, &u), None);
        // no command level at all
        assert_eq!(find(&y, &[]), None);
        // the record starts with the command's ramp from idle to its first level (the
        // simulated stand's plan: 30 samples at 0, 0.5 s ramp): the output follows the command
        let mut u: Vec<f64> = (0..4000)
            .map(|k: usize| (k.saturating_sub(30) as f64 / 500.0).min(1.0) * 0.3)
            .collect();
        u[2000] += 0.1;
        let mut y = Plant::new(12.0, 0.7, 12.0, 0.001)
            .simulate(&u, 0.0)
            .remove(0);
        add_noise(&mut y, 0.01, 8);
        assert_eq!(find(&y, &u), None);
    }

    #[test]
    fn a_quantised_idle_channel_and_missing_samples() {
        // a load cell at idle reading 0 with one-count flicker, then a tare step of 3 counts
        // settling: found; without it: none
        let mut y = vec![0.0; 2000];
        for k in (0..2000).step_by(13) {
            y[k] = 0.01;
        }
        let u = vec![0.0; 2000];
        assert_eq!(find(&y, &u), None);
        let mut t = y.clone();
        t[..120].iter_mut().for_each(|v| *v += 0.1);
        let f = find(&t, &u).unwrap();
        assert!((120..=250).contains(&f.end), "{f:?}");
        // the first block missing (NaN, marked): judged from the first block with a median
        let mut missing = vec![false; 2000];
        missing[..62].iter_mut().for_each(|m| *m = true);
        t[..62].iter_mut().for_each(|v| *v = f64::NAN);
        let g = start_transient(&t, &missing, &u, &SegmentRules::DEFAULT).unwrap();
        assert_eq!(g.end, f.end);
    }

    /// A staircase logged from the instant its first level was commanded (2 s at 100 Hz): the
    /// thrust spins up from rest under the first level (τ = 80 ms) while the command shows no
    /// step. Found on the short level, and left out until it has settled; the same staircase
    /// started settled has none.
    #[test]
    fn a_spin_up_under_a_short_first_level_is_found() {
        let levels = [0.2, 0.4, 0.6, 0.3];
        let u: Vec<f64> = levels
            .iter()
            .flat_map(|&l| std::iter::repeat(l).take(200))
            .collect();
        let a = (-0.01f64 / 0.08).exp();
        let run = |x0: f64| {
            let mut x = x0;
            let mut y: Vec<f64> = u
                .iter()
                .map(|&uk| {
                    x = a * x + (1.0 - a) * 10.0 * uk;
                    x
                })
                .collect();
            add_noise(&mut y, 0.01, 5);
            y
        };
        let f = find(&run(0.0), &u).expect("a spin-up from rest");
        assert!(f.offset < -1.0, "{f:?}");
        let remains = 2.0 * a.powi(f.end as i32);
        assert!(remains < 0.05 && f.end <= 100, "{f:?} leaves {remains}");
        assert_eq!(find(&run(2.0), &u), None);
    }
}
