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

    /// Delays up to [`max_delay_samples`]. A coarse
    /// grid (every 4th delay) with a short refit of every parameter at each delay (the
    /// baseline's `fn` and `ζ` have absorbed part of the delay), then every delay around the
    /// best with a longer refit.
    fn extend(&self, ctx: &Ctx, cur: &Fit) -> Option<Fit> {
        let dmax = max_delay_samples(ctx.sig.dt_s, ctx.est.len());
        let lm_at = |d: usize, iters: usize| {
            let start = cur.model.with(DeadTimeParams { delay_samples: d });
            ctx.lm(&start, iters)
        };
        let coarse = (1..=dmax).step_by(4).map(|d| (d, lm_at(d, 8).sse));
        let d0 = coarse.min_by(|a, b| a.1.total_cmp(&b.1))?.0;
        let mut best: Option<Fit> = None;
        for d in d0.saturating_sub(4).max(1)..=(d0 + 4).min(dmax) {
            let f = lm_at(d, 30);
            if best.as_ref().map_or(true, |b| f.sse < b.sse) {
                best = Some(f);
            }
        }
        best
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
