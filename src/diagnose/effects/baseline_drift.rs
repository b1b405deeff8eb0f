//! `baseline_drift`: the output creeps linearly in time whatever the input does (load-cell
//! creep, temperature): `ŷ ← ŷ + r t`.

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::diagnose::ctx::Ctx;
use crate::diagnose::effect::{to_map, Effect, Place, Scale, Term};
use crate::diagnose::fit::Fit;
use crate::diagnose::model::{Core, Signals};

/// The published name.
pub const NAME: &str = "baseline_drift";

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
