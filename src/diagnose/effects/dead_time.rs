//! `dead_time`: a transport delay of the throttle (ESC update, filtering, logging),
//! `v_k = u_{k−d}` with `d` whole samples (the first sample held before the record starts).

use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::diagnose::ctx::Ctx;
use crate::diagnose::effect::{to_map, Effect, Place, Term};
use crate::diagnose::fit::Fit;
use crate::diagnose::model::{Core, Signals};

/// The published name.
pub const NAME: &str = "dead_time";
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

/// The catalogue entry.
#[derive(Debug, Clone, Copy)]
pub struct DeadTime;

/// The fitted delay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadTimeParams {
    /// Delay `d`, whole samples (≥ 1 once fitted).
    pub delay_samples: usize,
}

/// The finding's published parameters.
#[derive(Serialize)]
struct Published {
    /// Delay, seconds.
    delay_s: f64,
    /// Delay, samples.
    delay_samples: usize,
}

impl Effect for DeadTime {
    fn name(&self) -> &'static str {
        NAME
    }

    /// Delays up to [`max_delay_samples`], each tried with every parameter of the current
    /// model refitted jointly (the core's `fn` and `ζ` have absorbed part of the delay, and
    /// the other effects' parameters shift with it). A coarse grid with a short refit, then
    /// every delay around the best [`FINE_STARTS`] coarse delays with a longer refit.
    ///
    /// The coarse step is [`coarse_step`]: the SSE as a function of the delay is not smooth
    /// when the core rings (a delay of one period of the core's mode fits almost as well as
    /// none, a half period fits worst), so the grid must sample that period; a step of 4 on a
    /// mode of 8 samples per period skips the true delay's narrow valley and lands a whole
    /// period later (Silverbox at 610 Hz, a 65 Hz resonance: 3 samples found as 11).
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let dmax = max_delay_samples(ctx.sig.dt_s, ctx.est.len());
        let lm_at = |d: usize, iters: usize| {
            let start = cur.model.with(DeadTimeParams { delay_samples: d });
            ctx.lm(&start, iters)
        };
        let step = coarse_step(cur.model.core.fn_hz, ctx.sig.dt_s);
        let mut coarse: Vec<(usize, f64)> = (1..=dmax)
            .step_by(step)
            .map(|d| (d, lm_at(d, 8).sse))
            .collect();
        coarse.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut fine: Vec<usize> = coarse
            .iter()
            .take(FINE_STARTS)
            .flat_map(|&(d0, _)| d0.saturating_sub(step).max(1)..=(d0 + step).min(dmax))
            .collect();
        fine.sort_unstable();
        fine.dedup();
        let mut best: Option<Fit> = None;
        for d in fine {
            let f = lm_at(d, 30);
            if best.as_ref().map_or(true, |b| f.sse < b.sse) {
                best = Some(f);
            }
        }
        best
    }
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
    fn name(&self) -> &'static str {
        NAME
    }

    fn place(&self) -> Place {
        Place::InputShift
    }

    fn clone_box(&self) -> Box<dyn Term> {
        Box::new(*self)
    }

    fn shape_input(&self, v: &mut [f64], _sig: &Signals) {
        let d = self.delay_samples;
        for k in (1..v.len()).rev() {
            v[k] = v[k.saturating_sub(d)];
        }
    }

    fn terms(&self, dt_s: f64, terms: &mut Map<String, Value>) {
        if self.delay_samples > 0 {
            terms.insert("delay_samples".into(), json!(self.delay_samples));
            terms.insert("delay_s".into(), json!(self.delay_s(dt_s)));
        }
    }

    fn finding_params(&self, dt_s: f64) -> Map<String, Value> {
        to_map(Published {
            delay_s: self.delay_s(dt_s),
            delay_samples: self.delay_samples,
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
        DeadTimeParams { delay_samples: 2 }.shape_input(&mut v, &sig);
        assert_eq!(v, [1.0, 1.0, 1.0, 2.0, 3.0]);
    }

    #[test]
    fn the_published_parameters_keep_their_names() {
        let p = DeadTimeParams { delay_samples: 16 };
        let text = |m: &Map<String, Value>| serde_json::to_string(m).unwrap();
        assert_eq!(
            text(&p.finding_params(0.002)),
            r#"{"delay_s":0.032,"delay_samples":16}"#
        );
        let mut terms = Map::new();
        p.terms(0.002, &mut terms);
        assert_eq!(text(&terms), r#"{"delay_s":0.032,"delay_samples":16}"#);
    }
}
