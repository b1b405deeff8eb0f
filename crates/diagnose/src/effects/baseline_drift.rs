//! `baseline_drift`: the output creeps linearly in time whatever the input does (load-cell
//! creep, temperature): `ŷ ← ŷ + r t`.
//!
//! **Identifiability.** The drift's regressor `t` competes with the static map's: a command
//! `u` that runs one way through the whole record, slowly against the dynamics (a thrust-curve
//! ramp), is an affine function of time, `u = a + b t`, and then a drift of the output is
//! indistinguishable from a change of the map: `K u + r t = (K + r/b) u − r a/b`, and with a
//! curved map the drift is read only through the assumed shape of the curve (a drift hidden in
//! a measured ramp is named as a steeper or more curved map). [`confounding`] measures it: `R²`
//! of the least-squares fit of `t` by `[1, u]` over the estimation samples (the fitted rate's
//! variance grows as `1 / (1 − R²)`). At `R² ≥` [`UNIDENTIFIABLE_R2`] diagnose says so (a
//! `baseline_drift_unidentifiable` warning) rather than nothing. The command, not the fitted
//! response, is the measure: the 2nd-order baseline bends its response (a slow mode) to imitate
//! a curved map, and would hide the ramp. A staircase holds each level while `t` runs on (`R²`
//! of a monotone staircase of `L` equal levels is about `1 − 1/L²`) and a ramp up and back down
//! is uncorrelated with `t`: on those the drift is read from the creep within the holds, or from
//! the difference between the way up and the way down at the same command.

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::Ctx;
use crate::effect::{to_map, Effect, Place, Scale, Term};
use crate::fit::Fit;
use crate::model::{Core, Signals};

/// The published name.
pub const NAME: &str = "baseline_drift";

/// `R²` at and above which the drift is called unidentifiable: the fitted rate's variance
/// inflated a thousandfold, `t` affine in the command to within 0.1 % of its variance (a
/// monotone staircase needs about 30 equal levels to get there).
pub const UNIDENTIFIABLE_R2: f64 = 0.999;

/// `R²` of `t` fitted by `[1, u]` over the estimation samples with a measured output, `u` the
/// command (module doc); 0 when the command is constant there.
pub fn confounding(ctx: &Ctx) -> f64 {
    let ks = measured_estimation_samples(ctx, 0);
    let dt = ctx.sig.dt_s;
    affine_r2(&ks, |k| k as f64 * dt, |k| ctx.sig.u[k])
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

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct BaselineDrift;

/// The fitted drift.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaselineDriftParams {
    /// Drift rate `r`, output units per second.
    pub rate_per_s: f64,
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// Drift rate, output units per second.
    rate_per_s: f64,
}

impl Effect for BaselineDrift {
    fn name(&self) -> &'static str {
        NAME
    }

    /// One start (no drift); the rate enters linearly.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let start = cur.model.with(BaselineDriftParams { rate_per_s: 0.0 });
        Some(ctx.best_of([start], 1))
    }
}

impl Term for BaselineDriftParams {
    fn name(&self) -> &'static str {
        NAME
    }

    fn place(&self) -> Place {
        Place::OutputAdd
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    fn shape_output(&self, y: &mut [f64], sig: &Signals) {
        for (k, yk) in y.iter_mut().enumerate() {
            *yk += self.rate_per_s * (k as f64 * sig.dt_s);
        }
    }

    /// The lowest bins, `(0, 8.5/T]` over the estimation part's `T = n·dt`: where a line over
    /// the record has its power (Hann periodogram of the mean-removed ramp).
    fn band_hz(&self, n: usize, dt_s: f64) -> Option<[f64; 2]> {
        Some([0.0, 8.5 / (n as f64 * dt_s)])
    }

    fn free(&self) -> Vec<(f64, Scale)> {
        vec![(self.rate_per_s, Scale::Linear)]
    }

    fn set_free(&mut self, values: &[f64]) {
        self.rate_per_s = values[0];
    }

    fn linear_count(&self) -> usize {
        1
    }

    fn linear_row(&self, t_s: f64, row: &mut [f64]) {
        row[0] = t_s;
    }

    fn set_linear(&mut self, theta: &[f64]) {
        self.rate_per_s = theta[0];
    }

    fn terms(&self, _dt_s: f64, terms: &mut Map<String, Value>) {
        terms.insert("drift_per_s".into(), json!(self.rate_per_s));
    }

    fn finding_params(&self, _dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            rate_per_s: self.rate_per_s,
        })
    }

    fn evidence(&self, _core: &Core, ctx: &Ctx, drop: &str) -> String {
        format!(
            "the output creeps by {:.5} units per second ({:.4} over the record) whatever the \
             input does; with a drift term {drop}",
            self.rate_per_s,
            self.rate_per_s * ctx.sig.u.len() as f64 * ctx.sig.dt_s
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Signals;

    fn ctx<'a>(u: &'a [f64], y: &'a [f64]) -> Ctx<'a> {
        Ctx {
            sig: Signals {
                dt_s: 0.02,
                u,
                y,
                voltage: None,
                u_ref: 0.5,
                v_ref: 0.0,
            },
            est: 0..u.len(),
            val: 0..u.len(),
            rules: propid_numerics::segment::SegmentRules::DEFAULT,
        }
    }

    /// A one-way ramp confounds the drift with the map; a staircase of 5 levels and a ramp up
    /// and back down do not.
    #[test]
    fn a_one_way_ramp_confounds_the_drift_and_a_staircase_or_a_ramp_up_and_down_does_not() {
        let n = 2000;
        let ramp: Vec<f64> = (0..n).map(|k| k as f64 / n as f64).collect();
        let stairs: Vec<f64> = (0..n).map(|k| (5 * k / n) as f64 * 0.2).collect();
        let updown: Vec<f64> = (0..n)
            .map(|k| 1.0 - (2.0 * k as f64 / n as f64 - 1.0).abs())
            .collect();
        let y = vec![0.0; n];
        let r2 = |u: &[f64]| confounding(&ctx(u, &y));
        assert!(r2(&ramp) >= UNIDENTIFIABLE_R2, "{}", r2(&ramp));
        assert!(r2(&stairs) < 0.97, "{}", r2(&stairs));
        assert!(r2(&updown) < 0.01, "{}", r2(&updown));
        assert_eq!(r2(&vec![0.3; n]), 0.0);
    }

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = BaselineDriftParams { rate_per_s: -0.02 };
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(text(&p.finding_params(0.002)), r#"{"rate_per_s":-0.02}"#);
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(text(&terms), r#"{"drift_per_s":-0.02}"#);
    }
}
