//! A clock coarser than the rows: time stamps that repeat for several rows and then step by one
//! tick (a logger that writes `hh:mm:ss` ten times a second, a spreadsheet that saved its date-
//! time column in whole seconds, a millisecond clock under a faster loop).
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/ingest/src/coarse_clock.rs`.

use serde::Serialize;

/// Share of the rows with a finite stamp that must repeat a neighbour's for the clock to be
/// read as coarser than the rows.
pub const MIN_REPEATED_SHARE: f64 = 0.5;

/// What was found and done.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CoarseClock {
    /// The clock's tick (the step between stamps), seconds.
    pub tick_s: f64,
    /// Median rows per tick (of the ticks between the first and the last).
    pub rows_per_tick: usize,
    /// Rows given a time within their tick.
    pub rows_spread: usize,
}

/// The times `t` with the rows of each tick spread over it (module documentation), and what
/// was found; `None` when the stamps do not show a coarse clock (then `t` stands as it is).
/// Non-finite stamps stay as they are.
pub fn spread(t: &[f64]) -> Option<(Vec<f64>, CoarseClock)> {
    let rows: Vec<usize> = (0..t.len()).filter(|&i| t[i].is_finite()).collect();
    // Runs of equal stamps, as (first row's position in `rows`, length).
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for (p, w) in rows.iter().enumerate() {
        match runs.last_mut() {
            Some((start, len)) if t[rows[*start]] == t[*w] => *len += 1,
            Some((start, _)) if t[*w] < t[rows[*start]] => return None, // the clock went back
            _ => runs.push((p, 1)),
        }
    }
    let repeated: usize = runs.iter().filter(|r| r.1 >= 2).map(|r| r.1).sum();
    if runs.len() < 3 || (repeated as f64) < MIN_REPEATED_SHARE * rows.len() as f64 {
        return None;
    }
    let stamp = |run: &(usize, usize)| t[rows[run.0]];
    let mut steps: Vec<f64> = runs
        .windows(2)
        .map(|w| stamp(&w[1]) - stamp(&w[0]))
        .collect();
    steps.sort_by(f64::total_cmp);
    // The tick as the stamps were written (a difference of two decimal stamps is the tick to
    // within rounding: 0.019999999999999577 for 0.02).
    let tick = format!("{:.9e}", steps[0])
        .parse::<f64>()
        .unwrap_or(steps[0]);
    let whole = |d: f64| {
        let m = (d / tick).round();
        m >= 1.0 && (d - m * tick).abs() <= 0.01 * tick
    };
    // Most ticks have rows: the median step is one tick.
    let median_is_one = (steps[steps.len() / 2] - tick).abs() <= 0.01 * tick;
    let positive = tick.is_finite() && tick > 0.0;
    if !positive || !median_is_one || !steps.iter().all(|&d| whole(d)) {
        return None;
    }
    let mut inner: Vec<usize> = runs[1..runs.len() - 1].iter().map(|r| r.1).collect();
    inner.sort_unstable();
    let typical = inner[inner.len() / 2];
    if typical < 2 {
        return None;
    }
    let mut out = t.to_vec();
    let last = runs.len() - 1;
    for (k, run) in runs.iter().enumerate() {
        let (s, n) = (stamp(run), run.1);
        // Within the record a tick's rows fill it; a first or last tick cut by the record's
        // start or end holds rows spaced as the typical tick's.
        let cut = k == 0 || k == last;
        let per = tick / if cut { n.max(typical) } else { n } as f64;
        // The first tick, cut at the record's start, ends where the next begins.
        let first = if k == 0 && k != last && n < typical {
            s + tick - n as f64 * per
        } else {
            s
        };
        for j in 0..n {
            out[rows[run.0 + j]] = first + j as f64 * per;
        }
    }
    Some((
        out,
        CoarseClock {
            tick_s: tick,
            rows_per_tick: typical,
            rows_spread: repeated,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows at `rate` Hz from `t0`, stamped by a clock of tick `tick` (floored).
    fn stamped(n: usize, rate: f64, t0: f64, tick: f64) -> (Vec<f64>, Vec<f64>) {
        let truth: Vec<f64> = (0..n).map(|k| t0 + k as f64 / rate).collect();
        let stamps = truth.iter().map(|t| (t / tick).floor() * tick).collect();
        (truth, stamps)
    }

    #[test]
    fn whole_second_stamps_at_50_hz_are_spread_over_their_seconds() {
        // Starts 0.3 s into a second: the first second holds 35 rows, the others 50.
        let (truth, stamps) = stamped(500, 50.0, 100.3, 1.0);
        let (t, c) = spread(&stamps).unwrap();
        assert_eq!((c.tick_s, c.rows_per_tick), (1.0, 50));
        for (a, b) in t.iter().zip(&truth) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
        assert!(t.windows(2).all(|w| w[1] > w[0]));
    }

    #[test]
    fn a_millisecond_clock_under_a_faster_loop_is_spread() {
        // 2.5 kHz rows on a 1 ms clock: 2 or 3 rows per stamp; spread, every spacing is
        // within half a millisecond of the true 0.4 ms.
        let (truth, stamps) = stamped(5000, 2500.0, 0.0, 1e-3);
        let (t, c) = spread(&stamps).unwrap();
        assert!((c.tick_s - 1e-3).abs() < 1e-12);
        for (a, b) in t.iter().zip(&truth) {
            assert!((a - b).abs() < 5e-4, "{a} vs {b}");
        }
    }

    #[test]
    fn stamps_that_do_not_repeat_or_go_back_are_left_alone() {
        let uniform: Vec<f64> = (0..100).map(|k| k as f64 * 0.01).collect();
        assert_eq!(spread(&uniform), None);
        // A few duplicated rows are no coarse clock.
        let mut dup = uniform.clone();
        dup[10] = dup[9];
        dup[50] = dup[49];
        assert_eq!(spread(&dup), None);
        // A second run appended: the clock goes back.
        let (_, mut stamps) = stamped(300, 50.0, 0.0, 1.0);
        let again = stamps.clone();
        stamps.extend(again);
        assert_eq!(spread(&stamps), None);
        // Stamps that step by other than whole ticks.
        let odd = [0.0, 0.0, 1.0, 1.0, 2.5, 2.5, 3.0, 3.0, 4.0, 4.0];
        assert_eq!(spread(&odd), None);
        assert_eq!(spread(&[]), None);
        assert_eq!(spread(&[f64::NAN; 5]), None);
    }

    #[test]
    fn a_tick_without_rows_stays_a_gap() {
        // Seconds 3 and 4 missing (a logging pause): the rows of second 5 still start at 5.
        let (_, stamps) = stamped(500, 50.0, 0.0, 1.0);
        let kept: Vec<f64> = stamps
            .into_iter()
            .filter(|&s| s != 3.0 && s != 4.0)
            .collect();
        let (t, _) = spread(&kept).unwrap();
        let first_of_5 = t.iter().position(|&x| x >= 5.0).unwrap();
        assert!((t[first_of_5] - 5.0).abs() < 1e-12);
        assert!((t[first_of_5 - 1] - (2.0 + 49.0 / 50.0)).abs() < 1e-12);
    }
}
