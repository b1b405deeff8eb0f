//! The worker: windows per operating point, identification, publishing.
//!
//! The worker drains the sampler's queue. For each item it does the window bookkeeping
//! ([`Window`]), and when a window is complete the short hot call — [`Identifier::identify`],
//! which makes no heap allocation — followed by the slow work around it: building the report,
//! publishing the `"model"` line, updating the gain schedule and the latency statistics.
//!
//! Published lines (one JSON object each):
//! - `{"type":"model", "t_s", "operating_point", "level", "first_sample", "samples",
//!   "reason", <the model fields of propid identify --json>}` — `t_s` is the device time of the
//!   window's last sample (unwrapped, s), `operating_point` the throttle level (fraction).
//! - `{"type":"event", "kind", ...}` and `{"type":"warning", "kind", "message", ...}`.
//! - At the end `{"type":"schedule", "models":[...]}`: the last model per operating point (the
//!   gain schedule a flight controller needs), ordered by operating point.
//!
//! Nothing here depends on wall-clock time except the latency measurement, which is reported in
//! the stats line only; the published model lines depend only on the byte stream, so a live run
//! and the replay of its recording publish identical model lines.

use crossbeam_channel::Receiver;
use serde_json::{json, Map, Value};
use std::time::Instant;

use super::item::{EventItem, Item, PlanNote, SampleItem};
use super::publish::Publisher;
use super::quality;
use super::stats::WorkStats;
use super::window::{Reason, Window, WindowView};
use super::DaemonError;

/// Identifies one window. The daemon's implementation wraps the core's workspace.
pub trait Identifier: Send {
    /// The hot call: identifies the window; must not allocate on success.
    fn identify(&mut self, view: &WindowView<'_>) -> Result<(), String>;
    /// The model fields of the last successful identification (allocates; a JSON object).
    fn report(&self) -> Result<Map<String, Value>, String>;
}

/// Latency samples kept (the first ones of a run; enough for p99).
const LATENCY_CAP: usize = 65_536;

/// What the worker hands back when the queue closes.
pub struct WorkerOutcome {
    /// The publisher, still open (the caller adds the stats line and closes it).
    pub publisher: Publisher,
    /// Worker counters.
    pub stats: WorkStats,
    /// Latencies from the last sample of a window to its published line, seconds, sorted.
    pub latencies_s: Vec<f64>,
    /// The first publishing error, if any (publishing continued on the other sinks).
    pub error: Option<DaemonError>,
}

/// The worker's state.
pub struct Worker<I: Identifier> {
    window: Window,
    identifier: I,
    publisher: Publisher,
    stats: WorkStats,
    schedule: Vec<(u32, f64, Map<String, Value>)>,
    latencies_s: Vec<f64>,
    error: Option<DaemonError>,
}

impl<I: Identifier> Worker<I> {
    /// A worker with its window (allocated here, once) and identifier.
    pub fn new(window: Window, identifier: I, publisher: Publisher) -> Worker<I> {
        Worker {
            window,
            identifier,
            publisher,
            stats: WorkStats::default(),
            schedule: Vec::new(),
            latencies_s: Vec::with_capacity(LATENCY_CAP),
            error: None,
        }
    }

    /// Drains the queue until the sampler closes it, then publishes the schedule.
    pub fn run(mut self, rx: Receiver<Item>) -> WorkerOutcome {
        for item in rx.iter() {
            self.handle(item);
        }
        self.finish()
    }

    /// Handles one item.
    pub fn handle(&mut self, item: Item) {
        match item {
            Item::Sample(s) => self.on_sample(&s),
            Item::Gap { before, count } => {
                self.window.on_gap(count);
                self.emit(
                    json!({"type": "event", "kind": "gap", "before": before, "count": count}),
                );
            }
            Item::Segment { boot_id } => {
                let mut done = Vec::new();
                let identifier = &mut self.identifier;
                self.window
                    .on_segment(|v| done.push(identify_one(identifier, v)));
                for d in done {
                    self.publish_model(d);
                }
                self.emit(json!({"type": "event", "kind": "segment", "boot_id": boot_id}));
            }
            Item::Event(e) => self.on_event(&e),
            Item::Plan(n) => self.on_plan(n),
            Item::Notice(n) => {
                let kind = if n.is_warning() { "warning" } else { "event" };
                self.emit(json!({"type": kind, "kind": n.name()}));
            }
        }
    }

