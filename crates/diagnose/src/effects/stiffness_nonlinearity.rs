//! `stiffness_nonlinearity`: a hardening or softening spring, a cubic restoring term in the core
//! (the Silverbox benchmark, Wigren & Schoukens 2013):
//!
//! ```text
//!   m y'' + d y' + k1 y + k3 y³ = u   ⇔   T'' + 2ζωn T' + ωn² (T + ε T³) = ωn² K v,  ε = k3/k1
//! ```
//!
//! with `T = ŷ − c` the displacement from the rest position (the output at zero input, the
//! model's offset `c`). Its signature is not a static map: the small-signal stiffness
//! `k1 (1 + 3 ε T²)` — so the resonance and the gain — moves with the displacement; the steady
//! output follows `T + ε T³ = K v`. Stepped by [`propid_numerics::nonlinear_core`].

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::Ctx;
use crate::effect::Effect;
use crate::fit::Fit;
use crate::signals::Core;
use crate::term::{to_map, Place, Scale, Term};
use propid_numerics::nonlinear_core::CoreLaw;
use propid_numerics::EffectName;

/// The published name.
pub const NAME: EffectName = EffectName::StiffnessNonlinearity;
/// Plausible range of the small-signal stiffness factor `1 + 3 ε T²` at the largest
/// displacement of the data (below: a softening spring near its fold, where the core has no
/// steady state; above: a term that is no longer a correction).
pub const STIFFNESS_FACTOR: std::ops::RangeInclusive<f64> = 0.2..=20.0;
/// Smallest change `|3 ε T²|` of the small-signal stiffness at the largest displacement of the
/// data that names a spring: a cubic term that moves the stiffness by less over everything
/// the record shows is no spring's, it absorbs another misfit (measured: on a simulated 100 Hz
/// motor stand with a supply sag hidden on its thrust, a softening "spring" of −1.6 % at the
/// largest thrust, −0.4 % at the RMS, raised the held-out fit by 0.5 pp and took the place of
/// the stand's own dead time). The detection table's springs move it by 15 % and more.
pub const MIN_STIFFNESS_CHANGE: f64 = 0.03;

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct StiffnessNonlinearity;

/// The fitted cubic term.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StiffnessNonlinearityParams {
    /// `ε = k3 / k1`, per output unit squared (> 0 hardens, < 0 softens).
    pub k3_per_k1: f64,
    /// `Y²`: the mean square displacement `(y − c)²` of the estimation samples when the term
    /// was started, output units squared; the fit moves `ε Y²` (dimensionless), and the finding
    /// reports the stiffening at `T = Y`.
    pub scale_sq: f64,
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// `"hardens"` (ε > 0) or `"softens"`.
    curvature: &'static str,
    /// `ε = k3 / k1`, per output unit squared.
    k3_per_k1: f64,
    /// Change of the small-signal stiffness at the RMS displacement, `300 ε Y²`, percent.
    stiffening_pct_at_rms: f64,
}

impl Effect for StiffnessNonlinearity {
    fn name(&self) -> EffectName {
        NAME
    }

    /// Starts at `ε Y²` = −0.1, −0.03, 0.03, 0.1 and 0.3 with `Y²` the mean square of the output
    /// about the current model's offset; Levenberg–Marquardt from the two best.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let c = cur.model.core.offset;
        let (mut s2, mut n) = (0.0, 0usize);
        for &y in ctx.sig.y[ctx.est.clone()].iter().filter(|v| v.is_finite()) {
            s2 += (y - c) * (y - c);
            n += 1;
        }
        let scale_sq = s2 / n.max(1) as f64;
        if !(scale_sq.is_finite() && scale_sq > 0.0) {
            return None;
        }
        let starts = [-0.1, -0.03, 0.03, 0.1, 0.3].map(|s| {
            cur.model.with(StiffnessNonlinearityParams {
                k3_per_k1: s / scale_sq,
                scale_sq,
            })
        });
        Some(ctx.best_of(starts, 2))
    }
}

