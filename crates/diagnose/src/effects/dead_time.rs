//! `dead_time`: a transport delay of the throttle (ESC update, filtering, logging), `v_k =
//! u_{k−d}` with `d` whole samples (the first sample held before the record starts).
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/diagnose/src/effects/dead_time.rs`.

use crate::thresholds::{CONFOUNDING_SHIFT, UNIDENTIFIABLE_R2};
use propid_numerics::segment::{Command, SegmentRules};
use propid_numerics::stand::step_table;
use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::ctx::Ctx;
use crate::ctx::{affine_r2, measured_estimation_samples};
use crate::effect::Effect;
use crate::fit::Fit;
use crate::signals::{Core, Signals};
use crate::term::{to_map, Place, Term};
use crate::verdict::{Warning, WarningKind};
use propid_numerics::EffectName;

/// The published name.
pub const NAME: EffectName = EffectName::DeadTime;
/// Longest dead time searched, seconds (ESC update, filtering and logging of a motor stand).
pub const MAX_DELAY_S: f64 = 0.15;
/// Yet never fewer delays than this are searched: a slowly sampled log counts its delay in its
/// own samples (a 45 Hz stand export holds and buffers a sample or two in its logger on top of
/// the ESC's delay, a process logged every 4 s has its transport delay in samples of 4 s), and
/// 0.15 s is there only a few samples (6 at 43 Hz) or none (at 0.25 Hz).
pub const MIN_DELAY_SAMPLES: usize = 16;

/// The longest delay searched, samples: [`MAX_DELAY_S`] but at least [`MIN_DELAY_SAMPLES`],
/// and at most 80 samples and a tenth of the `est_len` estimation samples (≥ 1).
pub fn max_delay_samples(dt_s: f64, est_len: usize) -> usize {
    let cap = (est_len / 10).clamp(1, 80);
    ((MAX_DELAY_S / dt_s).round() as usize)
        .max(MIN_DELAY_SAMPLES)
        .clamp(1, cap)
}

/// The longest delay searched in a record whose command steps show a dead time of
/// `steps_delay` samples ([`steps_delay_samples`]): [`max_delay_samples`], raised to
/// `1.5 θ + 2` when the steps show more (a slow load cell's filter delays the thrust by
/// 0.2–0.3 s: a Crazyflie stand at 100 Hz shows 23 samples), within a tenth of the estimation
/// samples.
pub fn delay_search_samples(dt_s: f64, est_len: usize, steps_delay: Option<f64>) -> usize {
    let base = max_delay_samples(dt_s, est_len);
    let seen = steps_delay.map_or(0, |d| (1.5 * d + 2.0).ceil() as usize);
    base.max(seen.min(est_len / 10))
}

/// The dead time the command's clean steps show, samples: the median of the steps'
/// first-order-plus-dead-time delays in `identify`'s step table ([`step_table`]); `None`
/// without a step that has one.
pub fn steps_delay_samples(sig: &Signals, rules: &SegmentRules) -> Option<f64> {
    let mut d: Vec<f64> = step_table(Command::new(sig.u), sig.dt_s, rules, sig.y)
        .iter()
        .filter_map(|f| f.dead_time_s)
        .map(|t| t / sig.dt_s)
        .filter(|d| d.is_finite())
        .collect();
    if d.is_empty() {
        return None;
    }
    d.sort_by(f64::total_cmp);
    Some(d[d.len() / 2])
}

/// `R²` of the command delayed by [`CONFOUNDING_SHIFT`] samples fitted by `[1, u_k]` over the
/// estimation samples with a measured output; 0 when the command is constant there.
///
/// **Identifiability.** A delay is told from the rest of the model only through what the
/// command does within the delay: on a ramp `u_{k−d} = u_k − b d` exactly, so a delay is a shift
/// of the thrust curve (an input offset the static map and the gain absorb), and on any command
/// smooth against the sample period it is a phase lag, the same as the core's own at low
/// frequency (`≈ 2ζ/ωn`). `1 − R²` is the share of the delayed command that no affine function
/// of the undelayed one gives: about 6e-3 on a 5-level staircase of 640 samples, 2e-2 on the
/// cascaded tanks' random steps, ≈ 1 on noise and multisines, below 1e-6 on a slow thrust-curve
/// ramp. At `R² ≥` [`super::baseline_drift::UNIDENTIFIABLE_R2`] diagnose says the delay cannot
/// be identified (`dead_time_unidentifiable`) instead of saying nothing.
pub fn confounding(ctx: &Ctx) -> f64 {
    let (u, d) = (ctx.sig.u, CONFOUNDING_SHIFT);
    let ks: Vec<usize> = measured_estimation_samples(ctx, d)
        .into_iter()
        .filter(|&k| k < u.len())
        .collect();
    affine_r2(&ks, |k| u[k - d], |k| u[k])
}

/// How many of the command's clean steps `identify` times with a dead time on the output
/// (its step table, [`step_table`]: a delay measured, or bounded below a sample).
pub fn timed_steps(ctx: &Ctx) -> usize {
    let sig = &ctx.sig;
    step_table(Command::new(sig.u), sig.dt_s, &ctx.rules, sig.y)
        .iter()
        .filter(|f| f.dead_time_s.is_some() || f.dead_time_below_sample)
        .count()
}

/// Whether a dead time can be seen in the record, decided once (issue 29 item 4): yes when
/// `identify` times a step of it with a dead time ([`timed_steps`]: the same steps, so that
/// `diagnose` never calls a dead time unidentifiable in a log whose steps `identify` timed);
/// else, for a command without such steps, yes unless it is smooth against the sample period
/// ([`confounding`] below [`UNIDENTIFIABLE_R2`]: noise and multisines show a delay without a
/// step). The `dead_time_unidentifiable` warning when it cannot.
pub fn identifiability_warning(ctx: &Ctx) -> Option<Warning> {
    if timed_steps(ctx) > 0 {
        return None;
    }
    dead_time_warning(confounding(ctx))
}

/// The `dead_time_unidentifiable` warning when `r2` (the share of the command delayed by
/// [`CONFOUNDING_SHIFT`] samples that an affine function of the command explains) reaches
/// [`UNIDENTIFIABLE_R2`] ([`confounding`]), for a command with no step `identify` times.
fn dead_time_warning(r2: f64) -> Option<Warning> {
    (r2 >= UNIDENTIFIABLE_R2).then(|| Warning {
        kind: WarningKind::DeadTimeUnidentifiable,
        message: format!(
            "dead time not identifiable: the command has no clean step that `identify` times \
             with a dead time, and it is smooth against the sample period (delayed by \
             {CONFOUNDING_SHIFT} samples it is an affine function of itself to R² = {r2:.5}), \
             so a delay of the output cannot be told from a shift of the thrust curve or a lag; \
             steps or holds would show it"
        ),
        model: "baseline",
        value: r2,
        band_hz: None,
    })
}

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct DeadTime;

/// The fitted delay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadTimeParams {
    /// Delay `d`, whole samples (≥ 1 once fitted).
    pub delay_samples: usize,
    /// The part of it on the output's side (≤ `delay_samples`): the measured voltage reaches
    /// the model that much late too ([`Term::voltage_delay`]; 0 without a voltage).
    pub sensor_samples: usize,
}

impl DeadTimeParams {
    /// A delay of `d` samples all on the throttle's side.
    pub fn throttle(d: usize) -> DeadTimeParams {
        DeadTimeParams {
            delay_samples: d,
            sensor_samples: 0,
        }
    }
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// Delay, seconds.
    delay_s: f64,
    /// Delay, samples.
    delay_samples: usize,
    /// The part of it on the output's side, samples: the measured supply voltage reaches the
    /// model that much late too (only when some of it is; module doc).
    #[serde(skip_serializing_if = "Option::is_none")]
    sensor_delay_samples: Option<usize>,
}

impl Effect for DeadTime {
    fn name(&self) -> EffectName {
        NAME
    }

    /// Delays up to [`delay_search_samples`], each tried with every parameter of the current
    /// model refitted jointly (the core's `fn` and `ζ` have absorbed part of the delay, and
    /// the other effects' parameters shift with it), from the current model and from it with
    /// the core's lag given back ([`compensated_core`]). A coarse grid with a short refit, then
    /// every delay around the best [`FINE_STARTS`] coarse delays with a longer refit; with a
    /// term that reads the voltage, each delay all on one side and all on the other, then the
    /// best delay's share on the output's side ([`shares`]).
    ///
    /// The coarse step is [`coarse_step`], and at least a 32nd of the range (a range raised by
    /// the steps stays a few dozen fits). The SSE as a function of the delay is not smooth when
    /// the core rings (a delay of one period of the core's mode fits almost as well as none, a
    /// half period fits worst), so the grid must sample that period; a step of 4 on a mode of
    /// 8 samples per period skips the true delay's narrow valley and lands a whole period
    /// later (Silverbox at 610 Hz, a 65 Hz resonance: 3 samples found as 11).
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let dmax = delay_search_samples(
            ctx.sig.dt_s,
            ctx.est.len(),
            steps_delay_samples(&ctx.sig, &ctx.rules),
        );
        // With a term that reads the voltage, where the delay lies matters (module doc): each
        // delay is tried all on the throttle's side and all on the output's, and the best
        // delay's share is refined.
        let split = ctx.sig.voltage.is_some() && cur.model.terms().any(|t| t.reads_voltage());
        let d_cur = cur.model.input_delay();
        let lm_at = |p: DeadTimeParams, iters: usize| {
            let delayed = cur.model.with(p);
            let from_cur = ctx.lm(&delayed, iters);
            let delay_s = (p.delay_samples as f64 - d_cur as f64) * ctx.sig.dt_s;
            match compensated_core(&cur.model.core, delay_s) {
                Some(core) => {
                    let f = ctx.lm(&delayed.with_core(core), iters);
                    if f.sse < from_cur.sse {
                        f
                    } else {
                        from_cur
                    }
                }
                None => from_cur,
            }
        };
        let fit_d = |d: usize, iters: usize| {
            let throttle = lm_at(DeadTimeParams::throttle(d), iters);
            if !split {
                return throttle;
            }
            let output = lm_at(
                DeadTimeParams {
                    delay_samples: d,
                    sensor_samples: d,
                },
                iters,
            );
            if output.sse < throttle.sse {
                output
            } else {
                throttle
            }
        };
        // Beside a whole sample of input lead one sample of delay would only undo the lead
        // (`crate::lead`): the shortest delay tried is then 2.
        let first = if cur.model.core.lead >= 1.0 { 2 } else { 1 };
        let step = coarse_step(cur.model.core.fn_hz, ctx.sig.dt_s).max(dmax / 32);
        // The delays' fits are independent of one another: on the cores left idle.
        let grid: Vec<usize> = (first..=dmax.max(first)).step_by(step).collect();
        let sse = crate::par::map(&grid, |&d| fit_d(d, 8).sse);
        let mut coarse: Vec<(usize, f64)> = grid.into_iter().zip(sse).collect();
        coarse.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut fine: Vec<usize> = coarse
            .iter()
            .take(FINE_STARTS)
            .flat_map(|&(d0, _)| d0.saturating_sub(step).max(first)..=(d0 + step).min(dmax))
            .collect();
        fine.sort_unstable();
        fine.dedup();
        let mut best: Option<Fit> = None;
        for f in crate::par::map(&fine, |&d| fit_d(d, 30)) {
            if best.as_ref().map_or(true, |b| f.sse < b.sse) {
                best = Some(f);
            }
        }
        let best = best?;
        if !split {
            return Some(best);
        }
        let d = best.model.term(NAME).map_or(0, |t| t.input_delay());
        let mut best = best;
        for share in shares(d).into_iter().filter(|&s| s > 0 && s < d) {
            let f = lm_at(
                DeadTimeParams {
                    delay_samples: d,
                    sensor_samples: share,
                },
                30,
            );
            if f.sse < best.sse {
                best = f;
            }
        }
        Some(best)
    }

    fn warning(
        &self,
        ctx: &Ctx,
        _cur: &Fit,
        _found: bool,
        _model: &'static str,
    ) -> Option<Warning> {
        identifiability_warning(ctx)
    }
}

/// The shares of a delay of `all` samples tried on the output's side: every one from 0 to
/// `all`, or 9 evenly spaced when there are more.
pub fn shares(all: usize) -> Vec<usize> {
    let step = all.div_ceil(8).max(1);
    let mut s: Vec<usize> = (0..=all).step_by(step).collect();
    if s.last() != Some(&all) {
        s.push(all);
    }
    s
}

/// The current core with the lag that `delay_s` more of delay takes over given back (or, for
/// less delay, taken on): a core fitted without the delay has absorbed it (a lower `fn`, the
/// same low-frequency lag), and a fit started there with the delay added stays in that valley
/// (vanderploeg with 3 samples injected: 4 samples found at SSE 1.59 from the slow core, 5 at
/// 0.65 from this start). The low-frequency group delay of `ωn² / (s² + 2ζωn s + ωn²)` is
/// `τ = 2ζ/ωn`; the core that keeps `τ − delay` has `ωn' = 2ζ / (τ − delay)`. `None` for no
/// change, when the delay is not shorter than `τ` by a tenth of it (nothing to give back) or
/// the core is degenerate.
pub fn compensated_core(core: &Core, delay_s: f64) -> Option<Core> {
    let wn = std::f64::consts::TAU * core.fn_hz;
    let tau = 2.0 * core.zeta / wn;
    let left = tau - delay_s;
    (tau.is_finite() && delay_s != 0.0 && left > 0.1 * tau).then(|| Core {
        fn_hz: core.fn_hz * tau / left,
        ..*core
    })
}

