//! The stabilization diagram of ERA: the continuous poles of the models of orders `1..n_max`
//! realised from one Hankel SVD, each marked *stable* when the next order has a pole at nearly
//! the same frequency and damping (the standard tool of ERA/SSI modal analysis to tell
//! physical modes from noise modes: Peeters & De Roeck 2001, "Stochastic System Identification
//! for Operational Modal Analysis: A Review", J. Dyn. Sys. Meas. Control 123(4), 659–667, §5;
//! the realisation is Juang & Pappa 1985, J. Guidance 8(5), 620–627).
//!
//! # Realisation at every order from the same SVD
//! With `H(0) = U Σ Vᵀ` the decomposition the identification used ([`crate::era`]) and
//! `T = H(1) V_k` for the `k` leading triplets, the model of order `n ≤ k` is
//! [`era::realize`](crate::era::realize) on the first `n` triplets and the first `n` columns of
//! `T`: `A_n = Σ_n^-½ U_nᵀ H(1) V_n Σ_n^-½`, the leading `n × n` block of `A_k`. No second
//! SVD, no second ERA: truncating the same triplets is what changes the order. On the
//! truncated (Lanczos) SVD path the triplets beyond the model order are Ritz triplets of the
//! same Krylov basis (`H v = σ u` exactly, not converged to a tolerance): the columns of noise
//! they give are noise poles either way. The order of the published model is one row of the
//! diagram, with exactly the model's poles.
//!
//! # Poles
//! Each order's discrete poles `z` (eigenvalues of `A_n`) become `s = ln(z)/dt`
//! ([`crate::modal::continuous`]) and one entry per complex-conjugate pair (the `Im z > 0`
//! member) or real pole:
//!
//! ```text
//! fn = |s| / 2π,    ζ = −Re(s) / |s|
//! ```
//!
//! which for a pair is the mode's `ωn` and `ζ` (`ωn² = s s̄`), for a stable real pole
//! `fn = 1/(2π τ)` and `ζ = 1` (unstable: `ζ = −1`), and for a negative real `z` the pole at
//! Nyquist (`Im s = π/dt`). A pole at `z = 0` (`s = −∞`) or exactly `z = 1` (`|s| = 0`) has
//! no finite `fn`/`ζ` and is left out.
//!
//! # The stability rule ([`Criteria::USUAL`])
//! A pole `(f₁, ζ₁)` of order `n` is **stable** when the next realised order (`n + 1`, or the
//! next one whose realisation exists) has a pole `(f₂, ζ₂)` with
//!
//! ```text
//! |f₁ − f₂| / f₂ ≤ 0.01     and     |ζ₁ − ζ₂| / ζ₂ ≤ 0.05     (ζ₁, ζ₂ > 0)
//! ```
//!
//! i.e. 1 % in frequency and 5 % in damping, both relative to the next order's pole, and only
//! between poles of positive damping: a pole outside the unit circle is never a mode of the
//! stable plant on the stand, however well it repeats (the rounding-level triplets of
//! noise-free data realise undamped poles that do). The
//! damping tolerance is relative only, with no absolute floor near `ζ = 0`: the noise poles of
//! an ERA diagram are mostly lightly damped (`ζ` ≈ 0.002–0.02), and an absolute 0.005 would
//! let them pass as stable from one order to the next; the modes of a motor and propeller are
//! well damped. So that the top order listed is judged too, order `n_max + 1` is realised as
//! its comparison and not listed.
//!
//! # Orders
//! `n_max` defaults to [`default_n_max`] `= 2 · order + 8` (order: the model's), capped so
//! that `n_max + 1` triplets exist (the SVD's leading triplets, [`crate::era::Era::kmax`], at
//! most the smaller Hankel dimension). An order whose singular value is not positive (exact
//! data beyond their rank on the truncated path) has no realisation and is left out; the
//! `n_max` reported is the highest order listed, i.e. the highest one with a realised order
//! above it.

