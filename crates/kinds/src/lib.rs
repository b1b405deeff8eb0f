//! The analyses of the experiment kinds other than pulses (`[experiment] kind`: `staircase`,
//! `ramp`, `chirp`; `docs/experiment-kinds.md`) on a run's decoded samples: the applied
//! throttle the device reports and its outputs, nothing else, so that `propid run` and the
//! `propid replay` of its recording (with the same configuration) publish the same lines.
//!
//! - **staircase**: each step's figures ([`propid_numerics::step_response`]) as soon as the
//!   hold after it is over (the next step starts), a [`Published::Step`]; at the end the
//!   static map of each output over the holds ([`propid_numerics::stand`]) and the step
//!   figures' medians per direction ([`propid_numerics::step_directions`]).
//! - **ramp**: at the end, the static map of each leg (up to the highest throttle, and back)
//!   over the ramp's windows, and their hysteresis ([`hysteresis`]): the down leg's output
//!   against the up leg's at the same throttle.
//! - **chirp**: at the end, the frequency response of the thrust to the applied throttle over
//!   the sweep ([`propid_numerics::frequency_response`]: H1 and coherence, `peak_hz`,
//!   `bandwidth_hz`, phase delay, a fitted second-order-plus-dead-time model).
//!
//! Pure: samples in, typed results out ([`Analysis::push`], [`Analysis::finish`]).

use std::collections::BTreeMap;

use propid_numerics::frequency_response::{frequency_response, FrequencyResponse};
use propid_numerics::segment::{Command, SegmentRules};
use propid_numerics::stand::{stand_figures, OutputChannel, StaticMap};
use propid_numerics::step_directions::{by_direction, DirectionFigures};
use propid_numerics::step_response::StepFigures;
use propid_wire::experiment::{ExperimentConfig, Kind};
use serde::Serialize;

mod hysteresis;
pub mod report;
pub use hysteresis::{hysteresis, Hysteresis};

/// A throttle change between two samples (fraction) taken for a new step of a staircase.
pub const STEP_CHANGE: f64 = 0.005;
/// Longest run of missing samples filled in (a gap longer than this starts the record over
/// at its end: the analysis sees one stretch of uniformly sampled data).
pub const MAX_GAP: u64 = 10_000;

/// One decoded sample (NaN = not measured).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Sample index (the device's count, unwrapped): gaps are filled with missing samples.
    pub index: u64,
    /// Device time, µs.
    pub t_us: u64,
    /// Applied throttle, fraction.
    pub throttle: f64,
    /// Thrust, N.
    pub thrust: f64,
    /// Rotor speed, rpm.
    pub rpm: f64,
    /// Current, A.
    pub current: f64,
}

/// One step's figures, published as it comes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepLine {
    /// The experiment kind.
    pub kind: Kind,
    /// Step number in the run, from 0.
    pub index: usize,
    /// The output the figures are of (`thrust`).
    pub output: &'static str,
    /// The figures (`t_s` from the analysed record's start).
    #[serde(flatten)]
    pub figures: StepFigures,
}

/// The static map of one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticMapLine {
    /// The experiment kind.
    pub kind: Kind,
    /// `thrust`, `rpm` or `current`.
    pub output: &'static str,
    /// A ramp's leg (`up`, `down`); omitted for a staircase (its holds up and down together).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leg: Option<&'static str>,
    /// The map: `unit`, `levels` [{`throttle`, `mean`, `std`, `samples`}], `power`, `expo`,
    /// ... as `identify`'s.
    #[serde(flatten)]
    pub map: StaticMap,
    /// A staircase: the step figures' medians per direction (the `output`'s steps, thrust).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub directions: BTreeMap<&'static str, DirectionFigures>,
    /// A ramp's down leg: how far it lies from the up leg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hysteresis: Option<Hysteresis>,
}

/// The frequency response of the thrust over a chirp.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrequencyResponseLine {
    /// The experiment kind (`chirp`).
    pub kind: Kind,
    /// `thrust`.
    pub output: &'static str,
    /// The level swept about.
    pub level: f64,
    /// Sample period, s.
    pub dt_s: f64,
    /// The response and its figures.
    #[serde(flatten)]
    pub response: FrequencyResponse,
}

/// A result to publish.
#[derive(Debug, Clone, PartialEq)]
pub enum Published {
    /// `"step"`.
    Step(StepLine),
    /// `"static_map"`.
    StaticMap(StaticMapLine),
    /// `"frequency_response"`.
    FrequencyResponse(FrequencyResponseLine),
}

