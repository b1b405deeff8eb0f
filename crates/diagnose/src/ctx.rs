//! The data of one diagnosis (signals, estimation and validation samples) and the fitting
//! steps every effect uses: Levenberg–Marquardt from one start, the best of several starts,
//! residuals and the validation error.

use std::ops::Range;

use super::fit::{levenberg_marquardt, linear_refit, Fit};
use super::model::{simulate, Core, Model, Signals};
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
}

impl Ctx<'_> {
    /// Levenberg–Marquardt on the estimation samples from `start`, at most `iters` steps.
    pub fn lm(&self, start: &Model, iters: usize) -> Fit {
        levenberg_marquardt(start, &self.sig, self.est.clone(), iters)
    }

    /// Every start scored after a linear refit (gain, offset, linear terms), then
    /// Levenberg–Marquardt (40 steps) from the `keep` best; the best result wins. With no
    /// usable start: the first start with the default core and an infinite SSE.
    pub fn best_of(&self, starts: impl IntoIterator<Item = Model>, keep: usize) -> Fit {
        let starts: Vec<Model> = starts.into_iter().collect();
        let fallback = starts
            .first()
            .map_or_else(Model::default, |m| m.with_core(Core::default()));
        let mut scored: Vec<(f64, Model)> = starts
            .into_iter()
            .map(|p| {
                let (q, s) = linear_refit(&p, &self.sig, self.est.clone());
                (s, q)
            })
            .filter(|(s, _)| s.is_finite())
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best: Option<Fit> = None;
        for (_, p) in scored.into_iter().take(keep.max(1)) {
            let f = self.lm(&p, 40);
            if best.as_ref().map_or(true, |b| f.sse < b.sse) {
                best = Some(f);
            }
        }
        best.unwrap_or(Fit {
            model: fallback,
            sse: f64::INFINITY,
            n: 0,
        })
    }

    /// The simulation residual of a fit on the estimation samples.
    pub fn residual(&self, f: &Fit) -> Vec<f64> {
        let mut buf = vec![0.0; self.sig.u.len()];
        simulate(&f.model, &self.sig, &mut buf);
        self.est.clone().map(|k| self.sig.y[k] - buf[k]).collect()
    }
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
        }
    }
}