use nalgebra::Complex;
use serde::Serialize;

use crate::eig::eigenvalues;
use crate::era::{realize, Era, Factors};
use crate::hankel::HankelDims;
use crate::modal::continuous;
use crate::statespace::AbcdMut;
use crate::svd::SvdPath;
use crate::{IdentError, MarkovSeq};

/// The tolerances of the stability rule (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Criteria {
    /// Largest relative frequency difference `|f₁ − f₂| / f₂`.
    pub freq_rel: f64,
    /// Largest relative damping difference `|ζ₁ − ζ₂| / ζ₂`.
    pub zeta_rel: f64,
}

impl Criteria {
    /// 1 % in frequency, 5 % in damping: the usual ones.
    pub const USUAL: Criteria = Criteria {
        freq_rel: 0.01,
        zeta_rel: 0.05,
    };

    /// True when `p` (order `n`) matches `next` (order `n + 1`) within these tolerances, both
    /// with positive damping.
    pub fn matches(&self, p: &StabPole, next: &StabPole) -> bool {
        let df = (p.fn_hz - next.fn_hz).abs();
        let dz = (p.zeta - next.zeta).abs();
        p.zeta > 0.0
            && next.zeta > 0.0
            && df <= self.freq_rel * next.fn_hz
            && dz <= self.zeta_rel * next.zeta
    }
}

impl Default for Criteria {
    fn default() -> Self {
        Self::USUAL
    }
}

/// What to compute: the highest order (`None`: [`default_n_max`]) and the rule.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StabOptions {
    /// Highest order listed; `None` for `2 · order + 8`.
    pub n_max: Option<usize>,
    /// The stability rule.
    pub criteria: Criteria,
}

/// One pole entry of one order (a complex-conjugate pair or a real pole).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StabPole {
    /// `|s| / 2π`, Hz.
    pub fn_hz: f64,
    /// `−Re(s) / |s|`.
    pub zeta: f64,
    /// A pole of the next order lies within the criteria.
    pub stable: bool,
}

/// The poles of the model of one order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StabOrder {
    /// Model order `n`.
    pub order: usize,
    /// Its pole entries, ascending in frequency.
    pub poles: Vec<StabPole>,
}

/// The stabilization diagram (`identify --json`'s `"stabilization"`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stabilization {
    /// Highest order listed.
    pub n_max: usize,
    /// Order of the published model (its row holds the model's poles).
    pub model_order: usize,
    /// The stability rule.
    pub criteria: Criteria,
    /// Orders `1..=n_max` that have a realisation, ascending.
    pub orders: Vec<StabOrder>,
    /// `σ_1 .. σ_{n_max}` of `H(0)`: the singular value each order adds.
    pub singular_values: Vec<f64>,
}

impl Stabilization {
    /// Orders with a stable pole within the criteria of `(fn_hz, zeta)` (e.g. the model's).
    pub fn stable_orders_near(&self, fn_hz: f64, zeta: f64) -> Vec<usize> {
        let target = StabPole {
            fn_hz,
            zeta,
            stable: true,
        };
        self.orders
            .iter()
            .filter(|o| {
                o.poles
                    .iter()
                    .any(|p| p.stable && self.criteria.matches(p, &target))
            })
            .map(|o| o.order)
            .collect()
    }
}

/// `2 · model_order + 8`: room above the model for the noise poles to scatter.
pub fn default_n_max(model_order: usize) -> usize {
    2 * model_order + 8
}

/// One entry per complex-conjugate pair (`Im z > 0`) or real pole of the discrete poles `z`,
/// sample period `dt` (see the module docs), ascending in frequency, not yet marked.
pub fn pole_entries(z: &[Complex<f64>], dt: f64) -> Vec<StabPole> {
    let mut out: Vec<StabPole> = z
        .iter()
        .filter(|z| z.im >= 0.0)
        .filter_map(|&z| {
            let s = continuous(z, dt);
            let w = s.norm();
            let p = StabPole {
                fn_hz: w / (2.0 * std::f64::consts::PI),
                zeta: -s.re / w,
                stable: false,
            };
            (p.fn_hz.is_finite() && p.zeta.is_finite()).then_some(p)
        })
        .collect();
    out.sort_by(|a, b| a.fn_hz.total_cmp(&b.fn_hz));
    out
}

