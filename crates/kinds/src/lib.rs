//! The analyses of the experiment kinds other than pulses (`[experiment] kind`: `staircase`,
//! `ramp`, `chirp`; `docs/experiment-kinds.md`) on a run's decoded samples: the applied
//! throttle the device reports and its outputs, nothing else, so that `propid run` and the
//! `propid replay` of its recording (with the same configuration) publish the same lines.
//!
//! - **staircase**: each step's figures ([`propid_numerics::step_response`]) as soon as the
//!   hold after it is over (the next step starts), a [`Published::Step`], looked for in the
//!   record from the last published step's start only (a run boundary: the runs after it, so
//!   the steps and their figures, are the whole record's); at the end the
//!   static map of each output over the holds ([`propid_numerics::stand`]) and the step
//!   figures' medians per direction ([`propid_numerics::step_directions`]).
//! - **ramp**: at the end, the static map of each leg (up to the highest throttle, and back)
//!   over the ramp's windows, and their hysteresis ([`hysteresis`]): the down leg's output
//!   against the up leg's at the same throttle.
//! - **chirp**: at the end, the frequency response of the thrust to the applied throttle over
//!   the sweep ([`propid_numerics::frequency_response`]: H1 and coherence, `peak_hz`,
//!   `bandwidth_hz`, phase delay, a fitted second-order-plus-dead-time model).
//!
//! - **pulses**: nothing published here (the window models are the daemon's); the steady
//!   output at each operating point is accumulated ([`pulse_levels`]) for the run report's
//!   thrust curve, and the models the daemon publishes are kept for it
//!   ([`Analysis::add_model`]).
//!
//! The record's buffers are sized once, at the second sample, for the program's length at the
//! sample period seen ([`RESERVE_CAP`] at most), so that a run of the configured length grows
//! none.
//!
//! Pure: samples in, typed results out ([`Analysis::push`], [`Analysis::finish`]); the run
//! report's material at the end ([`Analysis::into_material`]).

use std::collections::BTreeMap;

use propid_numerics::frequency_response::{frequency_response, FrequencyResponse};
use propid_numerics::segment::{steps, Command, SegmentRules, Step};
use propid_numerics::stand::SAMPLES_ARE_STEADY;
use propid_numerics::stand::{
    add_thrust_coefficient, stand_figures, static_map, OutputChannel, StaticMap,
};
use propid_numerics::step_directions::{by_direction, DirectionFigures};
use propid_numerics::step_response::{step_figures, StepFigures};
use propid_numerics::ModelReport;
use propid_wire::experiment::{ExperimentConfig, Kind};
use serde::Serialize;

mod hysteresis;
pub mod pulse_levels;
pub mod report;
pub use hysteresis::{hysteresis, Hysteresis};

/// A throttle change between two samples (fraction) taken for a new step of a staircase.
pub const STEP_CHANGE: f64 = 0.005;
/// Longest run of missing samples filled in (a gap longer than this starts the record over
/// at its end: the analysis sees one stretch of uniformly sampled data).
pub const MAX_GAP: u64 = 10_000;

/// Most samples reserved per buffer up front (a longer run grows its buffers).
pub const RESERVE_CAP: usize = 4_000_000;

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

/// A model identified by an experiment kind: the fields of the daemon's pulse `model` line
/// (`t_s`, `operating_point`, `level`, `first_sample`, `samples`, `reason`, `path` and the
/// identification core's model fields), with the kind, the output and what the fit adds.
/// A chirp's is the second-order-plus-dead-time model fitted to its frequency response
/// (`path`: `frequency_response`; [`FrequencyResponse::model`] as the core reports a model:
/// `SecondOrder::to_report`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelLine {
    /// The experiment kind.
    pub kind: Kind,
    /// `thrust`.
    pub output: &'static str,
    /// Device time of the analysed stretch's last sample, s.
    pub t_s: f64,
    /// The operating point (the level swept about), fraction.
    pub operating_point: f64,
    /// The operating point's number (0: a chirp has one).
    pub level: u32,
    /// Device sample index of the analysed stretch's first sample.
    pub first_sample: u64,
    /// Samples analysed.
    pub samples: usize,
    /// Why it was identified: `end` (the run is over).
    pub reason: &'static str,
    /// How: `frequency_response` (fitted to the response's coherent bins).
    pub path: &'static str,
    /// Dead time `T` of the fit, s (not in `a`, `b`, `c`, `d`).
    pub dead_time_s: f64,
    /// RMS of the fit's weighted relative residual.
    pub rms_rel_error: f64,
    /// The model (`propid identify --json`'s model fields).
    #[serde(flatten)]
    pub report: ModelReport,
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
    /// `"model"`.
    Model(ModelLine),
}

