//! Sample indices for CSV rows, which carry none (docs/PROTOCOL.md §6 rows are `t_us,throttle,…`):
//! the one placer of the project, used by the daemon's CSV link (live and `replay`) and by
//! recording ingest (`identify`, through [`CsvStream`](super::csv_stream::CsvStream)), so that a
//! recording replayed and the same recording identified place every row at the same index.
//!
//! The binary SAMPLE frame counts samples (`sample_index`, +1 per sample taken), so lost
//! samples show as index jumps. A CSV row has only its time, so the index is rebuilt from the
//! time, relative to the previous row:
//!
//! ```text
//! index_0 = 0,   e_0 = t_0
//! s_k = max(0, round((t_k − e_{k-1}) / T)),   index_k = index_{k-1} + s_k
//! e_k = (e_{k-1} + s_k T) + (t_k − (e_{k-1} + s_k T)) / 16
//! ```
//!
//! with `T` the sample period and `e` the smoothed time of the last index (a first-order phase
//! tracker). A row one period after the last gets the next index; a row two periods after it
//! leaves a one-sample gap (the row in between was lost: counted and masked downstream, never
//! bridged); a row at the same time as the last repeats its index (a duplicate, dropped and
//! counted downstream). Measuring each step from the smoothed time, not from the last row's
//! time, absorbs timestamp jitter (a late row does not make the next one look early), and the
//! 1/16 correction follows a bench clock that runs off its nominal rate (0.3 % at 1 kHz: a
//! 48 µs lag) instead of drifting into false gaps.
//!
//! `T` is, in order of preference: the rate a `# HELLO … rate_hz R` line announced; else it is
//! measured on the first [`WARMUP_INTERVALS`] row intervals (rows are held until then): the
//! mean of the intervals within ±50 % of their median (the median ignores a lost or repeated row
//! among them; the mean of the single-step intervals cancels the jitter). A row with an `idx`
//! column keeps its own index.
//!
//! Time: a `t_us` column is the bench's `micros()`, a 32-bit counter that wraps every 71.6 min:
//! it is unwrapped with the same [`Unwrap32`] as recordings. A time more than
//! [`RESET_BACKWARDS_US`] before the last row means the bench restarted (index and clock start
//! again; the index going back tells the tracker a new segment starts); a smaller step back is
//! a row out of order, dropped and counted.

use super::clock::{Step, Unwrap32};

/// Row intervals whose median gives the sample period when no HELLO announced the rate.
pub const WARMUP_INTERVALS: usize = 16;

/// A time this far before the last row (µs) is a bench restart rather than a row out of order.
pub const RESET_BACKWARDS_US: i64 = 1_000_000;

/// The phase tracker's correction is 1 / this of the residual per row.
const PHASE_GAIN_INV: f64 = 16.0;

/// A row waiting for its index: its unwrapped time, its own index if it had one, its value.
#[derive(Debug, Clone, Copy)]
struct Held<T> {
    t_us: u64,
    own_index: Option<u64>,
    value: T,
}

/// A row with its place: what the placer hands on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed<T> {
    /// Sample index in the current numbering (as a device's `sample_index`, unwrapped).
    pub index: u64,
    /// The row's time, µs, unwrapped (its low 32 bits are what a device's `t_us` would be).
    pub t_us: u64,
    /// The row's value, as pushed.
    pub value: T,
}

/// What happened to a row pushed into the placer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// Placed (now or after the warm-up).
    Accepted,
    /// The time went back by less than [`RESET_BACKWARDS_US`]: dropped.
    OutOfOrder,
    /// The time went back further: the bench restarted; the row starts a new numbering.
    Restarted,
}

/// Gives CSV rows sample indices (see the module documentation). Allocation-free after `new`.
#[derive(Debug, Clone)]
pub struct RowPlacer<T> {
    period_us: Option<f64>,
    clock: Unwrap32,
    /// The last placed row: its unwrapped time, its index, the smoothed time of that index.
    last: Option<(u64, u64, f64)>,
    held: Vec<Held<T>>,
}

impl<T: Copy> Default for RowPlacer<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Copy> RowPlacer<T> {
    /// A placer with room for the warm-up rows.
    pub fn new() -> Self {
        Self {
            period_us: None,
            clock: Unwrap32::default(),
            last: None,
            held: Vec::with_capacity(WARMUP_INTERVALS + 1),
        }
    }

    /// The sample period in use, µs (`None` while still warming up).
    pub fn period_us(&self) -> Option<f64> {
        self.period_us
    }

