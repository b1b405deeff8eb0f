//! `supply_sag`: the gain follows the supply voltage (a sagging battery gives less thrust per unit
//! throttle): `v ← v · (1 + g_V (V_k − V_r))` with `V_r` the mean voltage of the record (the
//! voltage is a measured input, known on every sample).
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/effects/supply_sag.rs`.

use crate::thresholds::{EXPONENT_MAX, SCORE_THRESHOLD};
use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::measured_estimation_samples;
use crate::ctx::Ctx;
use crate::effect::Effect;
use crate::fit::Fit;
use crate::model::{simulate, Model};
use crate::signals::{Core, Signals};
use crate::term::{to_map, Place, Scale, Term};
use crate::verdict::{Warning, WarningKind};
use propid_numerics::EffectName;

/// The published name.
pub const NAME: EffectName = EffectName::SupplySag;

/// Exponents `n` of the starts `g_V = n / V_r` (thrust ∝ V^1–2 on a motor; one negative start).
pub const START_EXPONENTS: [f64; 4] = [-1.0, 0.5, 1.5, 4.0];

/// Score `n ln(SSE_drive / SSE_output)` by which the output must fit better than the drive to
/// be taken as what the supply scales (2: a likelihood ratio of e).
pub const OUTPUT_SCORE: f64 = 2.0;
/// Score by which the term on both sides, its output share fitted, must fit better than the
/// better side alone (one parameter more; a likelihood ratio of e⁵).
pub const BOTH_SCORE: f64 = 10.0;

/// The `supply_sag_unidentifiable` warning of model `model` (`"baseline"` or `"extended"`)
/// when `d.score`, the most a propeller-strong supply term driven by the voltage's own
/// variation could score on it ([`detectability`]), is below
/// [`SCORE_THRESHOLD`].
fn supply_sag_warning(d: &Detectability, model: &'static str) -> Option<Warning> {
    (d.score < SCORE_THRESHOLD).then(|| Warning {
        kind: WarningKind::SupplySagUnidentifiable,
        message: format!(
            "supply sag not identifiable: the supply voltage varies by {:.3} V RMS beyond what \
             the throttle explains; even with thrust ∝ V^{EXPONENT_MAX} that would change the \
             output by {:.2} % RMS, which would score {:.0} < {SCORE_THRESHOLD} above the {model} \
             model's residual ({:.1} % RMS of the output): a sag can be neither found nor ruled \
             out in this record (the voltage's variation with the throttle cannot be told from \
             the thrust curve). A supply that discharges across repeated levels, or is stepped, \
             would show it",
            d.own_rms_v,
            100.0 * d.relative_change,
            d.score,
            100.0 * d.relative_residual,
        ),
        model,
        value: d.score,
        band_hz: None,
    })
}

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct SupplySag;

/// What the voltage's own variation could show ([`detectability`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detectability {
    /// The score `n ln(1 + Σ δ² / SSE)` a supply term of exponent [`EXPONENT_MAX`] driven by it
    /// would reach on top of the fit.
    pub score: f64,
    /// RMS of the voltage's own variation `V − V̂(u)`, V.
    pub own_rms_v: f64,
    /// RMS of the change `δ` that term would make, relative to the RMS of the output `ŷ − c`.
    pub relative_change: f64,
    /// RMS of the fit's residual, relative to the RMS of the output `ŷ − c`.
    pub relative_residual: f64,
}

/// The module doc's bound on `fit` over the measured estimation samples; `None` without a
/// voltage channel, with no measured estimation sample or a fit with no residual.
pub fn detectability(ctx: &Ctx, fit: &Fit) -> Option<Detectability> {
    let volt = ctx.sig.voltage?;
    let ks = measured_estimation_samples(ctx, 0);
    if ks.is_empty() || fit.sse.is_nan() || fit.sse <= 0.0 {
        return None;
    }
    let vhat = voltage_from_throttle(ctx.sig.u, volt);
    let mut sim = vec![0.0; ctx.sig.u.len()];
    simulate(&fit.model, &ctx.sig, &mut sim);
    let g = EXPONENT_MAX / ctx.sig.v_ref.abs().max(1e-6);
    let c = fit.model.core.offset;
    let (mut d2, mut v2, mut y2) = (0.0, 0.0, 0.0);
    for &k in &ks {
        let own = volt[k] - vhat[k];
        d2 += ((sim[k] - c) * g * own).powi(2);
        v2 += own * own;
        y2 += (sim[k] - c).powi(2);
    }
    let n = ks.len() as f64;
    let relative = |x: f64| {
        if y2 > 0.0 {
            (x / y2).sqrt()
        } else {
            f64::INFINITY
        }
    };
    Some(Detectability {
        score: n * (d2 / fit.sse).ln_1p(),
        own_rms_v: (v2 / n).sqrt(),
        relative_change: relative(d2),
        relative_residual: relative(fit.sse),
    })
}

/// What the supply voltage scales (module doc, **Which side**).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scaled {
    /// The drive, before the dynamics: the motor's speed follows the voltage through its own
    /// lag.
    Drive,
    /// The measured output at once, after the dynamics.
    Output,
    /// Both, the output's share fitted.
    Both,
}

impl Scaled {
    /// The published word.
    pub fn word(self) -> &'static str {
        match self {
            Scaled::Drive => "drive",
            Scaled::Output => "output",
            Scaled::Both => "drive_and_output",
        }
    }
}

/// The fitted voltage dependence: `(1 + (1 − s) g_V ΔV)` on the drive and `(1 + s g_V ΔV)` on
/// the output, `ΔV = V − V_r`; to first order in `g_V ΔV` a steady output changes by `g_V ΔV`
/// whatever the share `s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupplySagParams {
    /// Relative gain change per volt `g_V`, 1/V.
    pub gain_per_volt: f64,
    /// What it scales.
    pub scales: Scaled,
    /// The share `s` on the output: 0 on the drive, 1 on the output, fitted in (0, 1) for
    /// both (as its logit).
    pub output_share: f64,
}