/// Marks each pole of `orders[i]` stable against `orders[i + 1]` (ascending orders; the last
/// one stays unmarked: it is the comparison of the one before).
pub fn mark_stable(orders: &mut [StabOrder], criteria: &Criteria) {
    for i in 0..orders.len().saturating_sub(1) {
        let (lo, hi) = orders.split_at_mut(i + 1);
        let next = &hi[0].poles;
        for p in &mut lo[i].poles {
            p.stable = next.iter().any(|q| criteria.matches(p, q));
        }
    }
}

/// The decomposition the model came from, borrowed: the Markov sequence ERA ran on, the Hankel
/// shape, the leading `k` triplets of `H(0)` and `T = H(1) V_k` (`rows × k`).
#[derive(Debug, Clone, Copy)]
pub struct Realisations<'a> {
    /// The Markov parameters ERA ran on.
    pub markov: &'a MarkovSeq,
    /// Hankel shape.
    pub dims: HankelDims,
    /// Leading triplets (`sigma` at least `k` long).
    pub factors: Factors<'a>,
    /// `H(1) V_k`.
    pub t: &'a [f64],
    /// Triplets usable, `k`.
    pub k: usize,
}

/// The diagram of orders `1..=n_max` from `r` (sample period `dt`); `n_max` is capped at
/// `r.k − 1` and lowered to the highest order with a realised order above it (see the module
/// docs).
pub fn diagram(
    r: &Realisations<'_>,
    dt: f64,
    n_max: usize,
    model_order: usize,
    criteria: Criteria,
) -> Stabilization {
    let n_max = n_max.min(r.k.saturating_sub(1));
    let (q, p) = (r.dims.q, r.dims.p);
    let mut orders: Vec<StabOrder> = (1..=n_max + 1)
        .filter_map(|n| {
            let s = r.factors.sigma[n - 1];
            if !(s.is_finite() && s > 0.0) {
                return None;
            }
            let (mut a, mut b, mut c, mut d) = (
                vec![0.0; n * n],
                vec![0.0; n * p],
                vec![0.0; q * n],
                vec![0.0; q * p],
            );
            let out = AbcdMut {
                a: &mut a,
                b: &mut b,
                c: &mut c,
                d: &mut d,
            };
            realize(r.markov.as_slice(), &r.dims, n, r.factors, r.t, out);
            let mut z = vec![Complex::new(0.0, 0.0); n];
            eigenvalues(&mut a, n, &mut z).ok()?;
            Some(StabOrder {
                order: n,
                poles: pole_entries(&z, dt),
            })
        })
        .collect();
    mark_stable(&mut orders, &criteria);
    // Every order listed has been judged: the last realised one is only a comparison.
    orders.pop();
    let n_max = orders.last().map_or(0, |o| o.order);
    Stabilization {
        n_max,
        model_order,
        criteria,
        orders,
        singular_values: r.factors.sigma[..n_max].to_vec(),
    }
}

