//! `asymmetric_dynamics`: spin-up and spin-down differ.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/effects/asymmetric_dynamics.rs`.

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::Ctx;
use crate::effect::Effect;
use crate::fit::Fit;
use crate::signals::Core;
use crate::term::{to_map, Place, Scale, Term};
use propid_numerics::discretise::discretise_second_order;
use propid_numerics::nonlinear_core::CoreLaw;
use propid_numerics::step_response::{step_figures, Step};
use propid_numerics::EffectName;

/// The published name.
pub const NAME: EffectName = EffectName::AsymmetricDynamics;
/// Largest plausible ratio of the two time scales.
pub const MAX_RATIO: f64 = 10.0;
/// Least share of the input's movement each direction must have in the estimation part
/// (`Σ max(Δu, 0)` against `Σ max(−Δu, 0)`): a time scale of falling back cannot be told from
/// a record whose command (almost) never falls, nor one of rising from a command that never
/// rises — there the "asymmetry" would only reshape the settling after one kind of step.
pub const MIN_DIRECTION_SHARE: f64 = 0.2;

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct AsymmetricDynamics;

/// The fitted asymmetry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AsymmetricDynamicsParams {
    /// `r = ln(down / up)`, the logarithm of the ratio of the time scales (0: symmetric).
    pub log_ratio: f64,
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// Time scale while the output is driven up, relative to the core's (dimensionless).
    up: f64,
    /// Time scale while the output falls back, relative to the core's (dimensionless).
    down: f64,
    /// `down / up`: > 1 falls back more slowly than it rises.
    down_over_up: f64,
}

impl Effect for AsymmetricDynamics {
    fn name(&self) -> EffectName {
        NAME
    }

    /// Needs a throttle-like input (never negative) that both rises and falls in the
    /// estimation part ([`MIN_DIRECTION_SHARE`]). Starts at `down / up` = 1/2.5, 1/1.6, 1.6
    /// and 2.5; Levenberg–Marquardt from the two best.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let u = &ctx.sig.u[ctx.est.clone()];
        let throttle_like = u.iter().all(|&x| x >= 0.0);
        if !throttle_like || !both_directions(u) {
            return None;
        }
        let starts = [1.0 / 2.5, 1.0 / 1.6, 1.6, 2.5].map(|ratio: f64| {
            cur.model.with(AsymmetricDynamicsParams {
                log_ratio: ratio.ln(),
            })
        });
        Some(ctx.best_of(starts, 2))
    }
}

impl Term for AsymmetricDynamicsParams {
    fn name(&self) -> EffectName {
        NAME
    }

    fn place(&self) -> Place {
        Place::Core
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    /// A ratio within 1/10..10, and step time constants up and down (of the fitted core,
    /// [`time_constant_s`]) that differ by at least one sample period: a smaller difference is
    /// below what the record resolves (as `identify` calls a time constant below one sample
    /// unresolvable).
    fn plausible(&self, ctx: &Ctx, core: &Core, has_nan: bool) -> bool {
        if has_nan || self.log_ratio.abs() > MAX_RATIO.ln() {
            return false;
        }
        let tau = |scale: f64| time_constant_s(core.fn_hz / scale, core.zeta);
        match (tau(self.up()), tau(self.down())) {
            // The difference must show on the sample grid, and neither direction may be
            // faster than half a sample (a time constant the record cannot resolve).
            (Some(up), Some(down)) => {
                (down - up).abs() >= ctx.sig.dt_s && up.min(down) >= 0.5 * ctx.sig.dt_s
            }
            _ => false,
        }
    }

    fn core_law(&self, law: &mut CoreLaw) {
        law.up_scale = self.up();
        law.down_scale = self.down();
    }

    fn free(&self) -> Vec<(f64, Scale)> {
        vec![(self.log_ratio, Scale::Linear)]
    }

    fn set_free(&mut self, values: &[f64]) {
        self.log_ratio = values[0];
    }

    fn terms(&self, _dt_s: f64, terms: &mut Map<String, Value>) {
        terms.insert("up".into(), json!(self.up()));
        terms.insert("down".into(), json!(self.down()));
    }

    fn finding_params(&self, _dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            up: self.up(),
            down: self.down(),
            down_over_up: self.log_ratio.exp(),
        })
    }

    fn evidence(&self, core: &Core, _ctx: &Ctx, drop: &str) -> String {
        let tau = |scale: f64| {
            time_constant_s(core.fn_hz / scale, core.zeta)
                .map_or("unresolved".to_string(), |t| format!("{:.1} ms", 1e3 * t))
        };
        let how = if self.log_ratio > 0.0 {
            "more slowly"
        } else {
            "faster"
        };
        format!(
            "spin-up and spin-down differ: the output falls back {how} than it rises \
             (time scales ×{:.2} up, ×{:.2} down; step time constants {} up, {} down); \
             with a time scale per direction {drop}",
            self.up(),
            self.down(),
            tau(self.up()),
            tau(self.down())
        )
    }
}

impl AsymmetricDynamicsParams {
    /// Time scale while driven up, `e^(−r/2)`.
    pub fn up(&self) -> f64 {
        (-0.5 * self.log_ratio).exp()
    }

