//! `saturation`: the throttle or the sensor clips. A throttle clip `v ← min(v, L)` acts before
//! the static map (more command gives no more thrust); a sensor clip `ŷ ← min(ŷ, Y)` is the
//! last step (readings above `Y` read `Y`). A sensor clip is recognised straight from the data
//! (a flat top at the largest reading) before any fit; a throttle clip is fitted.

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::Ctx;
use crate::effect::{Detected, Effect};
use crate::fit::{linear_refit, Fit};
use crate::signals::{Core, Signals};
use crate::term::{to_map, Place, Term};
use propid_numerics::EffectName;

/// The published name.
pub const NAME: EffectName = EffectName::Saturation;

/// Distinct values under a flat top that must be a continuous signal's ([`Saturation`]'s
/// detection).
pub const UNDER_TOP: usize = 3;
/// Most occurrences of each of them.
pub const UNDER_TOP_REPEATS: usize = 2;

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
    fn name(&self) -> EffectName {
        NAME
    }

    /// A sensor clip: the largest reading of the estimation part repeats on at least 20
    /// samples and 0.5 % of them (a flat top), and the readings just under it are a continuous
    /// signal's: each of the [`UNDER_TOP`] largest values below the top occurs at most
    /// [`UNDER_TOP_REPEATS`] times (a signal cut off at the top). A level settled onto from
    /// below and rounded (a noise-free log's `5.999999` nine times under its `6.0`) or a
    /// quantised load cell resting on its top code (whose neighbouring codes repeat as often)
    /// repeats its top as well, and is no clip. Its score is the number of clipped samples.
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
        let mut under: Vec<f64> = ys
            .iter()
            .copied()
            .filter(|v| v.is_finite() && top - *v > tol)
            .collect();
        under.sort_by(|a, b| b.total_cmp(a));
        let mut repeats: Vec<(f64, usize)> = Vec::new();
        for v in under {
            let same = repeats.last().is_some_and(|&(last, _)| last - v <= tol);
            if same {
                if let Some((_, n)) = repeats.last_mut() {
                    *n += 1;
                }
            } else if repeats.len() == UNDER_TOP {
                break;
            } else {
                repeats.push((v, 1));
            }
        }
        let cut_off = repeats.iter().all(|&(_, n)| n <= UNDER_TOP_REPEATS);
        (count >= 20 && count * 200 >= ys.len() && cut_off).then(|| Detected {
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
    fn name(&self) -> EffectName {
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

    /// A noisy response cut off at 5.0 is a clip; the same level settled onto from below
    /// without noise (rounded to 6 decimals), or a load cell quantised to 0.01 resting on its
    /// top code, repeats its top as often and is none.
    #[test]
    fn a_flat_top_is_a_clip_only_when_the_signal_under_it_is_continuous() {
        let n = 2000;
        let u = vec![0.5; n];
        let noise = propid_testkit::gaussian(n, 0.05, 7);
        let detect = |y: &[f64]| Saturation.detect(&Ctx::whole(0.01, &u, y)).is_some();
        let wave: Vec<f64> = (0..n)
            .map(|k| 4.5 + (k as f64 * 0.02).sin() + noise[k])
            .collect();
        let clipped: Vec<f64> = wave.iter().map(|v| v.min(5.0)).collect();
        assert!(detect(&clipped));
        let settled: Vec<f64> = (0..n)
            .map(|k| {
                let v = 6.0 * (1.0 - (-(k as f64) / 80.0).exp());
                (v * 1e6).round() / 1e6
            })
            .collect();
        assert!(!detect(&settled));
        let coded: Vec<f64> = (0..n)
            .map(|k| ((6.0 + 0.004 * noise[k] / 0.05) / 0.01).round() * 0.01)
            .collect();
        assert!(!detect(&coded));
    }
}