    /// The index a sample at bench time `t_us` has (or would have) in the current numbering,
    /// by the same rule as rows; `None` before the first placed row.
    pub fn index_at(&self, t_us: u64) -> Option<u64> {
        let (_, i, e) = self.last?;
        let at = self.clock.project(t_us as u32)? as f64;
        let steps = ((at - e) / self.period_us?).round() as i64;
        Some((i as i64).saturating_add(steps).max(0) as u64)
    }

    /// The nominal rate announced by the bench (a HELLO line). Ignored once a period is in use,
    /// so every row of a numbering is placed with one period.
    pub fn announce_rate(&mut self, rate_hz: u16, emit: &mut impl FnMut(Placed<T>)) {
        if self.period_us.is_none() && rate_hz > 0 {
            self.period_us = Some(1e6 / f64::from(rate_hz));
            self.release(emit);
        }
    }

    /// A new boot announced by the bench: the numbering starts again (after the held rows).
    pub fn restart(&mut self, emit: &mut impl FnMut(Placed<T>)) {
        self.flush(emit);
        self.clock = Unwrap32::default();
        self.last = None;
        self.period_us = None;
    }

    /// Places one row: `t_us` its time (µs, as read; wrapped to 32 bits here), `own_index` an
    /// `idx` column if the row had one. Placed rows go to `emit` with their index and
    /// unwrapped time, in the order they were pushed.
    pub fn push(
        &mut self,
        t_us: u64,
        own_index: Option<u64>,
        value: T,
        emit: &mut impl FnMut(Placed<T>),
    ) -> Placement {
        let raw = t_us as u32;
        let mut placement = Placement::Accepted;
        if let Some(at) = self.clock.project(raw) {
            if at < self.clock.value() as i64 {
                if self.clock.value() as i64 - at <= RESET_BACKWARDS_US {
                    return Placement::OutOfOrder;
                }
                let period = self.period_us;
                self.restart(emit);
                self.period_us = period; // the same bench, the same rate
                placement = Placement::Restarted;
            }
        }
        match self.clock.step(raw) {
            Step::Forward(_) => {}
            Step::Backward => return Placement::OutOfOrder, // not reachable after project()
        }
        let held = Held {
            t_us: self.clock.value(),
            own_index,
            value,
        };
        if self.period_us.is_some() {
            self.place(held, emit);
        } else {
            self.held.push(held);
            if self.held.len() > WARMUP_INTERVALS {
                self.period_us = measured_period(&self.held);
                self.release(emit);
            }
        }
        placement
    }

    /// End of input: rows still held are placed with the period their intervals give.
    pub fn flush(&mut self, emit: &mut impl FnMut(Placed<T>)) {
        if self.period_us.is_none() && !self.held.is_empty() {
            self.period_us = measured_period(&self.held);
            if self.period_us.is_none() {
                // a single row: it is index 0 whatever the period
                self.period_us = Some(f64::INFINITY);
                self.release(emit);
                self.period_us = None;
                return;
            }
        }
        self.release(emit);
    }

    fn release(&mut self, emit: &mut impl FnMut(Placed<T>)) {
        for i in 0..self.held.len() {
            let h = self.held[i];
            self.place(h, emit);
        }
        self.held.clear();
    }

    fn place(&mut self, h: Held<T>, emit: &mut impl FnMut(Placed<T>)) {
        let period = self.period_us.unwrap_or(f64::INFINITY);
        let t = h.t_us as f64;
        let (index, e) = match (h.own_index, self.last) {
            (Some(i), _) => (i, t),
            (None, None) => (0, t),
            (None, Some((_, i, e))) => {
                let steps = ((t - e) / period).round().max(0.0);
                let predicted = e + steps * period;
                let e = if steps.is_finite() && predicted.is_finite() {
                    predicted + (t - predicted) / PHASE_GAIN_INV
                } else {
                    e
                };
                (i.saturating_add(steps as u64), e)
            }
        };
        self.last = Some((h.t_us, index, e));
        emit(Placed {
            index,
            t_us: h.t_us,
            value: h.value,
        });
    }
}

