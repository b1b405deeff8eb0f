//! How many singular values of `H(0)` carry signal: the model order.
//!
//! A random `m × n` matrix of independent entries of standard deviation `σ` has largest
//! singular value about `σ(√m + √n)`; singular values of `H(0)` above
//! `noise_sv_factor · σ(√m + √n)` (`noise_sv_factor` = 1.5, [`THRESHOLDS`]) and above
//! `rank_tol · σ_1` (`1e-9`, rounding) carry signal ([`noise_singular_value`]). The order is
//! their count, capped at the workspace's maximum order ([`auto_order`]). `σ` is the noise of
//! the Markov parameters pooled over outputs ([`pooled_noise`]; per output from
//! [`super::noise_floor`]). A given order is kept when `H(0)` has at least that rank above
//! rounding ([`choose`]); [`check_order`] refuses, before anything is sized, an order the
//! record cannot support at all.
//!
//! **The automatic order settles** ([`settled_order`]). The count above the noise is an
//! estimate: a noise level read a little low lets a singular value of noise in, and its
//! realisation is often a pole pair near the Nyquist frequency just outside the unit circle
//! (measured: a staircase of a first-order stand with a 2-sample dead time, order 5 with
//! `z = −0.996 ± 0.190i`, `|z| = 1.014`; orders 3 and 4 settle and give the same time
//! constant and gain). A motor–propeller settles, so an automatic order steps down from the
//! count to the largest order whose poles all settle (`Re(s) < 0`, the rule of
//! [`crate::quality`]), and the report says from which count
//! (`order_stepped_down_from`). When no order down to 1 settles, the count stands and the
//! quality check refuses the model as before. A given order is never changed.

use super::hankel_size::HankelSize;
use super::THRESHOLDS;
use crate::hankel::HankelDims;
use crate::workspace::limits::Limits;
use crate::IdentError;

/// `σ = √(Σ_i σ_i² / q)` over the outputs' Markov-parameter noise `noise` (`q` values); an
/// unknown (non-finite) `σ_i` counts as zero.
pub fn pooled_noise(noise: &[f64]) -> f64 {
    (noise
        .iter()
        .map(|s| if s.is_finite() { s * s } else { 0.0 })
        .sum::<f64>()
        / noise.len() as f64)
        .sqrt()
}

/// The largest singular value expected from noise alone. For white Markov noise (one-sample
/// pulses, `growth` empty or all ones) `noise_sv_factor · σ (√rows + √cols)`. After the
/// deconvolution of wider pulses the noise is a random walk (strongly correlated), whose
/// Hankel matrix concentrates its energy in a few singular values; then the bound is the
/// Frobenius norm of the noise Hankel, `σ √(Σ_(a,b) q p g²_{a+b+1})`.
pub fn noise_singular_value(sigma_markov: f64, dims: &HankelDims, growth: &[f64]) -> f64 {
    let white = THRESHOLDS.noise_sv_factor
        * sigma_markov
        * ((dims.rows() as f64).sqrt() + (dims.cols() as f64).sqrt());
    if growth.iter().all(|g| *g <= 1.0 + 1e-12) {
        return white;
    }
    let mut fro2 = 0.0;
    for a in 0..dims.r {
        for b in 0..dims.c {
            let g = growth.get(a + b + 1).copied().unwrap_or(1.0);
            fro2 += g * g;
        }
    }
    white.max(sigma_markov * (fro2 * (dims.q * dims.p) as f64).sqrt())
}

/// Count of singular values above the noise singular value `noise_sv` and the rounding floor
/// `rank_tol · σ_1`, capped at `max_order`.
pub fn auto_order(sigma: &[f64], noise_sv: f64, max_order: usize) -> usize {
    let first = sigma.first().copied().unwrap_or(0.0);
    let floor = noise_sv.max(THRESHOLDS.rank_tol * first);
    sigma
        .iter()
        .take_while(|s| **s > floor)
        .count()
        .min(max_order)
}

/// Count of the singular values `sigma` of `H(0)` (`dims`) above the noise of Markov
/// parameters with per-output noise `noise` ([`pooled_noise`], [`noise_singular_value`]),
/// capped at `max_order`.
pub fn order_above_noise(
    sigma: &[f64],
    noise: &[f64],
    dims: &HankelDims,
    growth: &[f64],
    max_order: usize,
) -> usize {
    let noise_sv = noise_singular_value(pooled_noise(noise), dims, growth);
    auto_order(sigma, noise_sv, max_order)
}

/// The model order from the singular values `sigma` of `H(0)` (`dims`): a `given` order when
/// `H(0)` has at least that rank above rounding, else the count above the noise
/// ([`order_above_noise`], at most `max_order`). No order (0) is
/// [`IdentError::RankDeficient`].
pub fn choose(
    sigma: &[f64],
    noise: &[f64],
    dims: &HankelDims,
    growth: &[f64],
    given: Option<usize>,
    max_order: usize,
) -> Result<usize, IdentError> {
    let n = match given {
        Some(n) => {
            let rank = auto_order(sigma, 0.0, dims.rows().min(dims.cols()));
            if rank < n {
                return Err(IdentError::RankDeficient { rank, order: n });
            }
            n
        }
        None => order_above_noise(sigma, noise, dims, growth, max_order),
    };
    if n == 0 {
        return Err(IdentError::RankDeficient { rank: 0, order: 0 });
    }
    Ok(n)
}

