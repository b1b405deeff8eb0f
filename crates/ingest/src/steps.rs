//! Steps found from the response alone, for records whose command was not logged.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/ingest/src/steps.rs`.

use propid_numerics::outliers::MAD_TO_SD;
use propid_numerics::segment::{ResponseStepRules, SegmentRules};
use serde::Serialize;

/// One step found in a response.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FoundStep {
    /// Sample at which the command is taken to change (one before the response moves).
    pub sample: usize,
    /// Level before the step, output units.
    pub from: f64,
    /// Level after the step, output units.
    pub to: f64,
}

/// The steps of a response and the input built from them.
#[derive(Debug, Clone, PartialEq)]
pub struct StepFinding {
    /// The steps, in order.
    pub steps: Vec<FoundStep>,
    /// Synthetic input: the level sequence (see the module docs).
    pub input: Vec<f64>,
    /// Noise estimate `σ`, output units.
    pub noise: f64,
    /// Detection threshold used, output units.
    pub threshold: f64,
}

/// Finds the steps of `y` under [`SegmentRules::DEFAULT`] (see [`find_steps_with`]).
pub fn find_steps(y: &[f64]) -> Option<StepFinding> {
    find_steps_with(y, &SegmentRules::DEFAULT.response)
}

/// Finds the steps of `y` (missing samples are NaN and are bridged by the running median).
/// Returns `None` when `y` has fewer than `2·settle_samples` finite samples.
pub fn find_steps_with(y: &[f64], rules: &ResponseStepRules) -> Option<StepFinding> {
    let settle = Settle {
        samples: rules.settle_samples.max(1),
        fraction: rules.settle_fraction,
    };
    if y.iter().filter(|v| v.is_finite()).count() < 2 * settle.samples {
        return None;
    }
    let m = rules.smooth_samples.max(1);
    let s = moving_mean(&running_median(y, rules.median_samples), m);
    let mut diffs: Vec<f64> = s
        .windows(2 * m + 1)
        .map(|w| (w[2 * m] - 2.0 * w[m] + w[0]).abs() / 6f64.sqrt())
        .filter(|d| d.is_finite())
        .collect();
    let noise = MAD_TO_SD * quantile(&mut diffs, 0.5);
    let mut finite: Vec<f64> = s.iter().copied().filter(|v| v.is_finite()).collect();
    let range = quantile(&mut finite, 0.99) - quantile(&mut finite, 0.01);
    let thr = (rules.noise_sigmas * noise).max(rules.range_fraction * range);
    let mut steps = Vec::new();
    let Some((mut start, mut level)) = settle.from(&s, 0, thr) else {
        return Some(finish(y.len(), steps, noise, thr, s[0]));
    };
    let initial = level;
    let back = (rules.onset_sigmas * noise).max(rules.onset_fraction * thr);
    let mut k = start + settle.samples;
    while k < s.len() {
        if !(s[k].is_finite() && (s[k] - level).abs() > thr) {
            k += 1;
            continue;
        }
        let mut onset = k;
        while onset > start + 1 && s[onset - 1].is_finite() && (s[onset - 1] - level).abs() > back {
            onset -= 1;
        }
        let Some((next, new_level)) = settle.from(&s, k, thr) else {
            break;
        };
        let moved = (onset + m / 2 - 1).min(s.len() - 1);
        steps.push(FoundStep {
            sample: moved.saturating_sub(1).max(start),
            from: level,
            to: new_level,
        });
        (start, level) = (next, new_level);
        k = next + settle.samples;
    }
    Some(finish(y.len(), steps, noise, thr, initial))
}

fn finish(
    n: usize,
    steps: Vec<FoundStep>,
    noise: f64,
    threshold: f64,
    initial: f64,
) -> StepFinding {
    let mut input = vec![initial; n];
    for st in &steps {
        for v in &mut input[st.sample..] {
            *v = st.to;
        }
    }
    StepFinding {
        steps,
        input,
        noise,
        threshold,
    }
}

/// When a response has settled: `samples` in a row within `fraction·thr`.
struct Settle {
    samples: usize,
    fraction: f64,
}

