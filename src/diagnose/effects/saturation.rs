//! `saturation`: the throttle or the sensor clips. A throttle clip `v ← min(v, L)` acts before
//! the static map (more command gives no more thrust); a sensor clip `ŷ ← min(ŷ, Y)` is the
//! last step (readings above `Y` read `Y`). A sensor clip is recognised straight from the data
//! (a flat top at the largest reading) before any fit; a throttle clip is fitted.

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::diagnose::ctx::Ctx;
use crate::diagnose::effect::{to_map, Detected, Effect, Place, Term};
use crate::diagnose::fit::{linear_refit, Fit};
use crate::diagnose::model::{Core, Signals};

/// The published name.
pub const NAME: &str = "saturation";

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct Saturation;

/// What clips.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clipped {
    /// The throttle, before the static map.
    Throttle,
    /// The sensor, after everything else.
    Sensor {
        /// Estimation samples that read exactly the clip level.
        samples: usize,
    },
}

/// The clip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SaturationParams {
    /// Clip level: throttle (0..1) for a throttle clip, output units for a sensor clip.
    pub level: f64,
    /// What clips.
    pub clipped: Clipped,
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// Clip level (throttle, or output units).
    level: f64,
    /// `"throttle"` or `"sensor"`.
    signal: &'static str,
}

impl Effect for Saturation {
    fn name(&self) -> &'static str {
        NAME
    }

    /// A sensor clip: the largest reading of the estimation part repeats on at least 20
    /// samples and 0.5 % of them (a flat top). Its score is the number of clipped samples.
    fn detect(&self, ctx: &Ctx) -> Option<Detected> {
        let ys = &ctx.sig.y[ctx.est.clone()];
        let top = ys
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(f64::NEG_INFINITY, f64::max);
        if !top.is_finite() {
            return None;
        }
        let tol = 1e-9 * top.abs().max(1e-12);
        let count = ys.iter().filter(|v| (*v - top).abs() <= tol).count();
        (count >= 20 && count * 200 >= ys.len()).then(|| Detected {
            term: Box::new(SaturationParams {
                level: top,
                clipped: Clipped::Sensor { samples: count },
            }),
            score: count as f64,
        })
    }

    /// A throttle clip: a grid of 40 levels between the median and the largest throttle of the
    /// estimation part (other parameters held, gain, offset and linear terms by least squares),
    /// a finer grid of 21 around the best, then Levenberg–Marquardt with the level held.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let mut u: Vec<f64> = ctx.sig.u[ctx.est.clone()]
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        u.sort_by(|a, b| a.total_cmp(b));
        let lo = *u.get(u.len() / 2)?;
        let hi = *u.last()?;
        if hi - lo <= 1e-9 {
            return None;
        }
        let clip = |level: f64| SaturationParams {
            level,
            clipped: Clipped::Throttle,
        };
        let score = |l: f64| {
            let (q, e) = linear_refit(&cur.model.with(clip(l)), &ctx.sig, ctx.est.clone());
            (e, q)
        };
        let step = (hi - lo) / 40.0;
        let mut best = (f64::INFINITY, cur.model.clone(), hi);
        for i in 0..40 {
            let l = lo + step * i as f64;
            let (e, q) = score(l);
            if e < best.0 {
                best = (e, q, l);
            }
        }
        let centre = best.2;
        for i in -10..=10 {
            let l = centre + step * 0.1 * i as f64;
            let (e, q) = score(l);
            if e < best.0 {
                best = (e, q, l);
            }
        }
        Some(ctx.lm(&best.1.with(clip(best.2)), 30))
    }
}

impl Term for SaturationParams {
    fn name(&self) -> &'static str {
        NAME
    }

    fn place(&self) -> Place {
        match self.clipped {
            Clipped::Throttle => Place::InputLimit,
            Clipped::Sensor { .. } => Place::OutputLimit,
        }
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    fn shape_input(&self, v: &mut [f64], _sig: &Signals) {
        for x in v.iter_mut() {
            *x = x.min(self.level);
        }
    }

    fn shape_output(&self, y: &mut [f64], _sig: &Signals) {
        for yk in y.iter_mut() {
            *yk = yk.min(self.level);
        }
    }

    fn terms(&self, _dt_s: f64, terms: &mut Map<String, Value>) {
        let key = match self.clipped {
            Clipped::Throttle => "throttle_clip",
            Clipped::Sensor { .. } => "sensor_clip",
        };
        terms.insert(key.into(), json!(self.level));
    }

    fn finding_params(&self, _dt_s: f64) -> Map<String, Value> {
        let signal = match self.clipped {
            Clipped::Throttle => "throttle",
            Clipped::Sensor { .. } => "sensor",
        };
        to_map(Published {
            level: self.level,
            signal,
        })
    }

    fn evidence(&self, _core: &Core, ctx: &Ctx, drop: &str) -> String {
        let l = self.level;
        match self.clipped {
            Clipped::Sensor { samples } => format!(
                "the output reads exactly {l:.6} on {samples} of {} estimation samples and never \
                 more: the sensor clips there (flat tops where the response should peak)",
                ctx.est.len()
            ),
            Clipped::Throttle => {
                let above = ctx.sig.u.iter().filter(|&&x| x > l).count();
                format!(
                    "throttle above {l:.3} gives no more thrust ({above} samples above that \
                     level respond as if at it); with the throttle clipped there {drop}"
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = SaturationParams {
            level: 0.65,
            clipped: Clipped::Throttle,
        };
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(
            text(&p.finding_params(0.002)),
            r#"{"level":0.65,"signal":"throttle"}"#
        );
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(text(&terms), r#"{"throttle_clip":0.65}"#);
    }

    #[test]
    fn a_sensor_clip_is_published_as_such() {
        let p = SaturationParams {
            level: 12.5,
            clipped: Clipped::Sensor { samples: 40 },
        };
        assert_eq!(p.place(), Place::OutputLimit);
        let text = serde_json::to_string(&p.finding_params(0.002)).unwrap();
        assert_eq!(text, r#"{"level":12.5,"signal":"sensor"}"#);
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(
            serde_json::to_string(&terms).unwrap(),
            r#"{"sensor_clip":12.5}"#
        );
    }
}