    /// Closes the last window and publishes the gain schedule.
    pub fn finish(mut self) -> WorkerOutcome {
        let mut done = Vec::new();
        let identifier = &mut self.identifier;
        self.window
            .finish(|v| done.push(identify_one(identifier, v)));
        for d in done {
            self.publish_model(d);
        }
        self.publish_schedule();
        self.latencies_s.sort_by(f64::total_cmp);
        WorkerOutcome {
            publisher: self.publisher,
            stats: self.stats,
            latencies_s: self.latencies_s,
            error: self.error,
        }
    }

    fn on_sample(&mut self, s: &SampleItem) {
        // Hot path: bookkeeping and identification only; reports are built after.
        let mut done: Option<Done> = None;
        let identifier = &mut self.identifier;
        let outcome = self
            .window
            .on_sample(s, |v| done = Some(identify_one(identifier, v)));
        if outcome.pulse {
            self.stats.pulses += 1;
        }
        if outcome.unannounced_lost > 0 {
            // Only the sampler's full queue drops samples without a gap notice.
            self.emit(json!({"type": "warning", "kind": "overflow_gap",
                "message": "samples dropped by a full sampler queue; masked as missing",
                "before": s.index, "count": outcome.unannounced_lost}));
        }
        if let Some(d) = done {
            self.publish_model(d);
        }
        if outcome.overflowed {
            self.emit(json!({"type": "warning", "kind": "window_full",
                "message": "window filled before K pulses; its samples were discarded",
                "sample_index": s.index}));
        }
    }

    fn on_plan(&mut self, n: PlanNote) {
        let line = match n {
            PlanNote::PulseFired => return,
            PlanNote::Connected { boot_id } => {
                json!({"type": "event", "kind": "connected", "boot_id": boot_id})
            }
            PlanNote::Armed => json!({"type": "event", "kind": "arm_acknowledged"}),
            PlanNote::LevelReached { index, level } => {
                json!({"type": "event", "kind": "level_reached", "index": index, "operating_point": level})
            }
            PlanNote::LevelDone { index, level } => {
                json!({"type": "event", "kind": "level_done", "index": index, "operating_point": level})
            }
            PlanNote::Finished => json!({"type": "event", "kind": "plan_finished"}),
            PlanNote::Stopped => json!({"type": "event", "kind": "stop_acknowledged"}),
            PlanNote::DeviceReset { new_boot_id } => json!({"type": "warning",
                "kind": "device_reset", "boot_id": new_boot_id,
                "message": "the device reset and is disarmed; the plan is over and will not re-arm"}),
            PlanNote::WatchdogTripped => json!({"type": "warning", "kind": "plan_halted_watchdog",
                "message": "the device watchdog stopped the motor; the plan is over"}),
            PlanNote::Refused { command } => json!({"type": "warning", "kind": "command_refused",
                "command": command, "message": "the device refused a command; the plan is over"}),
            PlanNote::LinkFailed { command } => json!({"type": "warning", "kind": "link_failed",
                "command": command, "message": "a command went unanswered after its re-sends"}),
        };
        self.emit(line);
    }

    fn on_event(&mut self, e: &EventItem) {
        let (kind, warning) = match e.code {
            1 | 2 => return, // impulse edges: counted through the samples' flags
            3 => ("watchdog_trip", true),
            4 => ("limit_cutoff", true),
            5 => ("armed", false),
            6 => ("disarmed", false),
            7 => ("tx_overrun", true),
            8 => ("reset_cause", false),
            9 => ("tare_done", false),
            _ => ("unknown_event", true),
        };
        let ty = if warning { "warning" } else { "event" };
        self.emit(
            json!({"type": ty, "kind": kind, "code": e.code, "arg": e.arg,
            "t_s": e.t_us as f64 * 1e-6, "sample_index": e.sample_index}),
        );
    }