impl Settle {
    /// First index `i ≥ from` where `s[i .. i+samples]` is finite with range below
    /// `fraction·thr`, and the median level there.
    fn from(&self, s: &[f64], from: usize, thr: f64) -> Option<(usize, f64)> {
        (from..s.len().saturating_sub(self.samples - 1)).find_map(|i| {
            let w = &s[i..i + self.samples];
            if w.iter().any(|v| !v.is_finite()) {
                return None;
            }
            let lo = w.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (hi - lo < self.fraction * thr).then(|| (i, quantile(&mut w.to_vec(), 0.5)))
        })
    }
}

/// Centred running median over `w` samples (NaNs left out; NaN when the window has none).
fn running_median(y: &[f64], w: usize) -> Vec<f64> {
    let h = w / 2;
    (0..y.len())
        .map(|k| {
            let lo = k.saturating_sub(h);
            let hi = (k + h + 1).min(y.len());
            let mut win: Vec<f64> = y[lo..hi]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            if win.is_empty() {
                f64::NAN
            } else {
                quantile(&mut win, 0.5)
            }
        })
        .collect()
}

/// Centred moving mean over `w` samples (window `k − w/2 ..= k + w/2 − 1`, clipped at the ends;
/// NaNs left out; NaN when the window has none).
fn moving_mean(y: &[f64], w: usize) -> Vec<f64> {
    (0..y.len())
        .map(|k| {
            let lo = k.saturating_sub(w / 2);
            let hi = (k + w / 2).min(y.len());
            let (sum, cnt) = y[lo..hi]
                .iter()
                .filter(|v| v.is_finite())
                .fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
            if cnt == 0 {
                f64::NAN
            } else {
                sum / cnt as f64
            }
        })
        .collect()
}

/// Nearest-rank quantile; sorts in place; 0 for an empty slice.
fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// First-order response (pole `a`) to the levels given at the given samples, with an
    /// alternating ripple of amplitude `ripple`.
    fn response(n: usize, edges: &[(usize, f64)], a: f64, ripple: f64) -> Vec<f64> {
        let mut u = vec![0.0; n];
        for &(at, lvl) in edges {
            for v in &mut u[at..] {
                *v = lvl;
            }
        }
        let mut x = u[0];
        (0..n)
            .map(|k| {
                let yk = x + ripple * if k % 2 == 0 { 1.0 } else { -1.0 };
                x = a * x + (1.0 - a) * u[k];
                yk
            })
            .collect()
    }

    #[test]
    fn finds_up_and_down_steps_with_ripple() {
        let y = response(400, &[(100, 4.0), (250, 0.0)], 0.6, 0.1);
        let f = find_steps(&y).unwrap();
        assert_eq!(f.steps.len(), 2, "{:?}", f.steps);
        assert!((99..=101).contains(&f.steps[0].sample), "{:?}", f.steps);
        assert!((249..=251).contains(&f.steps[1].sample), "{:?}", f.steps);
        assert!((f.steps[0].to - 4.0).abs() < 0.15);
        assert!(f.steps[1].to.abs() < 0.15);
        assert!((f.input[200] - f.steps[0].to).abs() < 1e-12);
    }

    #[test]
    fn staircase_gives_one_step_per_level() {
        let edges: Vec<(usize, f64)> = (1..6).map(|i| (60 * i, i as f64)).collect();
        let f = find_steps(&response(400, &edges, 0.5, 0.0)).unwrap();
        assert_eq!(f.steps.len(), 5);
        for (st, e) in f.steps.iter().zip(&edges) {
            assert_eq!(st.sample, e.0);
        }
    }

    #[test]
    fn flat_or_short_record_has_no_steps() {
        assert!(find_steps(&[1.0; 5]).is_none());
        let f = find_steps(&vec![1.0; 100]).unwrap();
        assert!(f.steps.is_empty());
    }

    #[test]
    fn a_ramp_that_never_settles_gives_no_step_after_it_starts() {
        let y: Vec<f64> = (0..200)
            .map(|k| if k < 50 { 0.0 } else { (k - 50) as f64 })
            .collect();
        let f = find_steps(&y).unwrap();
        assert!(f.steps.is_empty(), "{:?}", f.steps);
    }
}
