//! A slow sensor written on every row as its last reading, repeated: the other way stand software
//! leaves a sensor's cells "not updated" (besides leaving them empty, which [`super::resample`]
//! reads as missing).
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/ingest/src/held.rs`.

/// Fewest runs of repeats for a channel to be called held.
pub const MIN_RUNS: usize = 20;
/// Share of the runs whose length must be the median's (module doc).
pub const REGULAR_SHARE: f64 = 0.8;

/// Lengths of the runs of exactly equal consecutive numbers of `values` (NaN cells skipped).
fn run_lengths(values: &[f64]) -> Vec<usize> {
    let mut runs = Vec::new();
    let mut last: Option<f64> = None;
    for &v in values.iter().filter(|v| v.is_finite()) {
        match (last, runs.last_mut()) {
            (Some(p), Some(n)) if p == v => *n += 1,
            _ => runs.push(1),
        }
        last = Some(v);
    }
    runs
}

/// The rows a held channel repeats each reading for (`L` of the module doc), or `None` when
/// `values` is not held.
pub fn held_period(values: &[f64]) -> Option<usize> {
    let runs = run_lengths(values);
    if runs.len() < MIN_RUNS {
        return None;
    }
    let mut sorted = runs.clone();
    sorted.sort_unstable();
    let l = sorted[sorted.len() / 2];
    if l < 2 {
        return None;
    }
    let lo = if l >= 3 { l - 1 } else { l };
    let regular = runs.iter().filter(|&&m| (lo..=l + 1).contains(&m)).count();
    (regular as f64 >= REGULAR_SHARE * runs.len() as f64).then_some(l)
}

/// Leaves as readings only the first cell of each run of repeats and every `period`-th cell of
/// a run longer than `period + 1`; the others become NaN. Returns the cells emptied.
pub fn unhold(values: &mut [f64], period: usize) -> usize {
    let period = period.max(1);
    let mut emptied = 0;
    let mut run_value: Option<f64> = None;
    let mut run: Vec<usize> = Vec::new();
    let mut flush = |run: &mut Vec<usize>, values: &mut [f64]| {
        let long = run.len() > period + 1;
        for (j, &i) in run.iter().enumerate() {
            let reading = j == 0 || (long && j % period == 0);
            if !reading {
                values[i] = f64::NAN;
                emptied += 1;
            }
        }
        run.clear();
    };
    for i in 0..values.len() {
        let v = values[i];
        if !v.is_finite() {
            continue;
        }
        if run_value != Some(v) {
            flush(&mut run, values);
            run_value = Some(v);
        }
        run.push(i);
    }
    flush(&mut run, values);
    emptied
}

/// Fills every empty (NaN) cell of the command `values` after its first number with the last
/// number before it (module doc); returns the cells filled.
pub fn hold_command(values: &mut [f64]) -> usize {
    let mut last: Option<f64> = None;
    let mut filled = 0;
    for v in values.iter_mut() {
        if v.is_finite() {
            last = Some(*v);
        } else if let Some(l) = last {
            *v = l;
            filled += 1;
        }
    }
    filled
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A load cell read every `l` rows (every 7th hold one row longer) of a ramp with a little
    /// deterministic noise, after `rest` rows at exactly 0.
    fn held(l: usize, rest: usize, rows: usize) -> Vec<f64> {
        let mut v = vec![0.0; rest];
        let mut k = 0;
        let mut i = 0;
        while v.len() < rows {
            let reading = 0.01 * i as f64 + 0.001 * (i as f64 * 1.3).sin();
            let len = if k % 7 == 6 { l + 1 } else { l };
            v.extend(std::iter::repeat(reading).take(len));
            k += 1;
            i += 1;
        }
        v.truncate(rows);
        v
    }

    #[test]
    fn a_sensor_written_on_every_row_is_read_at_its_own_rate() {
        let mut v = held(10, 100, 1000);
        assert_eq!(held_period(&v), Some(10));
        let before = v.clone();
        let emptied = unhold(&mut v, 10);
        // The rest: a reading every 10 rows; after it, the first row of each hold.
        let readings: Vec<usize> = (0..v.len()).filter(|&i| v[i].is_finite()).collect();
        assert_eq!(
            &readings[..11],
            &[0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100]
        );
        assert_eq!(emptied, v.len() - readings.len());
        for w in readings.windows(2).skip(10) {
            assert!((10..=11).contains(&(w[1] - w[0])), "{w:?}");
            assert_ne!(before[w[1]], before[w[1] - 1], "a reading starts a run");
        }
        for &i in &readings {
            assert_eq!(v[i], before[i], "readings keep their values");
        }
    }

    #[test]
    fn a_half_rate_sensor_alternating_two_and_three_rows_is_held() {
        let v: Vec<f64> = (0..200)
            .flat_map(|i| std::iter::repeat(i as f64).take(if i % 2 == 0 { 2 } else { 3 }))
            .collect();
        assert!(matches!(held_period(&v), Some(2 | 3)));
    }

    #[test]
    fn repeats_by_chance_in_a_coarsely_quantised_signal_are_not_a_hold() {
        // A slow random walk rounded to its noise's size: values repeat for 1, 2, 3, ... rows
        // with no clock.
        let mut x = 0.0f64;
        let mut state = 12345u64;
        let v: Vec<f64> = (0..5000)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                x += ((state >> 33) as f64 / (1u64 << 31) as f64) - 0.5;
                (x / 0.6).round()
            })
            .collect();
        let runs = run_lengths(&v);
        assert!(runs.iter().filter(|&&m| m > 1).count() > 100, "it repeats");
        assert_eq!(held_period(&v), None);
        // A signal that changes on every row, a constant, and too few runs are not held.
        let ramp: Vec<f64> = (0..500).map(|i| i as f64).collect();
        assert_eq!(held_period(&ramp), None);
        assert_eq!(held_period(&[1.0; 500]), None);
        assert_eq!(held_period(&held(10, 0, 150)), None);
    }

    #[test]
    fn a_command_written_on_its_changes_holds_until_the_next() {
        let nan = f64::NAN;
        let mut cmd = [nan, 0.2, nan, nan, 0.6, nan, 0.3, nan];
        assert_eq!(hold_command(&mut cmd), 4);
        assert!(cmd[0].is_nan(), "nothing before the first command");
        assert_eq!(&cmd[1..], &[0.2, 0.2, 0.2, 0.6, 0.6, 0.3, 0.3]);
    }

    #[test]
    fn empty_cells_are_skipped_not_counted() {
        let mut v = held(4, 0, 400);
        for i in (0..400).step_by(13) {
            v[i] = f64::NAN;
        }
        assert_eq!(held_period(&v), Some(4));
        let nan_before = v.iter().filter(|x| x.is_nan()).count();
        let emptied = unhold(&mut v, 4);
        assert_eq!(
            v.iter().filter(|x| x.is_nan()).count(),
            nan_before + emptied
        );
    }
}