impl SupplySagParams {
    /// A dependence of `g_V` per volt on the drive (the physical default).
    pub fn drive(gain_per_volt: f64) -> SupplySagParams {
        SupplySagParams::new(gain_per_volt, Scaled::Drive, 0.0)
    }

    /// `scales` with output share `share` (0 for the drive and 1 for the output whatever
    /// `share` says).
    pub fn new(gain_per_volt: f64, scales: Scaled, share: f64) -> SupplySagParams {
        let output_share = match scales {
            Scaled::Drive => 0.0,
            Scaled::Output => 1.0,
            Scaled::Both => share.clamp(SHARE_EDGE, 1.0 - SHARE_EDGE),
        };
        SupplySagParams {
            gain_per_volt,
            scales,
            output_share,
        }
    }

    /// `x_k ← x_k (1 + part g_V (V_k − V_r))`.
    fn scale(&self, x: &mut [f64], sig: &Signals, part: f64) {
        if part == 0.0 {
            return;
        }
        if let Some(volt) = sig.voltage {
            let g = part * self.gain_per_volt;
            for (xk, vk) in x.iter_mut().zip(volt) {
                *xk *= 1.0 + g * (vk - sig.v_ref);
            }
        }
    }
}

/// Closest a fitted output share comes to 0 or 1 (its logit stays finite).
pub const SHARE_EDGE: f64 = 1e-6;

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// Relative gain change per volt, 1/V.
    gain_per_volt: f64,
    /// `"drive"`, `"output"` or `"drive_and_output"`.
    scales: &'static str,
    /// The share on the output, 0..1.
    output_share: f64,
}

impl Effect for SupplySag {
    fn name(&self) -> EffectName {
        NAME
    }