/// Coarse delays refined by [`DeadTime::extend`]: the best this many (the SSE over the delay
/// has a valley per period of a ringing core).
pub const FINE_STARTS: usize = 2;

/// The coarse step of the delay search, samples: a quarter of the core's period
/// `1 / (fn dt)` samples (so that every valley of the SSE over the delay is sampled, see
/// [`DeadTime::extend`]), within 1..=4.
pub fn coarse_step(fn_hz: f64, dt_s: f64) -> usize {
    let period = 1.0 / (fn_hz * dt_s);
    if period.is_finite() {
        ((period / 4.0).floor() as usize).clamp(1, 4)
    } else {
        4
    }
}

impl Term for DeadTimeParams {
    fn name(&self) -> EffectName {
        NAME
    }

    fn place(&self) -> Place {
        Place::InputShift
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    fn voltage_delay(&self) -> usize {
        self.sensor_samples
    }

    fn input_delay(&self) -> usize {
        self.delay_samples
    }

    fn with_voltage_delay(&self, samples: usize) -> Option<Box<dyn Term>> {
        Some(Box::new(DeadTimeParams {
            sensor_samples: samples.min(self.delay_samples),
            ..*self
        }))
    }

    /// [`shares`] of its delay.
    fn voltage_delay_shares(&self) -> Vec<usize> {
        shares(self.delay_samples)
    }

    fn one_sample_shorter(&self) -> Option<Box<dyn Term>> {
        Some(Box::new(DeadTimeParams {
            delay_samples: self.delay_samples.saturating_sub(1),
            sensor_samples: self.sensor_samples.saturating_sub(1),
        }))
    }

    fn shape_input(&self, v: &mut [f64], _sig: &Signals) {
        // v_k = v_{max(k − d, 0)}.
        let (d, n) = (self.delay_samples, v.len());
        if d == 0 || n == 0 {
            return;
        }
        let d = d.min(n);
        v.copy_within(0..n - d, d);
        let first = v[0];
        v[1..d].fill(first);
    }

    fn terms(&self, dt_s: f64, terms: &mut Map<String, Value>) {
        if self.delay_samples > 0 {
            terms.insert("delay_samples".into(), json!(self.delay_samples));
            terms.insert("delay_s".into(), json!(self.delay_s(dt_s)));
        }
        if self.sensor_samples > 0 {
            terms.insert("sensor_delay_samples".into(), json!(self.sensor_samples));
        }
    }

    fn finding_params(&self, dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            delay_s: self.delay_s(dt_s),
            delay_samples: self.delay_samples,
            sensor_delay_samples: (self.sensor_samples > 0).then_some(self.sensor_samples),
        })
    }

    fn evidence(&self, _core: &Core, ctx: &Ctx, drop: &str) -> String {
        let d = self.delay_samples;
        format!(
            "the output starts to move {d} samples ({:.1} ms) after the throttle does; \
             with the input delayed by that much {drop}",
            1e3 * d as f64 * ctx.sig.dt_s
        )
    }
}