/// The sample period measured on the held rows, µs (see the module documentation; `None`
/// below two rows or when every interval is zero). The rows keep their order.
fn measured_period<T>(held: &[Held<T>]) -> Option<f64> {
    let mut d = [0u64; WARMUP_INTERVALS];
    let n = held.len().saturating_sub(1).min(WARMUP_INTERVALS);
    for (k, w) in held.windows(2).take(n).enumerate() {
        d[k] = w[1].t_us - w[0].t_us;
    }
    let d = &mut d[..n];
    d.sort_unstable();
    let positive: &[u64] = &d[d.iter().position(|&x| x > 0).unwrap_or(n)..];
    if positive.is_empty() {
        return None;
    }
    let m = positive.len();
    let med = if m % 2 == 1 {
        positive[m / 2] as f64
    } else {
        (positive[m / 2 - 1] + positive[m / 2]) as f64 / 2.0
    };
    let single: (f64, usize) = positive
        .iter()
        .map(|&x| x as f64)
        .filter(|&x| x > 0.5 * med && x < 1.5 * med)
        .fold((0.0, 0), |(s, n), x| (s + x, n + 1));
    Some(single.0 / single.1 as f64) // the median itself is always in range: n ≥ 1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(times: &[u64]) -> (Vec<(u32, u32)>, Vec<Placement>) {
        let mut p = RowPlacer::new();
        let mut out = Vec::new();
        let mut how = Vec::new();
        for &t in times {
            how.push(p.push(t, None, (), &mut |s| {
                out.push((s.index as u32, s.t_us as u32))
            }));
        }
        p.flush(&mut |s| out.push((s.index as u32, s.t_us as u32)));
        (out, how)
    }

    #[test]
    fn regular_rows_count_one_by_one_after_the_warm_up() {
        let times: Vec<u64> = (0..40).map(|k| 5_000 + k * 1000).collect();
        let (out, _) = run(&times);
        assert_eq!(out.len(), 40);
        for (k, &(i, t)) in out.iter().enumerate() {
            assert_eq!(i as usize, k);
            assert_eq!(t as u64, times[k]);
        }
    }

    #[test]
    fn a_lost_row_leaves_a_gap_a_repeated_row_a_duplicate_and_jitter_is_absorbed() {
        // 1 kHz with up to ±100 µs jitter (10 % of the period), row 25 lost, row 30 sent twice
        let mut times = Vec::new();
        for k in 0..40u64 {
            if k == 25 {
                continue;
            }
            let jitter = [0, 100, -80i64, 40, -100, 60][k as usize % 6];
            times.push((1_000_000 + k as i64 * 1000 + jitter) as u64);
            if k == 30 {
                times.push(*times.last().unwrap());
            }
        }
        let (out, _) = run(&times);
        let idx: Vec<u32> = out.iter().map(|o| o.0).collect();
        let mut want: Vec<u32> = (0..40).filter(|&k| k != 25).collect();
        let at = want.iter().position(|&k| k == 30).unwrap();
        want.insert(at, 30);
        assert_eq!(idx, want);
    }

    #[test]
    fn a_slow_clock_does_not_drift_into_false_gaps() {
        // the bench's clock runs 0.3 % slow against the nominal 1 kHz announced in HELLO
        let mut p = RowPlacer::new();
        let mut out = Vec::new();
        p.announce_rate(1000, &mut |s| out.push(s));
        for k in 0..5000u64 {
            p.push(k * 997, None, (), &mut |s| out.push(s));
        }
        assert!(out.iter().enumerate().all(|(k, s)| s.index as usize == k));
    }

    #[test]
    fn the_32_bit_micros_counter_wraps_without_a_gap() {
        let start = u32::MAX as u64 - 20_500;
        let times: Vec<u64> = (0..60).map(|k| (start + k * 1000) % (1 << 32)).collect();
        let (out, how) = run(&times);
        assert!(how.iter().all(|&h| h == Placement::Accepted));
        let idx: Vec<u32> = out.iter().map(|o| o.0).collect();
        assert_eq!(idx, (0..60).collect::<Vec<u32>>());
    }

    #[test]
    fn a_row_slightly_back_is_dropped_a_big_step_back_restarts() {
        let mut times: Vec<u64> = (0..30).map(|k| 10_000_000 + k * 1000).collect();
        times.push(10_000_000 + 20 * 1000); // out of order
        times.extend((0..5).map(|k| 3_000 + k * 1000)); // rebooted
        let (out, how) = run(&times);
        assert_eq!(how[30], Placement::OutOfOrder);
        assert_eq!(how[31], Placement::Restarted);
        assert!(how[32..].iter().all(|&h| h == Placement::Accepted));
        let idx: Vec<u32> = out.iter().map(|o| o.0).collect();
        let mut want: Vec<u32> = (0..30).collect();
        want.extend(0..5);
        assert_eq!(idx, want);
    }

    #[test]
    fn own_index_wins_and_short_inputs_are_placed_at_the_end() {
        let mut p = RowPlacer::new();
        let mut out = Vec::new();
        p.push(0, Some(7), (), &mut |s| out.push(s));
        p.push(2000, Some(9), (), &mut |s| out.push(s));
        assert!(out.is_empty(), "held during the warm-up");
        p.flush(&mut |s| out.push(s));
        let idx: Vec<u64> = out.iter().map(|s| s.index).collect();
        assert_eq!(idx, vec![7, 9]);
        let (one, _) = run(&[123]);
        assert_eq!(one, vec![(0, 123)]);
    }
}