    /// Without a voltage channel: not applicable. Otherwise the term on the drive
    /// ([`fit_scaling`]); which side it scales is settled on the final model ([`side`]).
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        ctx.sig.voltage?;
        Some(fit_scaling(ctx, cur))
    }

    /// The module doc's test: `after` refitted with the voltage replaced by
    /// [`voltage_from_throttle`] (from `after`'s values and from this effect's own starts on
    /// `before`); the real voltage must lower the SSE by a score `n ln(SSE_alt / SSE_after)` of
    /// at least [`SCORE_THRESHOLD`], or the alternative must be no static map: a thrust that
    /// falls as the throttle rises ([`map_turns_back`]: a supply that collapses on the top
    /// level gives less thrust there than on the level below, which the voltage explains and
    /// no propeller's map does).
    fn identifiable(&self, ctx: &Ctx, before: &Fit, after: &Fit) -> Result<(), String> {
        let Some(volt) = ctx.sig.voltage else {
            return Ok(());
        };
        let quad = VoltageOfThrottle::fit(ctx.sig.u, volt);
        let vhat: Vec<f64> = ctx.sig.u.iter().map(|&u| quad.at(u)).collect();
        let alt = Ctx {
            sig: Signals {
                voltage: Some(&vhat),
                ..ctx.sig
            },
            est: ctx.est.clone(),
            val: ctx.val.clone(),
            rules: ctx.rules,
            gate: ctx.gate,
        };
        let mut f = alt.best_of([after.model.clone()], 1);
        if let Some(g) = self.extend(&alt, before).filter(|g| g.sse < f.sse) {
            f = g;
        }
        let own = after.n as f64 * (f.sse / after.sse).ln();
        if own >= SCORE_THRESHOLD || map_turns_back(&alt, &f.model, &quad) {
            return Ok(());
        }
        Err(format!(
            "fits in-sample, but the supply voltage follows the throttle: with the voltage \
             replaced by a smooth function of the throttle the fit is as good (the voltage's own \
             variation scores {own:.0} < {SCORE_THRESHOLD}), so a voltage gain cannot be told \
             from a static map of the throttle in this record: not taken"
        ))
    }

    /// What the supply scales, settled on the model the search ends with ([`side`]).
    fn settle(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        side(ctx, cur)
    }

    fn warning(&self, ctx: &Ctx, cur: &Fit, found: bool, model: &'static str) -> Option<Warning> {
        if found {
            return None;
        }
        supply_sag_warning(&detectability(ctx, cur)?, model)
    }
}

/// The score `n ln(SSE_a / SSE_b)` of fit `b` over fit `a`.
fn gain(a: &Fit, b: &Fit) -> f64 {
    a.n as f64 * (a.sse / b.sse).ln()
}

/// Which side the supply scales, settled on a final model `cur` whose supply term scales the
/// drive (module doc, **Which side**): the term moved to the output, and split between both
/// (from each side's fit with a tenth of it moved to the other, and from the better side's
/// gain split evenly), every other parameter refitted from `cur`'s values. The output is
/// taken when it fits better than the drive by [`OUTPUT_SCORE`] (equal parameter counts),
/// both when they fit better than the better side by [`BOTH_SCORE`] (one parameter more).
/// `None` when `cur` has no supply term on the drive or the drive stays.
pub fn side(ctx: &Ctx, cur: &Fit) -> Option<Fit> {
    let g = cur.model.term(NAME)?.free();
    if g.len() != 1 {
        return None;
    }
    let moved = |m: &Model, scales, share| {
        let g = m.term(NAME).map_or(0.0, |t| t.free()[0].0);
        m.with(SupplySagParams::new(g, scales, share))
    };
    // Every share of a dead time on the output's side (the voltage as late as the output it
    // scales, or as early as the drive).
    let mut delays: Vec<Model> = cur
        .model
        .with_each_voltage_delay()
        .into_iter()
        .map(|(_, m)| m)
        .collect();
    if delays.is_empty() {
        delays.push(cur.model.clone());
    }
    let output = ctx.best_of(delays.iter().map(|m| moved(m, Scaled::Output, 1.0)), 3);
    let better = if output.sse < cur.sse { &output } else { cur };
    let both = ctx.best_of(
        [
            moved(&cur.model, Scaled::Both, 0.1),
            moved(&output.model, Scaled::Both, 0.9),
            moved(&better.model, Scaled::Both, 0.5),
        ],
        3,
    );
    let one = (gain(cur, &output) > OUTPUT_SCORE).then_some(output);
    let best_one = one.as_ref().unwrap_or(cur);
    if gain(best_one, &both) > BOTH_SCORE {
        Some(both)
    } else {
        one
    }
}