    fn publish_model(&mut self, d: Done) {
        let report = match d.result.and_then(|()| self.identifier.report()) {
            Ok(r) => r,
            Err(message) => {
                self.stats.identify_errors += 1;
                self.emit(json!({"type": "warning", "kind": "identification_failed",
                    "message": message, "operating_point": d.level, "t_s": d.t_s}));
                return;
            }
        };
        let mut line = Map::new();
        line.insert("type".into(), json!("model"));
        line.insert("t_s".into(), json!(d.t_s));
        line.insert("operating_point".into(), json!(d.level));
        line.insert("level".into(), json!(d.level_number));
        line.insert("first_sample".into(), json!(d.first_index));
        line.insert("samples".into(), json!(d.samples));
        line.insert("reason".into(), json!(d.reason));
        for (k, v) in &report {
            line.entry(k.clone()).or_insert_with(|| v.clone());
        }
        let reasons = quality::judge(&report);
        if !reasons.is_empty() {
            // not the plant: published for inspection, never as a model nor in the schedule
            line.insert("type".into(), json!("warning"));
            line.insert("kind".into(), json!("model_unreliable"));
            line.insert("reasons".into(), json!(reasons));
            line.insert("message".into(), json!(quality::HINT));
            self.emit(Value::Object(line));
            self.stats.models_unreliable += 1;
            return;
        }
        self.emit(Value::Object(line));
        self.stats.models += 1;
        if let Some(t) = d.last_received {
            if self.latencies_s.len() < LATENCY_CAP {
                self.latencies_s.push(t.elapsed().as_secs_f64());
            }
        }
        match self.schedule.iter_mut().find(|e| e.0 == d.level_number) {
            Some(e) => e.2 = report,
            None => self.schedule.push((d.level_number, d.level, report)),
        }
    }

    fn publish_schedule(&mut self) {
        let mut rows: Vec<&(u32, f64, Map<String, Value>)> = self.schedule.iter().collect();
        rows.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        let models: Vec<Value> = rows
            .iter()
            .map(|(_, level, m)| {
                let get = |k: &str| m.get(k).cloned().unwrap_or(Value::Null);
                json!({"operating_point": level, "order": get("order"), "fn_hz": get("fn_hz"),
                    "zeta": get("zeta"), "dc_gain": get("dc_gain"),
                    "time_constants_s": get("time_constants_s"), "pulses": get("pulses"),
                    "uncertainty": get("uncertainty")})
            })
            .collect();
        self.emit(json!({"type": "schedule", "models": models}));
    }

    fn emit(&mut self, v: Value) {
        if let Err(e) = self.publisher.publish_json(&v) {
            self.error.get_or_insert(e);
        }
    }
}

/// An identification done in the hot path, waiting to be published.
struct Done {
    result: Result<(), String>,
    t_s: f64,
    level: f64,
    level_number: u32,
    first_index: u64,
    samples: usize,
    reason: &'static str,
    last_received: Option<Instant>,
}

fn reason_name(r: Reason) -> &'static str {
    match r {
        Reason::Pulses => "pulses",
        Reason::LevelEnd => "level_end",
        Reason::Full => "window_full",
        Reason::Segment => "segment",
        Reason::End => "end",
    }
}

/// The hot call and the facts needed to publish it later (no allocation).
fn identify_one<I: Identifier>(id: &mut I, v: &WindowView<'_>) -> Done {
    Done {
        result: id.identify(v),
        t_s: v.last_t_us as f64 * 1e-6,
        level: v.level,
        level_number: v.level_number,
        first_index: v.first_index,
        samples: v.input.len(),
        reason: reason_name(v.reason),
        last_received: v.last_received,
    }
}

#[cfg(test)]
mod pinned;
#[cfg(test)]
mod tests;
