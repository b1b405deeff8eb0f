//! Choosing the number `ℓ` of observer Markov parameters of OKID ([`crate::okid`]) by output
//! (simulation) error: the order of OKID's regression, not the model order ([`super`]).
//!
//! The one-step residual of the observer regression keeps falling as `ℓ` grows (a longer ARX
//! whitens output noise better), so a criterion on it (AIC, BIC) picks large `ℓ` on noisy data.
//! With an input that excites few directions (a staircase has four steps) the extra
//! parameters are then fitted to noise and the recovered Markov parameters are poor, while the
//! one-step fit looks fine. What matters for the Markov parameters is how well they *simulate*
//! the record: for each candidate `ℓ` the fitted observer model is run in simulation (its own
//! past outputs fed back instead of the measured ones), which is the convolution of the input
//! with the complete recovered Markov sequence,
//!
//! ```text
//! d_k = Σ_{i=1..ℓ} M_i^y d_{k−i} + Σ_{i=0..ℓ} M_i^u (u_{k−i} − u_0),   d_{<0} = 0, u_{<0} = u_0
//! ŷ_k = c + d_k                                 (at rest before the record; offset c fitted)
//! ```
//!
//! and scored by `Σ_outputs ‖y − ŷ‖² / var(y)`. Noise is not predictable by simulation, so this
//! score does not reward fitting it; an unstable fit diverges and is never chosen. The smallest
//! `ℓ` whose score is within `observer_tie` ([`THRESHOLDS`]) of the best wins (noise-free
//! data: the deadbeat order `⌈n/q⌉`, where the score drops to rounding). Cost
//! `O(N ℓ q (p+q))` per candidate.

use super::THRESHOLDS;

/// The candidates (`observer_candidates` of [`THRESHOLDS`]) below `ell_max`, then `ell_max`
/// itself.
pub fn candidates(ell_max: usize) -> Vec<usize> {
    let mut c: Vec<usize> = THRESHOLDS
        .observer_candidates
        .iter()
        .copied()
        .filter(|&l| l < ell_max)
        .collect();
    c.push(ell_max);
    c
}

/// Output-error score of the observer model `(mu, my)` (blocks `M_i^u`, `q × p`, `i = 0..ℓ`
/// and `M_i^y`, `q × q`, `i = 1..ℓ`, column-major, as [`crate::okid`] packs them). Missing
/// inputs hold their last value; missing outputs are not scored; a diverging simulation scores
/// NaN.
pub fn output_error(
    (mu, my): (&[f64], &[f64]),
    (p, q, ell): (usize, usize, usize),
    u: &[&[f64]],
    y: &[&[f64]],
) -> f64 {
    let n = u[0].len();
    let held: Vec<Vec<f64>> = u.iter().map(|c| hold(c)).collect();
    let mut d = vec![0.0; n * q];
    for k in 0..n {
        for r in 0..q {
            let mut acc = 0.0;
            for i in 0..=ell.min(k) {
                for (j, uj) in held.iter().enumerate() {
                    acc += mu[i * q * p + r + j * q] * (uj[k - i] - uj[0]);
                }
                if i > 0 {
                    for c in 0..q {
                        acc += my[i * q * q + r + c * q] * d[(k - i) * q + c];
                    }
                }
            }
            d[k * q + r] = acc;
        }
        if !d[k * q..(k + 1) * q]
            .iter()
            .all(|v| v.is_finite() && v.abs() < 1e150)
        {
            return f64::NAN;
        }
    }
    let mut total = 0.0;
    for (i, yi) in y.iter().enumerate() {
        let pairs = || {
            (0..n)
                .filter(|&k| yi[k].is_finite())
                .map(|k| (yi[k], d[k * q + i]))
        };
        let cnt = pairs().count().max(1) as f64;
        let off = pairs().map(|(a, s)| a - s).sum::<f64>() / cnt;
        let mean = pairs().map(|(a, _)| a).sum::<f64>() / cnt;
        let var = pairs().map(|(a, _)| (a - mean).powi(2)).sum::<f64>() / cnt;
        let err = pairs().map(|(a, s)| (a - s - off).powi(2)).sum::<f64>() / cnt;
        total += err / var.max(f64::MIN_POSITIVE);
    }
    total
}

/// The smallest candidate within `observer_tie` ([`THRESHOLDS`]) of the best score (NaN scores
/// never win).
pub fn pick(scores: &[(usize, f64)]) -> Option<usize> {
    let best = scores
        .iter()
        .map(|s| s.1)
        .filter(|v| v.is_finite())
        .fold(f64::INFINITY, f64::min);
    scores
        .iter()
        .find(|s| s.1.is_finite() && s.1 <= best * (1.0 + THRESHOLDS.observer_tie) + 1e-24)
        .map(|s| s.0)
}

/// The channel with NaNs replaced by the last finite value (the first finite one at the start).
fn hold(c: &[f64]) -> Vec<f64> {
    let mut last = c.iter().copied().find(|v| v.is_finite()).unwrap_or(0.0);
    c.iter()
        .map(|&v| {
            if v.is_finite() {
                last = v;
            }
            last
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_end_at_the_maximum() {
        assert_eq!(candidates(1), vec![1]);
        assert_eq!(candidates(7), vec![1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(*candidates(40).last().unwrap(), 40);
    }

    #[test]
    fn pick_prefers_the_smallest_near_tie() {
        assert_eq!(pick(&[(1, 0.5), (2, 0.101), (4, 0.1), (8, 0.1)]), Some(2));
        assert_eq!(pick(&[(1, f64::NAN), (2, 1.0)]), Some(2));
        assert_eq!(pick(&[(1, 0.0), (2, 0.0)]), Some(1));
    }

    #[test]
    fn exact_model_simulates_a_step_exactly() {
        // y_k = 0.5 y_{k-1} + 0.5 u_{k-1}: a unit step at 10 gives 1 - 0.5^(k-10) from k = 11.
        let (mu, my) = (vec![0.0, 0.5], vec![0.0, 0.5]);
        let u: Vec<f64> = (0..60).map(|k| if k < 10 { 0.0 } else { 1.0 }).collect();
        let y: Vec<f64> = (0..60)
            .map(|k| {
                if k < 11 {
                    0.0
                } else {
                    1.0 - 0.5f64.powi(k - 10)
                }
            })
            .collect();
        let s = output_error((&mu, &my), (1, 1, 1), &[&u], &[&y]);
        assert!(s < 1e-20, "{s}");
        let unstable = output_error((&mu, &[0.0, 1.5]), (1, 1, 1), &[&u], &[&y]);
        assert!(unstable.is_nan() || unstable > 1.0);
    }
}
