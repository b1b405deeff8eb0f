//! `supply_sag`: the gain follows the supply voltage (a sagging battery gives less thrust per
//! unit throttle): `v ← v · (1 + g_V (V_k − V_r))` with `V_r` the mean voltage of the
//! estimation part. Needs a voltage channel.

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::diagnose::ctx::Ctx;
use crate::diagnose::effect::{to_map, Effect, Place, Scale, Term};
use crate::diagnose::fit::Fit;
use crate::diagnose::model::{Core, Signals};

/// The published name.
pub const NAME: &str = "supply_sag";

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct SupplySag;

/// The fitted voltage dependence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupplySagParams {
    /// Relative gain change per volt `g_V`, 1/V.
    pub gain_per_volt: f64,
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// Relative gain change per volt, 1/V.
    gain_per_volt: f64,
}

impl Effect for SupplySag {
    fn name(&self) -> &'static str {
        NAME
    }

    /// Without a voltage channel: not applicable. Starts at ±0.03 and ±0.1 per volt;
    /// Levenberg–Marquardt from the best.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        ctx.sig.voltage?;
        let starts = [-0.1, -0.03, 0.03, 0.1]
            .map(|gain_per_volt| cur.model.with(SupplySagParams { gain_per_volt }));
        Some(ctx.best_of(starts, 1))
    }
}

impl Term for SupplySagParams {
    fn name(&self) -> &'static str {
        NAME
    }

    fn place(&self) -> Place {
        Place::InputScale
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    fn shape_input(&self, v: &mut [f64], sig: &Signals) {
        if let Some(volt) = sig.voltage {
            for (x, vk) in v.iter_mut().zip(volt) {
                *x *= 1.0 + self.gain_per_volt * (vk - sig.v_ref);
            }
        }
    }

    fn free(&self) -> Vec<(f64, Scale)> {
        vec![(self.gain_per_volt, Scale::Linear)]
    }

    fn set_free(&mut self, values: &[f64]) {
        self.gain_per_volt = values[0];
    }

    fn terms(&self, _dt_s: f64, terms: &mut Map<String, Value>) {
        terms.insert("gain_per_volt".into(), json!(self.gain_per_volt));
    }

    fn finding_params(&self, _dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            gain_per_volt: self.gain_per_volt,
        })
    }

    fn evidence(&self, _core: &Core, ctx: &Ctx, drop: &str) -> String {
        let (lo, hi) = ctx.sig.voltage.map_or((0.0, 0.0), |x| {
            x.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                })
        });
        format!(
            "the gain follows the supply voltage ({:+.1} % per volt while the supply ranged \
             {lo:.2}..{hi:.2} V); with a voltage-scaled input {drop}",
            100.0 * self.gain_per_volt
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = SupplySagParams {
            gain_per_volt: 0.05,
        };
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(text(&p.finding_params(0.002)), r#"{"gain_per_volt":0.05}"#);
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(text(&terms), r#"{"gain_per_volt":0.05}"#);
    }
}
