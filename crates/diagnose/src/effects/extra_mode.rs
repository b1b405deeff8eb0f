//! `extra_mode`: a resonance in series after the core (the load-cell path, the stand's
//! structure): `s = (1 − g) T + g m` with `m'' + 2ζ_m ω_m m' + ω_m² m = ω_m² T`, discretised
//! exactly like the core; the model becomes 4th order.

use nalgebra::Vector2;
use propid_numerics::discretise::discretise_second_order;
use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::Ctx;
use crate::effect::Effect;
use crate::fit::Fit;
use crate::linear_part::{second_order_poles, LinearPart};
use crate::model::max_freq_hz;
use crate::signals::Core;
use crate::spectrum::peaks;
use crate::term::{to_map, Place, Scale, Term};
use propid_numerics::EffectName;

/// The published name.
pub const NAME: EffectName = EffectName::ExtraMode;

/// Largest plausible share `g` of the output through the mode. The path's numerator is
/// `(1 − g) s² + 2ζ_m ω_m (1 − g) s + ω_m²`: for `g > 1` its `s²` coefficient is negative and it
/// has a zero in the right half plane, so the modelled output first moves *against* a step
/// (an inverse response, `−(g − 1)` of the step at once). A structure or load cell in series
/// with the thrust (a mass on a spring: `g = 1`; part of the force around it: `g < 1`) has no
/// such zero; a fitted `g > 1` is the first-order Padé approximation of a delay, a stand-in for
/// a dead time (Bitcraze's cf21 log with a delay hidden in it fitted `g = 1.44` at 2 Hz, where
/// the thrust shows no ringing and no inverse response). The 5 % above 1 leaves room for the fit's
/// own scatter around a true `g = 1` (an inverse response of at most 5 % of the step).
pub const MAX_SHARE: f64 = 1.05;

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct ExtraMode;

/// The fitted mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtraModeParams {
    /// Natural frequency `f_m = ω_m / 2π`, Hz.
    pub fn_hz: f64,
    /// Damping ratio `ζ_m`.
    pub zeta: f64,
    /// Share `g` of the output that goes through the mode (dimensionless, plausible within
    /// (0, [`MAX_SHARE`]]).
    pub gain: f64,
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// Natural frequency, Hz.
    fn_hz: f64,
    /// Share of the output through the mode.
    gain: f64,
    /// Damping ratio.
    zeta: f64,
}

impl Effect for ExtraMode {
    fn name(&self) -> EffectName {
        NAME
    }

    /// Starts at the three strongest peaks of the residual spectrum above 1.5 `fn` and at 2, 4,
    /// 8 and 16 `fn` (below 0.9 Nyquist), each with damping 0.03 and 0.15 and share 1;
    /// Levenberg–Marquardt from the two best.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let dt = ctx.sig.dt_s;
        let fmax = max_freq_hz(dt);
        let f_core = cur.model.core.fn_hz;
        let lo = (1.5 * f_core).min(0.5 * fmax);
        let mut freqs: Vec<f64> = peaks(&ctx.residual(cur), dt, lo, 0.95 * fmax, 3)
            .into_iter()
            .map(|p| p.0)
            .collect();
        freqs.extend([2.0, 4.0, 8.0, 16.0].map(|m| (m * f_core).min(0.9 * fmax)));
        let mut starts = Vec::new();
        for fn_hz in freqs {
            for zeta in [0.03, 0.15] {
                starts.push(cur.model.with(ExtraModeParams {
                    fn_hz,
                    zeta,
                    gain: 1.0,
                }));
            }
        }
        Some(ctx.best_of(starts, 2))
    }
}

impl Term for ExtraModeParams {
    fn name(&self) -> EffectName {
        NAME
    }