/// The supply term on the drive, fitted on top of `cur`: starts where the gain goes as
/// `V^n` around the reference voltage, `g_V = n / V_r` for `n` in [`START_EXPONENTS`] (the same
/// starts for a 1-cell and a 6-cell battery); Levenberg–Marquardt from every start (the gain and
/// the core's gain and offset trade against each other: the start nearest in the linear refit is
/// not always the basin of the best fit). A dead time already in the model was placed with no
/// term reading the voltage: its share on the output's side is still open
/// ([`Term::voltage_delay`]); every share from none to all of it is tried.
fn fit_scaling(ctx: &Ctx, cur: &Fit) -> Fit {
    let v_ref = ctx.sig.v_ref.abs().max(1e-6);
    let starts = |m: &Model| START_EXPONENTS.map(|n| m.with(SupplySagParams::drive(n / v_ref)));
    let mut best = ctx.best_of(starts(&cur.model), START_EXPONENTS.len());
    for (_, m) in cur
        .model
        .with_each_voltage_delay()
        .into_iter()
        .filter(|(s, _)| *s > 0)
    {
        let f = ctx.best_of(starts(&m), 1);
        if f.sse < best.sse {
            best = f;
        }
    }
    best
}

/// The supply voltage as a smooth function of the throttle alone: the least-squares quadratic
/// `V̂ = a + b x + c x²` in the standardised throttle `x = (u − ū) / σ_u`. A load's IR drop
/// (∝ current, a power of the throttle near 1.5) and a discharge on a monotone ramp (∝ time ∝
/// throttle) are such functions; a voltage that collapses on one level only, or discharges
/// while a staircase comes back down, is not. A throttle that does not vary gives the mean
/// voltage (a small ridge keeps the solution defined when the throttle takes two values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoltageOfThrottle {
    /// Mean and standard deviation of the throttle (the standardisation).
    u_mean: f64,
    u_std: f64,
    /// `a, b, c`; `b = c = 0` when the throttle does not vary.
    coef: [f64; 3],
}

impl VoltageOfThrottle {
    /// The fit over the samples of `u` and `v`.
    pub fn fit(u: &[f64], v: &[f64]) -> VoltageOfThrottle {
        let n = u.len().min(v.len());
        let (u, v) = (&u[..n], &v[..n]);
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len().max(1) as f64;
        let (mu, mv) = (mean(u), mean(v));
        let su = (u.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / n.max(1) as f64).sqrt();
        let flat = VoltageOfThrottle {
            u_mean: mu,
            u_std: 1.0,
            coef: [mv, 0.0, 0.0],
        };
        if !(su > 0.0 && su.is_finite()) {
            return flat;
        }
        let mut ata = nalgebra::Matrix3::<f64>::zeros();
        let mut aty = nalgebra::Vector3::<f64>::zeros();
        for (&uk, &vk) in u.iter().zip(v) {
            let xk = (uk - mu) / su;
            let row = nalgebra::Vector3::new(1.0, xk, xk * xk);
            ata += row * row.transpose();
            aty += row * vk;
        }
        // A small ridge: with two distinct throttles x² is a multiple of the constant.
        let ridge = 1e-9 * ata.diagonal().max();
        for i in 0..3 {
            ata[(i, i)] += ridge;
        }
        match ata.cholesky().map(|c| c.solve(&aty)) {
            Some(c) if c.iter().all(|a| a.is_finite()) => VoltageOfThrottle {
                u_mean: mu,
                u_std: su,
                coef: [c[0], c[1], c[2]],
            },
            _ => flat,
        }
    }

    /// `V̂` at throttle `u`.
    pub fn at(&self, u: f64) -> f64 {
        let x = (u - self.u_mean) / self.u_std;
        self.coef[0] + self.coef[1] * x + self.coef[2] * x * x
    }
}

/// `V̂` of every sample ([`VoltageOfThrottle`] fitted over `u` and `v`).
pub fn voltage_from_throttle(u: &[f64], v: &[f64]) -> Vec<f64> {
    let q = VoltageOfThrottle::fit(u, v);
    u.iter().take(v.len()).map(|&x| q.at(x)).collect()
}