/// The automatic order that settles (see the module documentation): `count` when
/// `settles(count)`, else the largest order below it for which `settles` is true, else
/// `count`. `settles(n)` realises order `n` and says whether its poles all settle; it is
/// asked once per order, from `count` down, and last of the answer returned (so the
/// realisation left behind is the returned order's).
pub fn settled_order<E>(
    count: usize,
    mut settles: impl FnMut(usize) -> Result<bool, E>,
) -> Result<usize, E> {
    for n in (1..=count).rev() {
        if settles(n)? {
            return Ok(n);
        }
    }
    if count > 1 {
        settles(count)?;
    }
    Ok(count)
}

/// Refuses a requested `order` larger than `n` samples (or Markov blocks) with `q` outputs and
/// `p` inputs can support, before any workspace is sized from it. ERA's Hankel `H(0)` of `r × c`
/// blocks from `Y_1 .. Y_{r+c−1}` (and `H(1)` one block further) needs `r + c ≤ n − 1`; its
/// rank is at most `min(r q, c p)`, largest for `r q = c p`: `(n − 1) p q / (p + q)`. The
/// workspace also caps `r` and `c` at the default block counts of [`Limits`] when the size is
/// automatic. The core checks the exact Hankel later ([`IdentError::OrderTooHigh`] too); this
/// bound only has to be safe.
pub fn check_order(
    order: Option<usize>,
    n: usize,
    q: usize,
    p: usize,
    size: HankelSize,
) -> Result<(), IdentError> {
    let Some(order) = order else {
        return Ok(());
    };
    let (q, p) = (q.max(1), p.max(1));
    let d = Limits::default();
    let data = n.saturating_sub(1) * p * q / (p + q);
    let max = match size {
        HankelSize::Auto => data.min((d.max_block_rows * q).min(d.max_block_cols * p)),
        HankelSize::Square => data,
        HankelSize::Blocks(r, c) => data.min((r * q).min(c * p)),
    };
    if order > max {
        return Err(IdentError::OrderTooHigh { order, max });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_counts_singular_values_above_noise_and_rounding() {
        assert_eq!(auto_order(&[10.0, 5.0, 0.01, 0.009], 0.1, 8), 2);
        assert_eq!(auto_order(&[10.0, 5.0, 1e-12], 0.0, 8), 2);
        assert_eq!(auto_order(&[10.0, 5.0, 4.0], 0.0, 2), 2);
        // 1 × 1 blocks, 4 × 4: noise level 1.5 σ (2 + 2) = 6 σ.
        let dims = HankelDims {
            q: 1,
            p: 1,
            r: 4,
            c: 4,
        };
        assert_eq!(noise_singular_value(0.1, &dims, &[]), 1.5 * 0.1 * 4.0);
        assert_eq!(
            order_above_noise(&[10.0, 0.5, 0.4], &[0.1], &dims, &[], 8),
            1
        );
        // Unknown noise counts as zero: only rounding is cut.
        assert_eq!(pooled_noise(&[f64::NAN, 0.3]), (0.09f64 / 2.0).sqrt());
    }

    #[test]
    fn the_automatic_order_steps_down_to_the_largest_that_settles() {
        // Orders 5 and 4 realise a pole that does not settle, 3 settles: 3, asked last.
        let mut asked = Vec::new();
        let n = settled_order::<()>(5, |n| {
            asked.push(n);
            Ok(n <= 3)
        });
        assert_eq!((n, asked), (Ok(3), vec![5, 4, 3]));
        // The count settles: kept, asked once.
        let mut asked = Vec::new();
        let n = settled_order::<()>(2, |n| {
            asked.push(n);
            Ok(true)
        });
        assert_eq!((n, asked), (Ok(2), vec![2]));
        // None settles: the count stands, realised again last.
        let mut asked = Vec::new();
        let n = settled_order::<()>(3, |n| {
            asked.push(n);
            Ok(false)
        });
        assert_eq!((n, asked), (Ok(3), vec![3, 2, 1, 3]));
        // A realisation that fails stops the search with its error.
        assert_eq!(
            settled_order(3, |n| if n == 2 { Err("x") } else { Ok(false) }),
            Err("x")
        );
    }

    #[test]
    fn a_given_order_needs_that_rank() {
        let dims = HankelDims {
            q: 1,
            p: 1,
            r: 3,
            c: 3,
        };
        let sigma = [1.0, 0.5, 1e-12];
        assert_eq!(choose(&sigma, &[0.0], &dims, &[], Some(2), 8), Ok(2));
        assert_eq!(
            choose(&sigma, &[0.0], &dims, &[], Some(3), 8),
            Err(IdentError::RankDeficient { rank: 2, order: 3 })
        );
        assert_eq!(
            choose(&sigma, &[10.0], &dims, &[], None, 8),
            Err(IdentError::RankDeficient { rank: 0, order: 0 })
        );
    }

    #[test]
    fn orders_beyond_the_record_are_refused() {
        assert!(check_order(None, 3, 1, 1, HankelSize::Auto).is_ok());
        assert!(check_order(Some(4), 10, 1, 1, HankelSize::Square).is_ok());
        assert_eq!(
            check_order(Some(5), 10, 1, 1, HankelSize::Square),
            Err(IdentError::OrderTooHigh { order: 5, max: 4 })
        );
        assert!(check_order(Some(4), 100, 1, 1, HankelSize::Blocks(3, 3)).is_err());
    }
}