    /// Time scale while falling back, `e^(r/2)`.
    pub fn down(&self) -> f64 {
        (0.5 * self.log_ratio).exp()
    }
}

/// Whether the input moves both ways: each direction's total movement at least
/// [`MIN_DIRECTION_SHARE`] of the other's.
pub fn both_directions(u: &[f64]) -> bool {
    let (mut rise, mut fall) = (0.0, 0.0);
    for w in u.windows(2) {
        let d = w[1] - w[0];
        if d > 0.0 {
            rise += d;
        } else {
            fall -= d;
        }
    }
    rise > 0.0 && fall >= MIN_DIRECTION_SHARE * rise && rise >= MIN_DIRECTION_SHARE * fall
}

/// The time constant of the unit step response of `T'' + 2ζωn T' + ωn² T = ωn² v`, seconds,
/// by the two-point fit of [`step_figures`] (sampled 200 times per `1/fn`, for 10 time
/// constants of its slowest pole); `None` when it does not resolve.
pub fn time_constant_s(fn_hz: f64, zeta: f64) -> Option<f64> {
    if !(fn_hz.is_finite() && fn_hz > 0.0 && zeta.is_finite() && zeta > 0.0) {
        return None;
    }
    let dt = 1.0 / (200.0 * fn_hz);
    let wn = std::f64::consts::TAU * fn_hz;
    let slow = if zeta < 1.0 {
        zeta * wn
    } else {
        wn * (zeta - (zeta * zeta - 1.0).sqrt())
    };
    let n = ((10.0 / slow / dt).ceil() as usize).clamp(400, 200_000);
    let (a, b) = discretise_second_order(fn_hz, zeta, 1.0, dt);
    let pre = 20;
    let mut x = nalgebra::Vector2::zeros();
    let y: Vec<f64> = (0..pre + n)
        .map(|k| {
            let yk = x[0];
            x = a * x + b * if k >= pre { 1.0 } else { 0.0 };
            yk
        })
        .collect();
    let step = Step {
        before_start: 0,
        at: pre,
        after_end: pre + n,
        from: 0.0,
        to: 1.0,
    };
    step_figures(&y, dt, &step).time_constant_s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;

    #[test]
    fn a_direction_faster_than_half_a_sample_is_implausible() {
        use crate::signals::Core;
        // Down 9× slower than up around an 8 Hz core: spin-up τ ≈ 7 ms, spin-down ≈ 60 ms.
        let p = AsymmetricDynamicsParams {
            log_ratio: 9.0f64.ln(),
        };
        let model = Model::new(Core {
            fn_hz: 8.0,
            zeta: 0.7,
            ..Core::default()
        })
        .with(p);
        let (u, y) = (vec![0.5; 10], vec![0.0; 10]);
        let plausible_at =
            |dt_s: f64| p.plausible(&Ctx::whole(dt_s, &u, &y), &model.core, model.has_nan());
        // At 50 Hz the spin-up is faster than half a sample (10 ms): not resolvable; at 200 Hz
        // it is, and the directions differ by more than a sample.
        assert!(!plausible_at(0.02));
        assert!(plausible_at(0.005));
    }

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = AsymmetricDynamicsParams {
            log_ratio: 4.0f64.ln(),
        };
        let m = p.finding_params(0.002);
        assert_eq!(m.keys().collect::<Vec<_>>(), ["down", "down_over_up", "up"]);
        let get = |k: &str| m[k].as_f64().unwrap();
        assert!((get("up") - 0.5).abs() < 1e-12 && (get("down") - 2.0).abs() < 1e-12);
        assert!((get("down_over_up") - 4.0).abs() < 1e-12);
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(terms.keys().collect::<Vec<_>>(), ["down", "up"]);
    }

    #[test]
    fn a_staircase_that_only_rises_has_no_fall_to_time() {
        let stairs: Vec<f64> = (0..100).map(|k| 0.1 + 0.01 * (k / 10) as f64).collect();
        assert!(!both_directions(&stairs));
        let mut pulses = stairs.clone();
        pulses.extend((0..10).map(|k| 0.5 - 0.04 * k as f64));
        assert!(both_directions(&pulses));
        assert!(!both_directions(&[0.3; 10]));
    }

    #[test]
    fn a_first_order_like_core_has_the_time_constant_of_its_slow_pole() {
        // ζ = 5: poles −ωn (5 ± √24); the slow one dominates, τ ≈ 1/(ωn (5 − √24)) · (1 + small).
        let (fn_hz, zeta) = (2.0, 5.0);
        let wn = std::f64::consts::TAU * fn_hz;
        let slow = 1.0 / (wn * (zeta - (zeta * zeta - 1.0f64).sqrt()));
        let tau = time_constant_s(fn_hz, zeta).unwrap();
        assert!((tau - slow).abs() < 0.03 * slow, "{tau} vs {slow}");
        // Twice the time scale, twice the time constant.
        let t2 = time_constant_s(fn_hz / 2.0, zeta).unwrap();
        assert!((t2 / tau - 2.0).abs() < 0.01);
    }
}
