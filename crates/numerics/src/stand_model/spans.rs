//! The rows a stand fit compares: spans around the command's moves, the settled holds between
//! them left out ([`around_moves`]).
//!
//! Between two moves the command is held; once the rotor and the sensors have settled on the
//! held command, a row of the hold adds a reading of a steady level and no dynamics. The rows
//! kept are `[m − pre, m + post)` around every move `m` (a change of more than 2 % of the
//! command's range from one row to the next, as [`super::fit`] counts them), spans closer than
//! `pre + post` merged. A gap between two spans is left out only when the command holds over it
//! (within [`HOLD_TOLERANCE`] of its range): the spans are then joined end to end, and the
//! course stepped over the join continues from a rotor settled on the held command — the state
//! the left-out rows would have ended in when `post` covers the settling (`e^{−post/τ}` of the
//! step). A slow ramp (no row-to-row move) is kept whole.

/// Largest change of the command over a left-out gap, as a share of its range.
pub const HOLD_TOLERANCE: f64 = 0.005;

/// A move of the command: a change of more than this share of its range from one row to the
/// next (the stand fit's spans here, and the window `identify` reads of a long recording).
pub const MOVE_SHARE: f64 = 0.02;

/// The half-open row ranges of `u` (filled: no NaN) kept: `pre` rows before and `post` rows
/// after every move, gaps over which the command holds left out; `[(0, len)]` when nothing is
/// left out.
pub fn around_moves(u: &[f64], pre: usize, post: usize) -> Vec<(usize, usize)> {
    let len = u.len();
    let (lo, hi) = u
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let range = hi - lo;
    if len == 0 || range.is_nan() || range <= 0.0 {
        return vec![(0, len)];
    }
    let mut spans: Vec<(usize, usize)> = Vec::new();
    for k in 1..len {
        if (u[k] - u[k - 1]).abs() <= MOVE_SHARE * range {
            continue;
        }
        let (a, b) = (k.saturating_sub(pre), (k + post).min(len));
        match spans.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => spans.push((a, b)),
        }
    }
    if spans.is_empty() {
        return vec![(0, len)];
    }
    // A gap is left out only over a hold; else it joins its neighbours.
    let holds = |a: usize, b: usize| {
        let at = u[a];
        u[a..b]
            .iter()
            .all(|&v| (v - at).abs() <= HOLD_TOLERANCE * range)
    };
    let mut kept: Vec<(usize, usize)> = Vec::new();
    for s in spans {
        match kept.last_mut() {
            Some(last) if !holds(last.1.saturating_sub(1), s.0) => last.1 = s.1,
            _ => kept.push(s),
        }
    }
    // The record's start before the first span and its end after the last are left out only
    // over a hold too (the course starts settled on the first command kept).
    if let Some(first) = kept.first_mut() {
        if !holds(0, first.0 + 1) {
            first.0 = 0;
        }
    }
    if let Some(last) = kept.last_mut() {
        if !holds(last.1.saturating_sub(1), len) {
            last.1 = len;
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_between_moves_are_left_out_and_ramps_kept() {
        let mut u = vec![0.2; 1000];
        for x in u.iter_mut().skip(100).take(2) {
            *x = 0.5;
        }
        for x in u.iter_mut().skip(600) {
            *x = 0.4;
        }
        assert_eq!(around_moves(&u, 10, 50), vec![(90, 152), (590, 650)]);
        // Overlapping spans merge; the end is clipped to the record.
        assert_eq!(around_moves(&u, 10, 600), vec![(90, 1000)]);
        // A ramp between the moves is no hold: its gap is kept.
        for (k, x) in u.iter_mut().enumerate().take(600).skip(300) {
            *x = 0.2 + 0.1 * ((k - 300) as f64 / 250.0).min(1.0);
        }
        assert_eq!(around_moves(&u, 10, 50), vec![(90, 650)]);
        // A ramp at the end (no move after it) is kept to the end.
        for (k, x) in u.iter_mut().enumerate().skip(600) {
            *x = 0.4 + 0.1 * (k - 600) as f64 / 400.0;
        }
        assert_eq!(around_moves(&u, 10, 50), vec![(90, 1000)]);
        // No move at all: everything.
        assert_eq!(around_moves(&[0.3; 50], 5, 5), vec![(0, 50)]);
    }
}
