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
mod tests {
    use super::*;
    use crate::daemon::item::flags;
    use crate::daemon::window::OutputChannel;

    /// A fake identifier: reports the window length and pulse count as the "model".
    struct Fake {
        last: Option<(usize, usize)>,
        fail_every: usize,
        /// Every n-th model has an unstable pole (0 = never).
        unstable_every: usize,
        calls: usize,
    }

    impl Identifier for Fake {
        fn identify(&mut self, v: &WindowView<'_>) -> Result<(), String> {
            self.calls += 1;
            if self.fail_every > 0 && self.calls % self.fail_every == 0 {
                return Err("no pulse found".into());
            }
            self.last = Some((v.input.len(), v.pulse_starts.len()));
            Ok(())
        }
        fn report(&self) -> Result<Map<String, Value>, String> {
            let (n, p) = self.last.ok_or("nothing")?;
            let unstable = self.unstable_every > 0 && self.calls % self.unstable_every == 0;
            let re = if unstable { 3.0 } else { -30.0 };
            let v = json!({"order": 2, "fn_hz": n as f64, "zeta": 0.5, "dc_gain": 1.0,
                "pulses": p, "poles_s": [[re, 40.0], [re, -40.0]]});
            Ok(v.as_object().unwrap().clone())
        }
    }

    fn sample(index: u64, raw: u16, f: u16) -> Item {
        Item::Sample(SampleItem {
            index,
            t_us: index * 1000,
            throttle_raw: raw,
            flags: f,
            thrust_n: 1.0,
            torque_nm: 0.0,
            rpm: 0.0,
            received: Instant::now(),
        })
    }

    fn run_levels(fail_every: usize, unstable_every: usize) -> Vec<Value> {
        let (publisher, lines) = Publisher::capture();
        let fake = Fake {
            last: None,
            fail_every,
            unstable_every,
            calls: 0,
        };
        let window = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
        let (tx, rx) = crossbeam_channel::bounded(100_000);
        let mut i = 0;
        for level in [3000u16, 4500, 6000] {
            for rel in 0..400u64 {
                let pulse = rel % 100 == 50;
                let f = if pulse { flags::IMPULSE_ACTIVE } else { 0 };
                let raw = if pulse { level + 800 } else { level };
                tx.send(sample(i, raw, f)).unwrap();
                i += 1;
            }
            for _ in 0..10 {
                tx.send(sample(i, level, flags::RAMP_ACTIVE)).unwrap();
                i += 1;
            }
        }
        tx.send(Item::Event(EventItem {
            code: 3,
            arg: 0,
            t_us: 5,
            sample_index: 5,
        }))
        .unwrap();
        drop(tx);
        let out = Worker::new(window, fake, publisher).run(rx);
        assert_eq!(out.stats.pulses, 12);
        let v = lines
            .lock()
            .unwrap()
            .iter()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        v
    }

    #[test]
    fn publishes_models_per_level_and_the_schedule() {
        let lines = run_levels(0, 0);
        let models: Vec<&Value> = lines.iter().filter(|l| l["type"] == "model").collect();
        // 4 pulses per level, K = 2: one model at pulse 3, one at the level end.
        assert_eq!(models.len(), 6);
        assert_eq!(models[0]["operating_point"], 0.3);
        assert_eq!(models[0]["reason"], "pulses");
        assert_eq!(models[1]["reason"], "level_end");
        assert_eq!(models[0]["pulses"], 2);
        assert_eq!(models[0]["order"], 2);
        assert!(lines
            .iter()
            .any(|l| l["type"] == "warning" && l["kind"] == "watchdog_trip"));
        let sched = lines.last().unwrap();
        assert_eq!(sched["type"], "schedule");
        let rows = sched["models"].as_array().unwrap();
        assert_eq!(rows.len(), 3);
        assert_eq!(rows[2]["operating_point"], 0.6);
    }

    #[test]
    fn an_unreliable_model_is_a_warning_and_stays_out_of_the_schedule() {
        // models 2, 4, 6 (the level-end one of each level) have an unstable pole
        let lines = run_levels(0, 2);
        let models: Vec<&Value> = lines.iter().filter(|l| l["type"] == "model").collect();
        assert_eq!(models.len(), 3);
        assert!(models.iter().all(|m| m["reason"] == "pulses"));
        let bad: Vec<&Value> = lines
            .iter()
            .filter(|l| l["kind"] == "model_unreliable")
            .collect();
        assert_eq!(bad.len(), 3);
        assert_eq!(bad[0]["type"], "warning");
        assert_eq!(bad[0]["reasons"], json!(["unstable_pole"]));
        assert_eq!(
            bad[0]["reason"], "level_end",
            "the numbers are kept for inspection"
        );
        // the schedule keeps each level's last reliable model
        let sched = lines.last().unwrap();
        assert_eq!(sched["type"], "schedule");
        let rows = sched["models"].as_array().unwrap();
        assert_eq!(rows.len(), 3);
        for (row, m) in rows.iter().zip(&models) {
            assert_eq!(row["fn_hz"], m["fn_hz"]);
        }
    }

    #[test]
    fn overflow_hole_inside_a_pulse_window_is_masked_and_reported() {
        let (publisher, lines) = Publisher::capture();
        struct Masked(Vec<usize>);
        impl Identifier for Masked {
            fn identify(&mut self, v: &WindowView<'_>) -> Result<(), String> {
                self.0.push(v.missing.iter().filter(|m| **m).count());
                Ok(())
            }
            fn report(&self) -> Result<Map<String, Value>, String> {
                let mut m = Map::new();
                m.insert("masked".into(), json!(self.0.last()));
                Ok(m)
            }
        }
        let window = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
        let mut w = Worker::new(window, Masked(Vec::new()), publisher);
        for i in (0..200u64).filter(|i| !(60..70).contains(i)) {
            let pulse = i == 50;
            let f = if pulse { flags::IMPULSE_ACTIVE } else { 0 };
            w.handle(sample(i, if pulse { 3800 } else { 3000 }, f));
        }
        let out = w.finish();
        drop(out.publisher);
        let lines = lines.lock().unwrap();
        let v: Vec<Value> = lines
            .iter()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert!(v
            .iter()
            .any(|l| l["kind"] == "overflow_gap" && l["count"] == 10 && l["before"] == 70));
        let models: Vec<&Value> = v.iter().filter(|l| l["type"] == "model").collect();
        assert_eq!(models.len(), 1);
        assert_eq!(models[0]["masked"], 10, "the hole is masked, not bridged");
        assert_eq!(models[0]["samples"], 200);
    }

    #[test]
    fn failed_identification_is_a_warning_not_a_model() {
        let lines = run_levels(2, 0);
        let models = lines.iter().filter(|l| l["type"] == "model").count();
        let failed = lines
            .iter()
            .filter(|l| l["kind"] == "identification_failed")
            .count();
        assert_eq!((models, failed), (3, 3));
    }
}