/// The analysis of one run.
#[derive(Debug, Clone)]
pub struct Analysis {
    cfg: ExperimentConfig,
    last_index: Option<u64>,
    first_t_us: Option<u64>,
    last_t_us: u64,
    u: Vec<f64>,
    thrust: Vec<f64>,
    rpm: Vec<f64>,
    current: Vec<f64>,
    steps_published: usize,
    /// Everything published so far (the run report's material).
    published: Vec<Published>,
}

impl Analysis {
    /// The analysis of a run with `cfg`'s kind; `None` for pulses (the window models are
    /// theirs).
    pub fn new(cfg: &ExperimentConfig) -> Option<Analysis> {
        (cfg.kind != Kind::Pulses).then(|| Analysis {
            cfg: cfg.clone(),
            last_index: None,
            first_t_us: None,
            last_t_us: 0,
            u: Vec::new(),
            thrust: Vec::new(),
            rpm: Vec::new(),
            current: Vec::new(),
            steps_published: 0,
            published: Vec::new(),
        })
    }

    /// The kind analysed.
    pub fn kind(&self) -> Kind {
        self.cfg.kind
    }

    /// Everything published so far.
    pub fn published(&self) -> &[Published] {
        &self.published
    }

    /// One sample; what it completes (a staircase's step).
    pub fn push(&mut self, s: Sample) -> Vec<Published> {
        match self.last_index {
            Some(last) if s.index > last + 1 && s.index - last - 1 <= MAX_GAP => {
                let held = self.u.last().copied().unwrap_or(s.throttle);
                for _ in last + 1..s.index {
                    self.u.push(held);
                    self.thrust.push(f64::NAN);
                    self.rpm.push(f64::NAN);
                    self.current.push(f64::NAN);
                }
            }
            Some(last) if s.index <= last || s.index - last - 1 > MAX_GAP => {
                // a new boot or a long gap: what came before is its own record
                let mut out = self.finish();
                self.clear();
                self.steps_published = 0;
                out.extend(self.push(s));
                return out;
            }
            _ => {}
        }
        self.last_index = Some(s.index);
        self.first_t_us.get_or_insert(s.t_us);
        self.last_t_us = s.t_us;
        let mut out = Vec::new();
        let prev = self.u.last().copied();
        if self.cfg.kind == Kind::Staircase
            && prev.is_some_and(|p| (s.throttle - p).abs() > STEP_CHANGE)
        {
            out = self.new_steps();
        }
        self.u.push(s.throttle);
        self.thrust.push(s.thrust);
        self.rpm.push(s.rpm);
        self.current.push(s.current);
        self.published.extend(out.iter().cloned());
        out
    }

    fn clear(&mut self) {
        self.last_index = None;
        self.first_t_us = None;
        self.u.clear();
        self.thrust.clear();
        self.rpm.clear();
        self.current.clear();
    }

    /// Sample period, s: the device time over the samples (1 ms without two).
    fn dt_s(&self) -> f64 {
        let n = self.u.len();
        match self.first_t_us {
            Some(t0) if n > 1 && self.last_t_us > t0 => {
                (self.last_t_us - t0) as f64 * 1e-6 / (n - 1) as f64
            }
            _ => 1e-3,
        }
    }

    /// The steps of the record so far whose holds are over, not yet published.
    fn new_steps(&mut self) -> Vec<Published> {
        let dt = self.dt_s();
        let rules = SegmentRules::for_record(dt, true);
        let figs = stand_figures(Command::new(&self.u), dt, &rules, &self.thrust, &[]);
        let mut out = Vec::new();
        for f in figs.steps.into_iter().skip(self.steps_published) {
            out.push(Published::Step(StepLine {
                kind: self.cfg.kind,
                index: self.steps_published,
                output: "thrust",
                figures: f,
            }));
            self.steps_published += 1;
        }
        out
    }

