//! The rules each caller had before, kept here as oracles: on the commands they were written
//! for, the one rule answers the same.

use proptest::prelude::*;

use super::*;

/// `pulses.rs` before: scan, `try_pulse`, `run_end`, `run_start` (1e-9, missing mask).
fn old_pulses(u: &[f64], missing: &[bool], max_width: usize) -> Vec<(usize, usize, f64, usize)> {
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9;
    let miss = |k: usize| missing.get(k).copied().unwrap_or(false);
    let level_at = |k: usize| (0..=k).rev().find(|&j| !miss(j)).map_or(f64::NAN, |j| u[j]);
    let run_end = |from: usize| {
        let lv = level_at(from);
        let mut k = from + 1;
        while k < u.len() && (miss(k) || same(u[k], lv)) {
            k += 1;
        }
        k
    };
    let run_start = |at: usize| {
        let lv = level_at(at);
        let mut k = at;
        while k > 0 && (miss(k - 1) || same(u[k - 1], lv)) {
            k -= 1;
        }
        k
    };
    let try_pulse = |s: usize| {
        let n = u.len();
        if s == 0 || s >= n {
            return None;
        }
        let (l0, lp) = (level_at(s - 1), level_at(s));
        if !l0.is_finite() || same(l0, lp) {
            return None;
        }
        let e1 = run_end(s);
        let width = e1 - s;
        if width > max_width || e1 >= n || !same(level_at(e1), l0) {
            return None;
        }
        Some((s, width, lp - l0, run_start(s - 1)))
    };
    let mut out = Vec::new();
    let mut k = 1;
    while k < u.len() {
        if !miss(k) && !same(u[k], level_at(k - 1)) {
            if let Some(p) = try_pulse(k) {
                out.push(p);
                k = p.0 + p.1 + 1;
                continue;
            }
        }
        k += 1;
    }
    out
}

/// `operating_points.rs::staircase` before: `(own, to, level)` per level.
fn old_staircase(u: &[f64], max_pulse: usize) -> Vec<(usize, usize, f64)> {
    let mut runs: Vec<(usize, usize, f64)> = Vec::new();
    let mut start = 0;
    for k in 1..=u.len() {
        let end = k == u.len() || (u[k] - u[start]).abs() > 1e-9 && u[k].is_finite();
        if end {
            if k - start > max_pulse {
                match runs.last_mut() {
                    Some(last) if (last.2 - u[start]).abs() <= 1e-9 => last.1 = k,
                    _ => runs.push((start, k, u[start])),
                }
            } else if let Some(last) = runs.last_mut() {
                last.1 = k;
            }
            start = k;
        }
    }
    runs
}

/// `okid/select.rs::is_ramped_staircase` before.
fn old_is_ramped_staircase(u: &[f64], max_pulse_width: usize) -> bool {
    let mut flat = 0;
    let mut start = 0;
    for k in 1..=u.len() {
        if k == u.len() || !(u[k] - u[start]).abs().le(&1e-9) {
            if k - start > max_pulse_width {
                flat += k - start;
            }
            start = k;
        }
    }
    flat * 2 >= u.len() && !u.is_empty()
}

/// `okid/select.rs::is_piecewise_constant` before.
fn old_is_piecewise_constant(u: &[f64]) -> bool {
    let changes = u
        .windows(2)
        .filter(|w| w[0].is_finite() && w[1].is_finite() && (w[1] - w[0]).abs() > 1e-9)
        .count();
    changes * 2 <= u.len()
}

/// `diagnose/report.rs::find_pulses` before (any excursion back to the level within 32).
fn old_find_pulses(u: &[f64]) -> Vec<(usize, f64)> {
    let mut out = Vec::new();
    let mut k = 1;
    while k < u.len() {
        let level = u[k - 1];
        let a = u[k] - level;
        if a.abs() > 1e-9 {
            let back = (k + 1..(k + 33).min(u.len())).find(|&j| (u[j] - level).abs() < 1e-9);
            if let Some(j) = back {
                out.push((k, a));
                k = j;
                continue;
            }
        }
        k += 1;
    }
    out
}

