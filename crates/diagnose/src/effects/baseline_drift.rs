//! `baseline_drift`: the output creeps linearly in time whatever the input does (load-cell creep,
//! temperature): `ŷ ← ŷ + r t`.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/effects/baseline_drift.rs`.

use crate::thresholds::UNIDENTIFIABLE_R2;
use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::{affine_r2, measured_estimation_samples, Ctx};
use crate::effect::Effect;
use crate::fit::Fit;
use crate::signals::{Core, Signals};
use crate::term::{to_map, Place, Scale, Term};
use crate::verdict::{Warning, WarningKind};
use propid_numerics::EffectName;

/// The published name.
pub const NAME: EffectName = EffectName::BaselineDrift;

/// `R²` of `t` fitted by `[1, u]` over the estimation samples with a measured output, `u` the
/// command (module doc); 0 when the command is constant there.
pub fn confounding(ctx: &Ctx) -> f64 {
    let ks = measured_estimation_samples(ctx, 0);
    let dt = ctx.sig.dt_s;
    affine_r2(&ks, |k| k as f64 * dt, |k| ctx.sig.u[k])
}

/// The `baseline_drift_unidentifiable` warning when `r2` (the share of `t` explained by the
/// command) reaches [`UNIDENTIFIABLE_R2`].
fn drift_warning(r2: f64) -> Option<Warning> {
    (r2 >= UNIDENTIFIABLE_R2).then(|| Warning {
        kind: WarningKind::BaselineDriftUnidentifiable,
        message: format!(
            "baseline drift not identifiable: the command runs one way through the record (time \
             is affine in it to R² = {r2:.5}), so a drift of the output cannot be told from a \
             change of the thrust curve; a ramp up and back down, or holds, would separate them"
        ),
        model: "baseline",
        value: r2,
        band_hz: None,
    })
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
    fn name(&self) -> EffectName {
        NAME
    }

    /// One start (no drift); the rate enters linearly.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let start = cur.model.with(BaselineDriftParams { rate_per_s: 0.0 });
        Some(ctx.best_of([start], 1))
    }

    fn warning(
        &self,
        ctx: &Ctx,
        _cur: &Fit,
        _found: bool,
        _model: &'static str,
    ) -> Option<Warning> {
        drift_warning(confounding(ctx))
    }
}

impl Term for BaselineDriftParams {
    fn name(&self) -> EffectName {
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
    use crate::signals::Signals;

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
            gate: Default::default(),
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