/// Levels at which a model's steady output is evaluated across the throttle's range.
pub const MAP_LEVELS: usize = 16;
/// Largest fall of a steady output against the throttle, as a share of its span, that still
/// counts as a map that does not turn back (noise of the fit).
pub const MAP_REVERSAL: f64 = 0.02;

/// True when model `m`'s steady output, with the supply at `vhat(u)`, turns back against the
/// throttle somewhere in the estimation samples' throttle range: falls by more than
/// [`MAP_REVERSAL`] of its span where its overall trend rises (or rises where it falls). A
/// propeller's thrust does not fall as the throttle rises at a fixed supply, so a "static map"
/// that must do so is not one. The steady output at a level is the model's first simulated
/// sample with the input held there (the states start in steady state).
pub fn map_turns_back(ctx: &Ctx, m: &crate::model::Model, vhat: &VoltageOfThrottle) -> bool {
    let us = ctx
        .est
        .clone()
        .map(|k| ctx.sig.u[k])
        .filter(|u| u.is_finite());
    let (lo, hi) = us.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), u| {
        (a.min(u), b.max(u))
    });
    if hi <= lo {
        return false;
    }
    let steady: Vec<f64> = (0..MAP_LEVELS)
        .map(|i| {
            let u = [lo + (hi - lo) * i as f64 / (MAP_LEVELS - 1) as f64];
            let v = [vhat.at(u[0])];
            let sig = Signals {
                u: &u,
                y: &u,
                voltage: Some(&v),
                ..ctx.sig
            };
            let mut out = [0.0];
            simulate(m, &sig, &mut out);
            out[0]
        })
        .collect();
    let (first, last) = (steady[0], steady[MAP_LEVELS - 1]);
    let span = steady.iter().fold(0.0f64, |s, &y| s.max((y - first).abs()));
    if span.is_nan() || span <= 0.0 || span.is_infinite() {
        return false;
    }
    let sign = if last >= first { 1.0 } else { -1.0 };
    steady
        .windows(2)
        .any(|w| sign * (w[1] - w[0]) < -MAP_REVERSAL * span)
}

impl Term for SupplySagParams {
    fn name(&self) -> EffectName {
        NAME
    }

