//! `static_nonlinearity`: a power-law static map before the linear core,
//! `v ← u_r · (max(v, 0) / u_r)^p` with `u_r` the mean throttle of the estimation part (so the
//! core's gain `K` stays the gain at the mean operating point).

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::Ctx;
use crate::effect::Effect;
use crate::fit::Fit;
use crate::signals::{Core, Signals};
use crate::term::{to_map, Place, Scale, Term};
use propid_numerics::EffectName;

/// The published name.
pub const NAME: EffectName = EffectName::StaticNonlinearity;

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct StaticNonlinearity;

/// The fitted map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticNonlinearityParams {
    /// Exponent `p` of the power law (dimensionless; 1 is linear).
    pub exponent: f64,
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// `"hardens"` (exponent above 1) or `"softens"`.
    curvature: &'static str,
    /// Exponent of the power law.
    exponent: f64,
}

impl Effect for StaticNonlinearity {
    fn name(&self) -> EffectName {
        NAME
    }

    /// A power law needs a throttle-like input: non-negative, away from zero on average. Starts
    /// at exponents 0.5, 0.75, 1.5, 2 and 3; Levenberg–Marquardt from the two best.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let throttle_like = ctx.sig.u[ctx.est.clone()].iter().all(|&x| x >= 0.0);
        if !throttle_like || ctx.sig.u_ref <= 1e-3 {
            return None;
        }
        let starts = [0.5, 0.75, 1.5, 2.0, 3.0]
            .map(|exponent| cur.model.with(StaticNonlinearityParams { exponent }));
        Some(ctx.best_of(starts, 2))
    }
}

impl Term for StaticNonlinearityParams {
    fn name(&self) -> EffectName {
        NAME
    }

    fn place(&self) -> Place {
        Place::InputMap
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    /// An exponent within 0.1..10.
    fn plausible(&self, _ctx: &Ctx, _core: &Core, _has_nan: bool) -> bool {
        (0.1..=10.0).contains(&self.exponent)
    }

    /// `u_ref · (max(v, 0) / u_ref)^e` per sample. A stand's command holds each level for many
    /// samples: the power of a value equal to the previous one is reused (the same result;
    /// `powf` was a third of a staircase's diagnosis time).
    fn shape_input(&self, v: &mut [f64], sig: &Signals) {
        let (mut last_in, mut last_out) = (f64::NAN, f64::NAN);
        for x in v.iter_mut() {
            if *x != last_in {
                last_in = *x;
                last_out = sig.u_ref * (x.max(0.0) / sig.u_ref).powf(self.exponent);
            }
            *x = last_out;
        }
    }

    fn free(&self) -> Vec<(f64, Scale)> {
        vec![(self.exponent, Scale::Linear)]
    }

    fn set_free(&mut self, values: &[f64]) {
        self.exponent = values[0];
    }

    /// `d/dv [u_r (v/u_r)^p]` at `v = u_r` is `p`.
    fn dc_slope(&self) -> f64 {
        self.exponent
    }

    fn terms(&self, _dt_s: f64, terms: &mut Map<String, Value>) {
        terms.insert("exponent".into(), json!(self.exponent));
    }

    fn finding_params(&self, _dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            curvature: self.curvature(),
            exponent: self.exponent,
        })
    }

    fn evidence(&self, core: &Core, ctx: &Ctx, drop: &str) -> String {
        let e = self.exponent;
        let how = self.curvature();
        let (lo, hi) = throttle_span(ctx);
        let g = |u: f64| core.gain * e * (u / ctx.sig.u_ref).powf(e - 1.0);
        format!(
            "the small-signal gain changes with the operating point ({:.3} per unit throttle at \
             {lo:.2}, {:.3} at {hi:.2}): the static map follows throttle^{e:.2} and {how}; \
             with that map before the linear part {drop}",
            g(lo),
            g(hi)
        )
    }
}

impl StaticNonlinearityParams {
    /// `"hardens"` for an exponent above 1, else `"softens"`.
    pub fn curvature(&self) -> &'static str {
        if self.exponent > 1.0 {
            "hardens"
        } else {
            "softens"
        }
    }
}

/// 10th and 90th percentile of the throttle.
fn throttle_span(ctx: &Ctx) -> (f64, f64) {
    let mut u: Vec<f64> = ctx.sig.u.to_vec();
    u.sort_by(|a, b| a.total_cmp(b));
    let q = |f: f64| u[((u.len() - 1) as f64 * f) as usize];
    (q(0.1), q(0.9))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = StaticNonlinearityParams { exponent: 0.5 };
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(
            text(&p.finding_params(0.002)),
            r#"{"curvature":"softens","exponent":0.5}"#
        );
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(text(&terms), r#"{"exponent":0.5}"#);
    }
}