    fn place(&self) -> Place {
        Place::Series
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    /// A mode below 0.95 Nyquist with damping within 0.002..5 and a share within (0,
    /// [`MAX_SHARE`]] (no inverse response: see there).
    fn plausible(&self, ctx: &Ctx, _core: &Core, _has_nan: bool) -> bool {
        let fmax = max_freq_hz(ctx.sig.dt_s);
        (self.fn_hz > 0.0 && self.fn_hz < 0.95 * fmax)
            && (0.002..=5.0).contains(&self.zeta)
            && self.gain > 0.0
            && self.gain <= MAX_SHARE
    }

    /// `s_k = (1 − g) T_k + g m_k[0]`, `m_{k+1} = A_m m_k + B_m T_k`, `m_0 = [T_0, 0]`.
    fn filter(&self, s: &mut [f64], dt_s: f64) {
        let Some(&first) = s.first() else {
            return;
        };
        let fmax = max_freq_hz(dt_s);
        let (am, bm) = discretise_second_order(
            self.fn_hz.clamp(1e-6, fmax),
            self.zeta.clamp(1e-4, 50.0),
            1.0,
            dt_s,
        );
        let g = self.gain;
        let mut m = Vector2::new(first, 0.0);
        for sk in s.iter_mut() {
            let thrust = *sk;
            *sk = (1.0 - g) * thrust + g * m[0];
            m = am * m + bm * thrust;
        }
    }

    fn free(&self) -> Vec<(f64, Scale)> {
        vec![
            (self.fn_hz, Scale::Log),
            (self.zeta, Scale::Log),
            (self.gain, Scale::Linear),
        ]
    }

    fn set_free(&mut self, values: &[f64]) {
        self.fn_hz = values[0];
        self.zeta = values[1];
        self.gain = values[2];
    }

    /// Appends the mode's two states: `A = [[A_p, 0], [B_m C_p, A_m]]`, `B = [B_p; 0]`,
    /// `C = [(1 − g) C_p, g, 0]` (structural zeros stay exact zeros).
    fn extend_linear(&self, lin: &mut LinearPart, dt_s: f64) {
        let (am, bm) = discretise_second_order(self.fn_hz, self.zeta, 1.0, dt_s);
        let g = self.gain;
        let times = |a: f64, b: f64| if b == 0.0 { 0.0 } else { a * b };
        let c_prev = lin.c.first().cloned().unwrap_or_default();
        for row in lin.a.iter_mut() {
            row.extend([0.0, 0.0]);
        }
        for i in 0..2 {
            let mut row: Vec<f64> = c_prev.iter().map(|&c| times(bm[i], c)).collect();
            row.extend([am[(i, 0)], am[(i, 1)]]);
            lin.a.push(row);
            lin.b.push(vec![0.0; lin.b.first().map_or(1, |r| r.len())]);
        }
        if let Some(c) = lin.c.first_mut() {
            *c = c_prev.iter().map(|&x| times(1.0 - g, x)).collect();
            c.extend([g, 0.0]);
        }
        lin.poles_s
            .extend(second_order_poles(self.fn_hz, self.zeta));
    }

    fn terms(&self, _dt_s: f64, terms: &mut Map<String, Value>) {
        terms.insert("mode_fn_hz".into(), json!(self.fn_hz));
        terms.insert("mode_zeta".into(), json!(self.zeta));
        terms.insert("mode_gain".into(), json!(self.gain));
    }

    fn finding_params(&self, _dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            fn_hz: self.fn_hz,
            gain: self.gain,
            zeta: self.zeta,
        })
    }

    fn evidence(&self, _core: &Core, _ctx: &Ctx, drop: &str) -> String {
        format!(
            "the residual rings at {:.2} Hz (damping {:.3}) after every input change, which a \
             2nd-order model cannot produce; with a series mode there (4th order) {drop}",
            self.fn_hz, self.zeta
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_published_linear_part_is_the_series_connection() {
        let mut lin = LinearPart {
            a: vec![vec![0.9, 0.1], vec![-0.2, 0.8]],
            b: vec![vec![0.5], vec![0.25]],
            c: vec![vec![1.0, 0.0]],
            poles_s: vec![[-1.0, 2.0], [-1.0, -2.0]],
        };
        let mode = ExtraModeParams {
            fn_hz: 30.0,
            zeta: 0.05,
            gain: 1.5,
        };
        mode.extend_linear(&mut lin, 2e-3);
        let (am, bm) = discretise_second_order(30.0, 0.05, 1.0, 2e-3);
        assert_eq!(lin.a[0], [0.9, 0.1, 0.0, 0.0]);
        assert_eq!(lin.a[2], [bm[0], 0.0, am[(0, 0)], am[(0, 1)]]);
        assert_eq!(lin.a[3], [bm[1], 0.0, am[(1, 0)], am[(1, 1)]]);
        assert_eq!(lin.b, [[0.5], [0.25], [0.0], [0.0]]);
        // (1 − g) · 0 stays +0, not −0, though 1 − g < 0.
        assert_eq!(lin.c[0], [-0.5, 0.0, 1.5, 0.0]);
        assert!(lin.c[0][1].is_sign_positive());
        assert_eq!(lin.poles_s.len(), 4);
    }

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = ExtraModeParams {
            fn_hz: 40.0,
            zeta: 0.05,
            gain: 1.0,
        };
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(
            text(&p.finding_params(0.002)),
            r#"{"fn_hz":40.0,"gain":1.0,"zeta":0.05}"#
        );
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(
            text(&terms),
            r#"{"mode_fn_hz":40.0,"mode_gain":1.0,"mode_zeta":0.05}"#
        );
    }
}