/// A model in short, for the run report (a pulses run's window models, a chirp's fit).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelRow {
    /// Device time of the model's last sample, s.
    pub t_s: f64,
    /// Its operating point, fraction.
    pub operating_point: f64,
    /// Natural frequency, Hz.
    pub fn_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// DC gain (the first output's), output units per unit throttle.
    pub dc_gain: f64,
    /// The longest real-pole time constant, s.
    pub tau_s: Option<f64>,
    /// Pulses averaged (0 for a chirp's fit).
    pub pulses: usize,
}

impl ModelRow {
    /// The row of `report` at `operating_point`, its last sample at `t_s`.
    pub fn new(t_s: f64, operating_point: f64, report: &ModelReport) -> ModelRow {
        use propid_numerics::report::Gain;
        let dc_gain = match &report.dc_gain {
            Gain::Scalar(g) => *g,
            Gain::List(v) => v.first().copied().unwrap_or(f64::NAN),
            Gain::Matrix(m) => m
                .first()
                .and_then(|r| r.first())
                .copied()
                .unwrap_or(f64::NAN),
        };
        ModelRow {
            t_s,
            operating_point,
            fn_hz: report.fn_hz,
            zeta: report.zeta,
            dc_gain,
            tau_s: report.time_constants_s.first().copied(),
            pulses: report.pulses,
        }
    }
}

/// What a run report is made of: the kind, every line the analysis published (for pulses the
/// static maps over the operating points too, which a pulses run does not publish), the models.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The experiment kind.
    pub kind: Kind,
    /// The lines (and a pulses run's maps).
    pub published: Vec<Published>,
    /// The models, in the order identified.
    pub models: Vec<ModelRow>,
}

/// The analysis of one run.
#[derive(Debug, Clone)]
pub struct Analysis {
    cfg: ExperimentConfig,
    last_index: Option<u64>,
    /// Device index of the record's first sample.
    first_index: u64,
    first_t_us: Option<u64>,
    last_t_us: u64,
    u: Vec<f64>,
    thrust: Vec<f64>,
    rpm: Vec<f64>,
    current: Vec<f64>,
    steps_published: usize,
    /// Where the next step is looked for: the last published step's start (0 before one).
    step_from: usize,
    /// The program's length, ms (the buffers' size at the second sample).
    program_ms: u64,
    /// Everything published so far (the run report's material).
    published: Vec<Published>,
    /// A pulses run's steady levels.
    pulse_levels: Option<pulse_levels::PulseLevels>,
    /// The models (the run report's).
    models: Vec<ModelRow>,
}

impl Analysis {
    /// The analysis of a run with `cfg`'s kind (module doc).
    pub fn new(cfg: &ExperimentConfig) -> Analysis {
        Analysis {
            cfg: cfg.clone(),
            last_index: None,
            first_index: 0,
            first_t_us: None,
            last_t_us: 0,
            u: Vec::new(),
            thrust: Vec::new(),
            rpm: Vec::new(),
            current: Vec::new(),
            steps_published: 0,
            step_from: 0,
            program_ms: propid_wire::experiment::program::program(cfg).1,
            published: Vec::new(),
            pulse_levels: (cfg.kind == Kind::Pulses).then(|| pulse_levels::PulseLevels::new(cfg)),
            models: Vec::new(),
        }
    }

    /// A model identified by the daemon (a pulses run's window), for the run report.
    pub fn add_model(&mut self, row: ModelRow) {
        self.models.push(row);
    }