    fn outputs(&self) -> Vec<OutputChannel<'_>> {
        let mut o = vec![OutputChannel {
            key: "thrust",
            unit: "N",
            y: &self.thrust,
        }];
        for (key, unit, y) in [("rpm", "rpm", &self.rpm), ("current", "A", &self.current)] {
            if y.iter().any(|v| v.is_finite()) {
                o.push(OutputChannel { key, unit, y });
            }
        }
        o
    }

    /// The run is over: what is left to publish (module doc).
    pub fn finish(&mut self) -> Vec<Published> {
        let out = match self.cfg.kind {
            Kind::Pulses => Vec::new(),
            Kind::Staircase => self.finish_staircase(),
            Kind::Ramp => self.finish_ramp(),
            Kind::Chirp => self.finish_chirp(),
        };
        self.published.extend(out.iter().cloned());
        out
    }

    fn finish_staircase(&mut self) -> Vec<Published> {
        if self.u.len() < 2 {
            return Vec::new();
        }
        // the last hold is over too: its step, then the maps over every hold
        let mut out = self.new_steps();
        let dt = self.dt_s();
        let rules = SegmentRules::for_record(dt, true);
        let outputs = self.outputs();
        let figs = stand_figures(Command::new(&self.u), dt, &rules, &self.thrust, &outputs);
        let directions = by_direction(&figs.steps);
        for o in &outputs {
            if let Some(map) = figs.static_map.get(o.key) {
                out.push(Published::StaticMap(StaticMapLine {
                    kind: Kind::Staircase,
                    output: o.key,
                    leg: None,
                    map: map.clone(),
                    directions: if o.key == "thrust" {
                        directions.clone()
                    } else {
                        BTreeMap::new()
                    },
                    hysteresis: None,
                }));
            }
        }
        out
    }

    fn finish_ramp(&mut self) -> Vec<Published> {
        let n = self.u.len();
        if n < 4 {
            return Vec::new();
        }
        // the top: the first sample at the highest throttle; the down leg starts after the
        // last one
        let top = self.u.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let first_top = self
            .u
            .iter()
            .position(|&v| v >= top - STEP_CHANGE)
            .unwrap_or(0);
        let last_top = self
            .u
            .iter()
            .rposition(|&v| v >= top - STEP_CHANGE)
            .unwrap_or(n - 1);
        let dt = self.dt_s();
        let rules = SegmentRules::for_record(dt, true);
        let mut out = Vec::new();
        let mut up_maps: BTreeMap<&'static str, StaticMap> = BTreeMap::new();
        for (leg, range) in [("up", 0..first_top + 1), ("down", last_top..n)] {
            let u = &self.u[range.clone()];
            let outputs: Vec<OutputChannel<'_>> = self
                .outputs()
                .into_iter()
                .map(|o| OutputChannel {
                    y: &o.y[range.clone()],
                    ..o
                })
                .collect();
            let figs = stand_figures(Command::new(u), dt, &rules, outputs[0].y, &outputs);
            for o in &outputs {
                let Some(map) = figs.static_map.get(o.key) else {
                    continue;
                };
                let hyst = match leg {
                    "down" => up_maps
                        .get(o.key)
                        .and_then(|up| hysteresis(&up.levels, &map.levels)),
                    _ => {
                        up_maps.insert(o.key, map.clone());
                        None
                    }
                };
                out.push(Published::StaticMap(StaticMapLine {
                    kind: Kind::Ramp,
                    output: o.key,
                    leg: Some(leg),
                    map: map.clone(),
                    directions: BTreeMap::new(),
                    hysteresis: hyst,
                }));
            }
        }
        out
    }

    fn finish_chirp(&mut self) -> Vec<Published> {
        let level = self.cfg.levels[0];
        let band = self.cfg.chirp_amplitude + 0.01;
        // from the end of the ramp to the level to the start of the ramp down
        let Some(start) = self
            .u
            .iter()
            .position(|&v| (v - level).abs() <= STEP_CHANGE)
        else {
            return Vec::new();
        };
        let end = self
            .u
            .iter()
            .rposition(|&v| (v - level).abs() <= band)
            .unwrap_or(start);
        let (u, y) = (&self.u[start..=end], &self.thrust[start..=end]);
        // missing thrust samples: held (a sensor slower than the stream)
        let mut held = Vec::with_capacity(y.len());
        let mut last = y.iter().copied().find(|v| v.is_finite()).unwrap_or(0.0);
        for &v in y {
            if v.is_finite() {
                last = v;
            }
            held.push(last);
        }
        let dt = self.dt_s();
        let Some(response) =
            frequency_response(u, &held, dt, self.cfg.chirp_f0_hz, self.cfg.chirp_f1_hz)
        else {
            return Vec::new();
        };
        vec![Published::FrequencyResponse(FrequencyResponseLine {
            kind: Kind::Chirp,
            output: "thrust",
            level,
            dt_s: dt,
            response,
        })]
    }
}

#[cfg(test)]
mod tests;