impl Term for StiffnessNonlinearityParams {
    fn name(&self) -> EffectName {
        NAME
    }

    fn place(&self) -> Place {
        Place::Core
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    /// The stiffness factor `1 + 3 ε T²` at the largest displacement `|y − c|` of the
    /// estimation samples within [`STIFFNESS_FACTOR`], and at least
    /// [`MIN_STIFFNESS_CHANGE`] away from 1.
    fn plausible(&self, ctx: &Ctx, core: &Core, has_nan: bool) -> bool {
        let c = core.offset;
        let t_max = ctx.sig.y[ctx.est.clone()]
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, &y| m.max((y - c).abs()));
        let change = 3.0 * self.k3_per_k1 * t_max * t_max;
        !has_nan
            && STIFFNESS_FACTOR.contains(&(1.0 + change))
            && change.abs() >= MIN_STIFFNESS_CHANGE
    }

    fn core_law(&self, law: &mut CoreLaw) {
        law.cubic = self.k3_per_k1;
    }

    fn free(&self) -> Vec<(f64, Scale)> {
        vec![(self.k3_per_k1 * self.scale_sq, Scale::Linear)]
    }

    fn set_free(&mut self, values: &[f64]) {
        self.k3_per_k1 = values[0] / self.scale_sq;
    }

    fn terms(&self, _dt_s: f64, terms: &mut Map<String, Value>) {
        terms.insert("k3_per_k1".into(), json!(self.k3_per_k1));
    }

    fn finding_params(&self, _dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            curvature: self.curvature(),
            k3_per_k1: self.k3_per_k1,
            stiffening_pct_at_rms: 300.0 * self.k3_per_k1 * self.scale_sq,
        })
    }

    fn evidence(&self, core: &Core, _ctx: &Ctx, drop: &str) -> String {
        let y = self.scale_sq.sqrt();
        let k1 = 1.0 / core.gain;
        format!(
            "the resonance and the gain move with the displacement: a spring that {} \
             (k3/k1 = {} per output unit², k3 = {} with k1 = 1/K = {}; the small-signal \
             stiffness is {:+.1} % at the RMS displacement {}); with the cubic term in the core \
             {drop}",
            self.curvature(),
            sig4(self.k3_per_k1),
            sig4(self.k3_per_k1 * k1),
            sig4(k1),
            300.0 * self.k3_per_k1 * self.scale_sq,
            sig4(y)
        )
    }
}

/// `x` with four significant digits (in scientific notation outside 0.001..100 000).
fn sig4(x: f64) -> String {
    let mag = if x == 0.0 || !x.is_finite() {
        0
    } else {
        x.abs().log10().floor() as i32
    };
    if (-3..5).contains(&mag) {
        format!("{x:.*}", (3 - mag).max(0) as usize)
    } else {
        format!("{x:.3e}")
    }
}

impl StiffnessNonlinearityParams {
    /// `"hardens"` for `ε > 0`, else `"softens"`.
    pub fn curvature(&self) -> &'static str {
        if self.k3_per_k1 > 0.0 {
            "hardens"
        } else {
            "softens"
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = StiffnessNonlinearityParams {
            k3_per_k1: 0.5,
            scale_sq: 0.1,
        };
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(
            text(&p.finding_params(0.002)),
            r#"{"curvature":"hardens","k3_per_k1":0.5,"stiffening_pct_at_rms":15.0}"#
        );
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(text(&terms), r#"{"k3_per_k1":0.5}"#);
    }

    #[test]
    fn the_fit_moves_the_dimensionless_coefficient() {
        let mut p = StiffnessNonlinearityParams {
            k3_per_k1: 0.5,
            scale_sq: 0.1,
        };
        assert!((p.free()[0].0 - 0.05).abs() < 1e-15);
        p.set_free(&[-0.02]);
        assert!((p.k3_per_k1 + 0.2).abs() < 1e-12);
        assert_eq!(p.curvature(), "softens");
    }
}