impl DeadTimeParams {
    /// The delay in seconds.
    pub fn delay_s(&self, dt_s: f64) -> f64 {
        self.delay_samples as f64 * dt_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_longest_delay_is_0_15_s_but_never_under_16_samples() {
        // The simulated stand at 500 Hz: 0.15 s.
        assert_eq!(max_delay_samples(0.002, 8400), 75);
        // 1 kHz: the 80-sample cap.
        assert_eq!(max_delay_samples(0.001, 8400), 80);
        // A 43 Hz stand export and the cascaded tanks at 0.25 Hz: 16 samples.
        assert_eq!(max_delay_samples(1.0 / 43.0, 700), 16);
        assert_eq!(max_delay_samples(4.0, 717), 16);
        // A short record: a tenth of its estimation part.
        assert_eq!(max_delay_samples(4.0, 90), 9);
        assert_eq!(max_delay_samples(4.0, 5), 1);
    }

    #[test]
    fn the_coarse_step_samples_a_quarter_of_the_core_period() {
        // Silverbox: a 65 Hz resonance at 610 Hz, 9.4 samples per period.
        assert_eq!(coarse_step(65.0, 1.0 / 610.35), 2);
        // A motor at 10 Hz sampled at 500 Hz: 50 samples per period, the step stays 4.
        assert_eq!(coarse_step(10.0, 0.002), 4);
        // Near Nyquist every delay is tried; a degenerate core keeps 4.
        assert_eq!(coarse_step(200.0, 1.0 / 610.35), 1);
        assert_eq!(coarse_step(0.0, 0.002), 4);
    }

    #[test]
    fn the_input_is_shifted_and_the_first_sample_held() {
        let sig = Signals {
            dt_s: 0.01,
            u: &[],
            y: &[],
            voltage: None,
            u_ref: 1.0,
            v_ref: 0.0,
        };
        let mut v = vec![1.0, 2.0, 3.0, 4.0, 5.0];
        DeadTimeParams::throttle(2).shape_input(&mut v, &sig);
        assert_eq!(v, [1.0, 1.0, 1.0, 2.0, 3.0]);
    }

    #[test]
    fn a_delay_is_unidentifiable_on_a_ramp_only() {
        let n = 600;
        let ramp: Vec<f64> = (0..n).map(|k| 0.1 + 0.8 * k as f64 / n as f64).collect();
        let stairs: Vec<f64> = (0..n).map(|k| 0.2 + 0.1 * (k / 120) as f64).collect();
        let noise: Vec<f64> = (0..n)
            .map(|k| 0.5 + 0.2 * ((k * 7919 % 101) as f64 / 101.0 - 0.5))
            .collect();
        let y = vec![0.0; n];
        let r2 = |u: &[f64]| confounding(&Ctx::whole(0.02, u, &y));
        let unidentifiable = UNIDENTIFIABLE_R2;
        assert!(r2(&ramp) >= unidentifiable, "{}", r2(&ramp));
        assert!(r2(&stairs) < unidentifiable, "{}", r2(&stairs));
        assert!(r2(&noise) < 0.5, "{}", r2(&noise));
        assert_eq!(r2(&[0.4; 600]), 0.0);
    }

    #[test]
    fn a_delay_is_identifiable_where_identify_times_the_steps() {
        // A Tyto-style staircase: 20 steps of 0.04, each held 4 s at 143 Hz; the thrust
        // follows 4 samples late as a first order with τ = 5 samples. Delayed by 2 samples
        // the command is an affine function of itself to R² > 0.999 (so the smoothness test
        // alone called the delay unidentifiable), yet `identify` times every step.
        let per = 572;
        let u: Vec<f64> = (0..20 * per)
            .map(|k| 0.1 + 0.04 * (k / per) as f64)
            .collect();
        let mut y = vec![u[0]; u.len()];
        for k in 1..u.len() {
            let target = u[k.saturating_sub(4)];
            y[k] = y[k - 1] + (target - y[k - 1]) * (1.0 - (-1.0f64 / 5.0).exp());
        }
        let dt = 1.0 / 143.0;
        let ctx = Ctx::whole(dt, &u, &y);
        let ctx = Ctx {
            rules: SegmentRules::for_record(dt, true),
            ..ctx
        };
        assert!(
            confounding(&ctx) >= UNIDENTIFIABLE_R2,
            "{}",
            confounding(&ctx)
        );
        assert!(timed_steps(&ctx) >= 15, "{}", timed_steps(&ctx));
        assert!(identifiability_warning(&ctx).is_none());
        // A one-way ramp has no step to time: the smoothness test decides, and says so.
        let ramp: Vec<f64> = (0..2000).map(|k| 0.1 + 0.8 * k as f64 / 2000.0).collect();
        let ctx = Ctx::whole(0.02, &ramp, &ramp);
        assert_eq!(timed_steps(&ctx), 0);
        let w = identifiability_warning(&ctx).expect("a ramp hides a delay");
        assert!(w.message.contains("no clean step"), "{}", w.message);
    }

    #[test]
    fn the_search_reaches_the_delay_the_steps_show() {
        // A Crazyflie stand at 100 Hz whose steps show 23 samples: searched to 1.5·23 + 2.
        assert_eq!(delay_search_samples(0.01, 1400, Some(23.0)), 37);
        // Steps that show less keep the default range; a short record caps it.
        assert_eq!(delay_search_samples(0.01, 1400, Some(3.0)), 16);
        assert_eq!(delay_search_samples(0.01, 1400, None), 16);
        assert_eq!(delay_search_samples(0.01, 200, Some(23.0)), 20);
    }

    #[test]
    fn the_steps_delay_is_the_median_of_the_steps_dead_times() {
        // A staircase of 4 levels, 100 samples each; the output follows 5 samples late as a
        // first order with τ = 4 samples.
        let n = 400;
        let u: Vec<f64> = (0..n).map(|k| 0.2 + 0.1 * (k / 100) as f64).collect();
        let mut y = vec![0.2; n];
        for k in 1..n {
            let target = u[k.saturating_sub(5)];
            y[k] = y[k - 1] + (target - y[k - 1]) * (1.0 - (-1.0f64 / 4.0).exp());
        }
        let sig = Signals {
            dt_s: 0.01,
            u: &u,
            y: &y,
            voltage: None,
            u_ref: 0.35,
            v_ref: 0.0,
        };
        let d = steps_delay_samples(&sig, &SegmentRules::DEFAULT).expect("three steps");
        assert!((d - 5.0).abs() < 1.0, "{d}");
        let flat = Signals {
            u: &[0.5; 400],
            ..sig
        };
        assert_eq!(steps_delay_samples(&flat, &SegmentRules::DEFAULT), None);
    }

    #[test]
    fn a_delay_gives_back_the_lag_the_core_took_on() {
        // τ = 2ζ/ωn = 2·0.7/(2π·2) = 0.1114 s; 0.05 s of delay leaves 0.0614 s.
        let core = Core {
            fn_hz: 2.0,
            zeta: 0.7,
            ..Core::default()
        };
        let c = compensated_core(&core, 0.05).expect("room left");
        let tau = 2.0 * 0.7 / (std::f64::consts::TAU * 2.0);
        assert!((c.fn_hz - 2.0 * tau / (tau - 0.05)).abs() < 1e-12);
        assert_eq!(c.zeta, 0.7);
        // Less delay: a slower core; no change, or no room: none.
        assert!(compensated_core(&core, -0.05).unwrap().fn_hz < 2.0);
        assert_eq!(compensated_core(&core, 0.0), None);
        assert_eq!(compensated_core(&core, 0.105), None);
    }

    #[test]
    fn shares_run_from_none_to_all_of_the_delay() {
        assert_eq!(shares(0), [0]);
        assert_eq!(shares(5), [0, 1, 2, 3, 4, 5]);
        assert_eq!(shares(20), [0, 3, 6, 9, 12, 15, 18, 20]);
        let p = DeadTimeParams::throttle(6);
        let t = p.with_voltage_delay(usize::MAX).unwrap();
        assert_eq!((t.input_delay(), t.voltage_delay()), (6, 6));
        assert_eq!(p.with_voltage_delay(2).unwrap().voltage_delay(), 2);
    }

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = DeadTimeParams::throttle(16);
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(
            text(&p.finding_params(0.002)),
            r#"{"delay_s":0.032,"delay_samples":16}"#
        );
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(text(&terms), r#"{"delay_s":0.032,"delay_samples":16}"#);
        let p = DeadTimeParams {
            delay_samples: 16,
            sensor_samples: 4,
        };
        assert_eq!(
            text(&p.finding_params(0.002)),
            r#"{"delay_s":0.032,"delay_samples":16,"sensor_delay_samples":4}"#
        );
    }
}