/// The diagram from `era`'s last decomposition of `markov` (Hankel `dims`, SVD `path`,
/// singular values `sigma`), the published model being of order `model_order`: `T = H(1) V_k`
/// for the triplets needed ([`Era::h1_times_v_into`]), then [`diagram`]. Allocates; runs after
/// the model, never in the daemon's hot path.
pub fn from_era(
    era: &mut Era,
    markov: &MarkovSeq,
    (dims, path): (HankelDims, SvdPath),
    sigma: &[f64],
    dt: f64,
    model_order: usize,
    opts: &StabOptions,
) -> Result<Stabilization, IdentError> {
    let avail = era
        .kmax()
        .min(dims.rows().min(dims.cols()))
        .min(sigma.len());
    if avail == 0 || model_order == 0 {
        return Err(IdentError::InvalidInput(
            "stabilization: no model or no singular triplets",
        ));
    }
    let n_max = opts.n_max.unwrap_or(default_n_max(model_order)).max(1);
    let k = (n_max + 1).min(avail);
    let mut t = vec![0.0; dims.rows() * k];
    era.h1_times_v_into(markov, dims, k, path, &mut t)?;
    let r = Realisations {
        markov,
        dims,
        factors: Factors {
            sigma,
            u: era.u(),
            v: era.v(),
        },
        t: &t,
        k,
    };
    Ok(diagram(&r, dt, n_max, model_order, opts.criteria))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pole(fn_hz: f64, zeta: f64) -> StabPole {
        StabPole {
            fn_hz,
            zeta,
            stable: false,
        }
    }

    #[test]
    fn the_rule_is_one_percent_in_frequency_and_five_in_damping() {
        let c = Criteria::USUAL;
        let next = pole(100.0, 0.2);
        assert!(c.matches(&pole(100.99, 0.2), &next));
        assert!(!c.matches(&pole(101.01, 0.2), &next));
        assert!(c.matches(&pole(100.0, 0.2099), &next));
        assert!(!c.matches(&pole(100.0, 0.2101), &next));
        // Relative near zero damping too: no absolute floor.
        assert!(c.matches(&pole(100.0, 0.00104), &pole(100.0, 0.001)));
        assert!(!c.matches(&pole(100.0, 0.0011), &pole(100.0, 0.001)));
        // Negative damping never matches, however close.
        assert!(!c.matches(&pole(100.0, -0.01), &pole(100.0, -0.01)));
        assert!(!c.matches(&pole(100.0, 0.0), &pole(100.0, 0.0)));
    }

    #[test]
    fn pairs_give_one_entry_and_real_poles_zeta_one() {
        let dt = 0.001;
        let (wn, zeta) = (2.0 * std::f64::consts::PI * 10.0, 0.3);
        let s = Complex::new(-zeta * wn, wn * (1.0f64 - zeta * zeta).sqrt());
        let z = (s * dt).exp();
        let real = Complex::new((-50.0f64 * dt).exp(), 0.0);
        let nyquist = Complex::new(-0.5, 0.0);
        let e = pole_entries(&[z, z.conj(), real, Complex::new(0.0, 0.0), nyquist], dt);
        assert_eq!(e.len(), 3, "{e:?}");
        assert!((e[0].fn_hz - 50.0 / (2.0 * std::f64::consts::PI)).abs() < 1e-9);
        assert!((e[0].zeta - 1.0).abs() < 1e-12);
        assert!((e[1].fn_hz - 10.0).abs() < 1e-9 && (e[1].zeta - 0.3).abs() < 1e-9);
        assert!(e[2].fn_hz > 0.5 / dt, "Nyquist pole above fs/2: {e:?}");
    }

    #[test]
    fn marking_compares_with_the_next_order_only() {
        let mut o = vec![
            StabOrder {
                order: 1,
                poles: vec![pole(5.0, 1.0)],
            },
            StabOrder {
                order: 2,
                poles: vec![pole(10.0, 0.2)],
            },
            StabOrder {
                order: 3,
                poles: vec![pole(10.05, 0.201), pole(30.0, 0.5)],
            },
            StabOrder {
                order: 4,
                poles: vec![pole(10.0, 0.2), pole(44.0, 0.1)],
            },
        ];
        mark_stable(&mut o, &Criteria::USUAL);
        assert!(!o[0].poles[0].stable);
        assert!(o[1].poles[0].stable);
        assert!(o[2].poles[0].stable && !o[2].poles[1].stable);
        assert!(o[3].poles.iter().all(|p| !p.stable), "no next order");
    }
}