/// `daemon/csv_link/pulse_flags.rs` before, on raw throttle (1e-4): the flags it set.
fn old_flags(t: &[u16], tol_raw: u16, cap: usize) -> Vec<bool> {
    let (mut level, mut open, mut out): (Option<u16>, Vec<u16>, Vec<bool>) =
        (None, Vec::new(), Vec::new());
    let mut k = 0;
    while k < t.len() {
        let s = t[k];
        let Some(l) = level else {
            level = Some(s);
            out.push(false);
            k += 1;
            continue;
        };
        if s.abs_diff(l) <= tol_raw {
            out.extend(open.drain(..).map(|_| true));
            level = Some(s);
            out.push(false);
        } else if open.len() == cap {
            level = open.last().copied();
            out.extend(open.drain(..).map(|_| false));
            continue; // the same sample again, against the new level
        } else {
            open.push(s);
        }
        k += 1;
    }
    out.extend(open.drain(..).map(|_| false));
    out
}

/// A stand's experiment: levels held longer than the widest pulse, flat pulses returning to
/// them, steps between levels (raw throttle, 1e-4).
fn stand_plan(w: usize) -> impl Strategy<Value = Vec<u16>> {
    let pulse = (1..=w, -3i32..=3).prop_filter("a pulse moves", |p| p.1 != 0);
    prop::collection::vec((0u16..4, 1..3 * w, prop::option::of(pulse)), 1..16).prop_map(
        move |parts| {
            let mut t = Vec::new();
            let mut level = 3000;
            for (i, &(l, hold, p)) in parts.iter().enumerate() {
                let next = 3000 + 500 * l;
                if i > 0 && next != level {
                    level = next;
                    t.extend(std::iter::repeat_n(level, w + 1)); // a step: held past the limit
                }
                t.extend(std::iter::repeat_n(level, hold));
                if let Some((width, a)) = p {
                    t.extend(std::iter::repeat_n((level as i32 + 100 * a) as u16, width));
                    t.push(level);
                }
            }
            t
        },
    )
}

proptest! {
    #[test]
    fn pulses_are_those_of_the_old_pulse_path(u in grid_runs(40), w in 1usize..40, holes in prop::collection::vec(0usize..1000, 0..6)) {
        let mut missing = vec![false; u.len()];
        let mut v = u.clone();
        for h in holes {
            let n = u.len();
            missing[h % n] = true;
            v[h % n] = f64::NAN;
        }
        let rules = SegmentRules { max_pulse_samples: w, ..R };
        let new: Vec<_> = pulses(Command::with_missing(&u, &missing), &rules)
            .map(|p| (p.start, p.width, p.amplitude, p.before_start))
            .collect();
        prop_assert_eq!(&new, &old_pulses(&u, &missing, w));
        let nan: Vec<_> = pulses(Command::new(&v), &rules)
            .map(|p| (p.start, p.width, p.amplitude, p.before_start))
            .collect();
        prop_assert_eq!(new, nan);
    }

    #[test]
    fn levels_and_kinds_are_those_of_the_old_callers(u in grid_runs(80), w in 1usize..40) {
        let rules = SegmentRules { max_pulse_samples: w, ..R };
        let cmd = Command::new(&u);
        let new: Vec<_> = levels(cmd, &rules).iter().map(|l| (l.start, l.end, l.value)).collect();
        prop_assert_eq!(new, old_staircase(&u, w));
        prop_assert_eq!(is_ramped_staircase(cmd, &rules), old_is_ramped_staircase(&u, w));
        prop_assert_eq!(is_piecewise_constant(cmd, &rules), old_is_piecewise_constant(&u));
    }

    #[test]
    fn the_report_finds_the_flat_pulses_it_found_before(u in grid_runs(40)) {
        // the old report rule also took non-flat excursions (and the return of one pulse as
        // the start of another); every flat pulse it found is still found, with its amplitude
        let new: Vec<PulseRun> = pulses(Command::new(&u), &R).collect();
        for (s, a) in old_find_pulses(&u) {
            let back = (s + 1..u.len()).find(|&j| (u[j] - u[s - 1]).abs() < 1e-9).unwrap();
            let flat = u[s..back].iter().all(|v| (v - u[s]).abs() <= 1e-9);
            let a_return = new.iter().any(|p| p.start + p.width == s);
            if flat && !a_return {
                prop_assert!(new.iter().any(|p| p.start == s && close(p.amplitude, a)), "{} {:?}", s, new);
            }
        }
    }

    #[test]
    fn the_csv_link_flags_a_stand_plan_as_before(t in stand_plan(8), tol in 0u16..60) {
        let rules = SegmentRules { level_tolerance: f64::from(tol), max_pulse_samples: 8, ..R };
        let u: Vec<f64> = t.iter().map(|&v| f64::from(v)).collect();
        let (marks, _) = stream_marks(&u, &rules);
        prop_assert_eq!(marks, old_flags(&t, tol, 8));
    }
}