    fn place(&self) -> Place {
        Place::InputScale
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    fn reads_voltage(&self) -> bool {
        true
    }

    fn shape_input(&self, v: &mut [f64], sig: &Signals) {
        self.scale(v, sig, 1.0 - self.output_share);
    }

    fn scale_output(&self, y: &mut [f64], sig: &Signals) {
        self.scale(y, sig, self.output_share);
    }

    fn free(&self) -> Vec<(f64, Scale)> {
        let mut free = vec![(self.gain_per_volt, Scale::Linear)];
        if self.scales == Scaled::Both {
            let s = self.output_share;
            free.push(((s / (1.0 - s)).ln(), Scale::Linear));
        }
        free
    }

    fn set_free(&mut self, values: &[f64]) {
        self.gain_per_volt = values[0];
        if let (Scaled::Both, Some(&logit)) = (self.scales, values.get(1)) {
            let s = 1.0 / (1.0 + (-logit).exp());
            self.output_share = s.clamp(SHARE_EDGE, 1.0 - SHARE_EDGE);
        }
    }

    fn terms(&self, _dt_s: f64, terms: &mut Map<String, Value>) {
        terms.insert("gain_per_volt".into(), json!(self.gain_per_volt));
        terms.insert("supply_scales".into(), json!(self.scales.word()));
        terms.insert("supply_output_share".into(), json!(self.output_share));
    }

    fn finding_params(&self, _dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            gain_per_volt: self.gain_per_volt,
            scales: self.scales.word(),
            output_share: self.output_share,
        })
    }

    fn evidence(&self, _core: &Core, ctx: &Ctx, drop: &str) -> String {
        let (lo, hi) = ctx.sig.voltage.map_or((0.0, 0.0), |x| {
            x.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                })
        });
        // The drop was measured when the term was taken, on the drive; the side is the final
        // model's (`side`).
        let side = match self.scales {
            Scaled::Drive => "on the drive".to_string(),
            Scaled::Output => "settled on the output at once".to_string(),
            Scaled::Both => format!(
                "settled with {:.0} % of it on the output",
                100.0 * self.output_share
            ),
        };
        format!(
            "the gain follows the supply voltage ({:+.1} % per volt while the supply ranged \
             {lo:.2}..{hi:.2} V, {side}); with a voltage-scaled input {drop}",
            100.0 * self.gain_per_volt
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_voltage_from_the_throttle_is_its_smooth_part() {
        // Two levels (0.2 and 0.6, 40 samples each) with a voltage falling through both.
        let u: Vec<f64> = (0..80).map(|k| if k < 40 { 0.2 } else { 0.6 }).collect();
        let v: Vec<f64> = (0..80).map(|k| 16.0 - 0.01 * k as f64).collect();
        let vhat = voltage_from_throttle(&u, &v);
        assert!((vhat[0] - (16.0 - 0.195)).abs() < 1e-6, "{}", vhat[0]);
        assert!(vhat[..40].iter().all(|&x| (x - vhat[0]).abs() < 1e-6));
        assert!((vhat[79] - (16.0 - 0.595)).abs() < 1e-6, "{}", vhat[79]);
        // A ramp with an IR drop growing as throttle^1.5: followed within 2 % of its span.
        let u: Vec<f64> = (0..640).map(|k| k as f64 / 640.0).collect();
        let v: Vec<f64> = u
            .iter()
            .map(|x| 4.0 - 0.3 * x - 0.4 * x.powf(1.5))
            .collect();
        let vhat = voltage_from_throttle(&u, &v);
        let worst = v
            .iter()
            .zip(&vhat)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 0.02 * 0.7, "{worst}");
        // A constant throttle: the mean voltage.
        assert_eq!(
            voltage_from_throttle(&[0.5; 4], &[1.0, 2.0, 3.0, 4.0]),
            [2.5; 4]
        );
    }

    /// A non-monotone staircase (150 samples a level at 100 Hz) through a 2nd-order core with
    /// a supply sag of 0.1 per volt on voltage `volt(k, u)`, a small deterministic noise
    /// added; the baseline fitted; returns (u, y, v).
    fn sagging_staircase(volt: impl Fn(usize, f64) -> f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        sagging_levels(&[0.3, 0.6, 0.4, 0.8, 0.5, 0.7, 0.35, 0.65], volt)
    }

    /// [`sagging_staircase`] over `levels`.
    fn sagging_levels(
        levels: &[f64],
        volt: impl Fn(usize, f64) -> f64,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        sagging(levels, 0.7, SupplySagParams::drive(0.1), volt)
    }

    /// [`sagging_levels`] through a core of damping `zeta` with the supply term `sag`.
    fn sagging(
        levels: &[f64],
        zeta: f64,
        sag: SupplySagParams,
        volt: impl Fn(usize, f64) -> f64,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        use crate::model::simulate;
        let u: Vec<f64> = levels
            .iter()
            .flat_map(|&l| std::iter::repeat(l).take(150))
            .collect();
        let v: Vec<f64> = u.iter().enumerate().map(|(k, &x)| volt(k, x)).collect();
        let truth = Model::new(Core {
            fn_hz: 3.0,
            zeta,
            gain: 2.0,
            offset: 0.0,
            lead: 0.0,
        })
        .with(sag);
        let mut y = vec![0.0; u.len()];
        let sig = Signals {
            dt_s: 0.01,
            u: &u,
            y: &u,
            voltage: Some(&v),
            u_ref: 0.5,
            v_ref: v.iter().sum::<f64>() / v.len() as f64,
        };
        simulate(&truth, &sig, &mut y);
        for (k, x) in y.iter_mut().enumerate() {
            *x += 0.003 * ((k as f64 * 1.7).sin() + (k as f64 * 0.37).cos());
        }
        (u, y, v)
    }

    /// The fit's context over every sample of `(u, y, v)` at 100 Hz.
    fn context<'a>(u: &'a [f64], y: &'a [f64], v: &'a [f64]) -> Ctx<'a> {
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
        Ctx {
            sig: Signals {
                dt_s: 0.01,
                u,
                y,
                voltage: Some(v),
                u_ref: mean(u),
                v_ref: mean(v),
            },
            est: 0..u.len(),
            val: 0..u.len(),
            rules: propid_numerics::segment::SegmentRules::DEFAULT,
            gate: Default::default(),
        }
    }

    /// The sag fitted on the baseline of `(u, y, v)`: the fit and the identifiability test.
    fn fit_sag(u: &[f64], y: &[f64], v: &[f64]) -> (Fit, Result<(), String>) {
        let ctx = context(u, y, v);
        let base = crate::baseline::baseline(&ctx, &Default::default(), &[]);
        let after = SupplySag.extend(&ctx, &base).expect("a voltage channel");
        let verdict = SupplySag.identifiable(&ctx, &base, &after);
        (after, verdict)
    }

    fn gain_per_volt(f: &Fit) -> f64 {
        f.model.term(NAME).map_or(f64::NAN, |t| t.free()[0].0)
    }

    #[test]
    fn the_side_the_supply_scales_is_settled_on_the_final_model() {
        // A lightly damped mode (ζ 0.05 at 3 Hz) rings after every step while the voltage
        // dips with the load and discharges: there a gain on the output is no gain on the
        // drive. Each truth is fitted on the drive first, then settled.
        let levels = [0.3, 0.6, 0.4, 0.8, 0.5, 0.7, 0.35, 0.65];
        let volt = |k: usize, x: f64| 16.8 - 1.5 * x - 2.4 * k as f64 / 1200.0;
        for (truth, share) in [(Scaled::Output, 1.0), (Scaled::Both, 0.5)] {
            let sag = SupplySagParams::new(0.1, truth, share);
            let (u, y, v) = sagging(&levels, 0.05, sag, volt);
            let ctx = context(&u, &y, &v);
            let base = crate::baseline::baseline(&ctx, &Default::default(), &[]);
            let drive = SupplySag.extend(&ctx, &base).unwrap();
            let settled = side(&ctx, &drive).expect("settled off the drive");
            let t = settled.model.term(NAME).unwrap();
            let word = t.finding_params(0.01)["scales"].clone();
            assert_eq!(word, truth.word(), "{truth:?}");
            let s = t.finding_params(0.01)["output_share"].as_f64().unwrap();
            assert!((s - share).abs() < 0.05, "{truth:?}: share {s}");
            let g = gain_per_volt(&settled);
            assert!((g - 0.1).abs() < 0.002, "{truth:?}: {g}");
            // The drive alone leaves the ringing's share of it in the residual.
            assert!(
                settled.sse < 0.5 * drive.sse,
                "{truth:?}: {} {}",
                drive.sse,
                settled.sse
            );
        }
        // A gain on the drive stays there.
        let (u, y, v) = sagging(&levels, 0.05, SupplySagParams::drive(0.1), volt);
        let ctx = context(&u, &y, &v);
        let base = crate::baseline::baseline(&ctx, &Default::default(), &[]);
        let drive = SupplySag.extend(&ctx, &base).unwrap();
        assert!(side(&ctx, &drive).is_none());
        assert!((gain_per_volt(&drive) - 0.1).abs() < 0.002);
    }

    #[test]
    fn a_battery_that_discharges_through_a_staircase_is_told_from_a_static_map() {
        // An IR drop with the load and a discharge of 2.4 V over the record: the levels come
        // back at lower voltages, which no function of the throttle follows.
        let (u, y, v) = sagging_staircase(|k, x| 16.8 - 1.5 * x - 2.4 * k as f64 / 1200.0);
        let (f, verdict) = fit_sag(&u, &y, &v);
        assert_eq!(verdict, Ok(()));
        let g = gain_per_volt(&f);
        assert!((g / 0.1 - 1.0).abs() < 0.1, "{g}");
    }

    #[test]
    fn a_voltage_that_only_follows_the_throttle_is_not_taken_for_a_sag() {
        // The IR drop alone: the voltage is a function of the throttle, the sag a static map.
        let (u, y, v) = sagging_staircase(|_, x| 16.8 - 3.0 * x * x);
        let (f, verdict) = fit_sag(&u, &y, &v);
        assert!(gain_per_volt(&f).is_finite());
        let reason = verdict.expect_err("not separable from a static map");
        assert!(reason.contains("follows the throttle"), "{reason}");
    }

    #[test]
    fn a_supply_that_collapses_on_the_top_level_is_a_sag_not_a_map() {
        // Three levels, 16.8 V on all but the top one (0.8), 13 V there: the voltage is a
        // function of the throttle (a quadratic through three levels follows it exactly), but
        // the thrust at 0.8 falls below the thrust at 0.6, which the voltage explains and no
        // propeller's static map does.
        let volt = |_: usize, x: f64| if x >= 0.8 { 13.0 } else { 16.8 };
        let (u, y, v) = sagging_levels(&[0.3, 0.6, 0.8, 0.3, 0.8, 0.6, 0.3, 0.8], volt);
        let (f, verdict) = fit_sag(&u, &y, &v);
        assert_eq!(verdict, Ok(()));
        let g = gain_per_volt(&f);
        assert!((g / 0.1 - 1.0).abs() < 0.1, "{g}");
        // The smooth function of the throttle that stands in for the voltage turns back ...
        let quad = VoltageOfThrottle::fit(&u, &v);
        let mut ctx = Ctx::whole(0.01, &u, &y);
        ctx.sig.voltage = Some(&v);
        ctx.sig.v_ref = v.iter().sum::<f64>() / v.len() as f64;
        assert!(map_turns_back(&ctx, &f.model, &quad));
        // ... while with an IR drop that only dips (thrust still rising) it does not.
        let (u, y, v) = sagging_staircase(|_, x| 16.8 - 3.0 * x * x);
        let (f, _) = fit_sag(&u, &y, &v);
        let mut ctx = Ctx::whole(0.01, &u, &y);
        ctx.sig.voltage = Some(&v);
        ctx.sig.v_ref = v.iter().sum::<f64>() / v.len() as f64;
        assert!(!map_turns_back(
            &ctx,
            &f.model,
            &VoltageOfThrottle::fit(&u, &v)
        ));
    }

    /// The detectability bound on the baseline of `(u, y, v)` (the whole record).
    fn detect(u: &[f64], y: &[f64], v: &[f64]) -> Detectability {
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
        let mut ctx = Ctx::whole(0.01, u, y);
        ctx.sig.voltage = Some(v);
        ctx.sig.v_ref = mean(v);
        let base = crate::baseline::baseline(&ctx, &Default::default(), &[]);
        detectability(&ctx, &base).expect("a voltage channel")
    }

    #[test]
    fn a_sag_is_undetectable_where_the_voltage_has_no_variation_of_its_own() {
        // A bench supply held at 16 V (a millivolt of ripple), or a voltage that only dips
        // with the load: even thrust ∝ V² leaves nothing a fit could score.
        for volt in [
            &(|k: usize, _: f64| 16.0 + 0.001 * (k as f64 * 0.9).sin())
                as &dyn Fn(usize, f64) -> f64,
            &|_, x| 16.8 - 3.0 * x * x,
        ] {
            let (u, y, v) = sagging_staircase(volt);
            let d = detect(&u, &y, &v);
            assert!(d.score < SCORE_THRESHOLD, "{d:?}");
            assert!(d.own_rms_v < 0.01, "{d:?}");
        }
        // A battery discharging 2.4 V while the levels come back: a propeller-strong term
        // would change the thrust by several per cent, far above the residual.
        let (u, y, v) = sagging_staircase(|k, x| 16.8 - 1.5 * x - 2.4 * k as f64 / 1200.0);
        let d = detect(&u, &y, &v);
        assert!(d.score > 10.0 * SCORE_THRESHOLD, "{d:?}");
        assert!((0.5..1.0).contains(&d.own_rms_v), "{d:?}");
        assert!((0.03..0.2).contains(&d.relative_change), "{d:?}");
    }

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = SupplySagParams::drive(0.05);
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(
            text(&p.finding_params(0.002)),
            r#"{"gain_per_volt":0.05,"output_share":0.0,"scales":"drive"}"#
        );
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(
            text(&terms),
            r#"{"gain_per_volt":0.05,"supply_output_share":0.0,"supply_scales":"drive"}"#
        );
    }
}
