//! The data of one diagnosis ([`Ctx`]: signals, estimation and validation samples, the
//! segmentation's rules) and the estimation samples an effect's evidence is read on; the
//! fitting steps on it are in [`crate::fit`].

use std::ops::Range;

use super::signals::Signals;
use propid_numerics::segment::SegmentRules;

/// The data, the estimation range and the validation range.
#[derive(Debug, Clone)]
pub struct Ctx<'a> {
    /// Signals.
    pub sig: Signals<'a>,
    /// Estimation samples.
    pub est: Range<usize>,
    /// Validation samples.
    pub val: Range<usize>,
    /// The segmentation's rules for this record (its holds, levels and steps): at its rate
    /// for a stand's command ([`SegmentRules::at_rate`]), by the sample count alone for a
    /// signal in its own units ([`super::Options::input_is_a_command`]).
    pub rules: SegmentRules,
    /// The acceptance test of a held-out gain ([`super::Options::gate`]).
    pub gate: super::thresholds::Gate,
}

/// The estimation samples from `first` on whose output is measured.
pub fn measured_estimation_samples(ctx: &Ctx, first: usize) -> Vec<usize> {
    ctx.est
        .clone()
        .filter(|&k| k >= first && ctx.sig.y.get(k).is_some_and(|y| y.is_finite()))
        .collect()
}

/// `R²` of `a` fitted by `[1, b]` over the samples `ks` (the squared correlation of `a` and
/// `b` there): how far one is an affine function of the other, the measure of both the drift's
/// and the dead time's identifiability. 0 when either is constant there (to within 1e-12 of
/// its mean) or with fewer than 3 samples.
pub fn affine_r2(ks: &[usize], a: impl Fn(usize) -> f64, b: impl Fn(usize) -> f64) -> f64 {
    if ks.len() < 3 {
        return 0.0;
    }
    let m = ks.len() as f64;
    let mean = |f: &dyn Fn(usize) -> f64| ks.iter().map(|&k| f(k)).sum::<f64>() / m;
    let (ma, mb) = (mean(&a), mean(&b));
    let sab = mean(&|k| (a(k) - ma) * (b(k) - mb));
    let saa = mean(&|k| (a(k) - ma).powi(2));
    let sbb = mean(&|k| (b(k) - mb).powi(2));
    if !(saa > 1e-24 * ma * ma && sbb > 1e-24 * mb * mb && saa > 0.0 && sbb > 0.0) {
        return 0.0;
    }
    (sab * sab / (saa * sbb)).clamp(0.0, 1.0)
}

#[cfg(test)]
impl<'a> Ctx<'a> {
    /// Tests: input `u` and output `y` every `dt_s`, no voltage, the whole record for
    /// estimation and validation, the static map referred to the input's mean.
    pub fn whole(dt_s: f64, u: &'a [f64], y: &'a [f64]) -> Ctx<'a> {
        let n = u.len();
        Ctx {
            sig: Signals {
                dt_s,
                u,
                y,
                voltage: None,
                u_ref: u.iter().sum::<f64>() / n.max(1) as f64,
                v_ref: 0.0,
            },
            est: 0..n,
            val: 0..n,
            rules: propid_numerics::segment::SegmentRules::DEFAULT,
            gate: Default::default(),
        }
    }
}