    /// The run report's material (after [`Analysis::finish`]).
    pub fn into_material(self) -> Material {
        Material {
            kind: self.cfg.kind,
            published: self.published,
            models: self.models,
        }
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
        if let Some(p) = self.pulse_levels.as_mut() {
            p.push(&s);
            return Vec::new();
        }
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
        if self.u.len() == 1 {
            self.reserve(s.t_us);
        }
        self.last_index = Some(s.index);
        if self.first_t_us.is_none() {
            self.first_t_us = Some(s.t_us);
            self.first_index = s.index;
        }
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

    /// Sizes the buffers for the program at the period from the first sample to the second
    /// (at `t_us`), plus 10 s.
    fn reserve(&mut self, t_us: u64) {
        let dt_us = t_us.saturating_sub(self.first_t_us.unwrap_or(t_us)).max(1);
        let n = ((self.program_ms + 10_000) * 1000 / dt_us).min(RESERVE_CAP as u64) as usize;
        for b in [
            &mut self.u,
            &mut self.thrust,
            &mut self.rpm,
            &mut self.current,
        ] {
            b.reserve(n.saturating_sub(b.len()));
        }
    }

    fn clear(&mut self) {
        self.step_from = 0;
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

    /// Device time of the record's sample at position `k`, s (the record's period).
    fn t_s_at(&self, k: usize) -> f64 {
        self.first_t_us.unwrap_or(0) as f64 * 1e-6 + k as f64 * self.dt_s()
    }

    /// The steps of the record so far whose holds are over, not yet published: the steps of
    /// the record from the last published step's start (module doc), timed on the whole
    /// record as [`stand_figures`] times them.
    fn new_steps(&mut self) -> Vec<Published> {
        let dt = self.dt_s();
        let rules = SegmentRules::for_record(dt, true);
        let w = self.step_from;
        let mut out = Vec::new();
        for st in steps(Command::new(&self.u[w..]), &rules) {
            let st = Step {
                before_start: st.before_start + w,
                at: st.at + w,
                after_end: st.after_end + w,
                ..st
            };
            if self.steps_published > 0 && st.at <= w {
                continue; // published
            }
            let mut f = step_figures(&self.thrust, dt, &st);
            if rules.samples_are_steady() {
                f = f.unsupported(SAMPLES_ARE_STEADY);
            }
            self.step_from = st.at;
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
            Kind::Pulses => {
                // the report's thrust curve, not published
                let maps = self.pulse_maps();
                self.published.extend(maps);
                return Vec::new();
            }
            Kind::Staircase => self.finish_staircase(),
            Kind::Ramp => self.finish_ramp(),
            Kind::Chirp => self.finish_chirp(),
        };
        self.published.extend(out.iter().cloned());
        out
    }

    /// A pulses run's static maps over its operating points ([`pulse_levels`]).
    fn pulse_maps(&self) -> Vec<Published> {
        let Some(p) = &self.pulse_levels else {
            return Vec::new();
        };
        let mut maps = BTreeMap::new();
        for (o, &(key, unit)) in pulse_levels::OUTPUTS.iter().enumerate() {
            let lv = p.levels(o);
            if !lv.is_empty() {
                maps.insert(key, static_map(unit, lv, Vec::new()));
            }
        }
        add_thrust_coefficient(&mut maps);
        // thrust, rpm, current: the order a staircase publishes them in
        pulse_levels::OUTPUTS
            .iter()
            .filter_map(|&(output, _)| Some((output, maps.remove(output)?)))
            .map(|(output, map)| {
                Published::StaticMap(StaticMapLine {
                    kind: Kind::Pulses,
                    output,
                    leg: None,
                    map,
                    directions: BTreeMap::new(),
                    hysteresis: None,
                })
            })
            .collect()
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
        let model = response.model.as_ref().map(|m| {
            let report = m.to_report(dt);
            self.models
                .push(ModelRow::new(self.t_s_at(end), level, &report));
            Published::Model(ModelLine {
                kind: Kind::Chirp,
                output: "thrust",
                t_s: self.t_s_at(end),
                operating_point: level,
                level: 0,
                first_sample: self.first_index + start as u64,
                samples: end + 1 - start,
                reason: "end",
                path: "frequency_response",
                dead_time_s: m.dead_time_s,
                rms_rel_error: m.rms_rel_error,
                report,
            })
        });
        let mut out = vec![Published::FrequencyResponse(FrequencyResponseLine {
            kind: Kind::Chirp,
            output: "thrust",
            level,
            dt_s: dt,
            response,
        })];
        out.extend(model);
        out
    }
}

#[cfg(test)]
mod tests;
