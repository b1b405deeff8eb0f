//! The worker: windows per operating point, identification, publishing.
//!
//! The worker drains the sampler's queue. For each item it does the window bookkeeping
//! ([`Window`]), and when a window is complete the short hot call — [`Identifier::identify`],
//! which makes no heap allocation — followed by the slow work around it: the typed model
//! ([`Identifier::report`]), the quality checks, publishing the `"model"` line, updating the
//! gain schedule and the latency statistics. Every line it publishes is a typed
//! [`Line`](super::line::Line) (the shapes are documented in [`super::line`]).
//!
//! Nothing here depends on wall-clock time except the latency measurement, which is reported in
//! the stats line only; the published model lines depend only on the byte stream, so a live run
//! and the replay of its recording publish identical model lines.

use crossbeam_channel::Receiver;
use propid_wire::protocol::message::EventCode;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub use super::identify::{Identifier, IdentifyError};
use super::item::{Item, SampleItem};
use super::line::{Event, Line, ScheduleRow, Warning, WindowFacts, WindowModel};
use super::live::{ResponseLine, SampleDigest, StabilizationLine};
use super::publish::Publisher;
use super::quality;
use super::recorder::{RecordNote, DROPPED_MESSAGE};
use super::stats::{LinkStats, StatsLine, WorkStats};
use super::window::{Interrupted, Window, WindowView};
use super::DaemonError;

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
    /// The run report's material (the experiment kind's analysis).
    pub kinds: Option<propid_kinds::Material>,
}

/// The worker's state.
pub struct Worker<I: Identifier> {
    window: Window,
    identifier: I,
    publisher: Publisher,
    stats: WorkStats,
    /// The gain schedule: per operating-point number, its last reliable model.
    schedule: Vec<(u32, ScheduleRow)>,
    latencies_s: Vec<f64>,
    error: Option<DaemonError>,
    /// The web page's lines ([`super::live`]), with an HTTP sink only.
    live: Option<Live>,
    /// The analysis of the experiment kind (on the decoded samples; the report's material).
    kinds: Option<propid_kinds::Analysis>,
}

/// What the worker keeps for the web page's lines.
struct Live {
    /// The sampler's copy of the link counters.
    link: Arc<Mutex<LinkStats>>,
    digest: SampleDigest,
    started: Instant,
    last_stats: Instant,
    /// When the last response and diagram were published.
    last_window: Option<Instant>,
    /// The latest window's, not yet published (windows come faster than [`LIVE_WINDOW`]);
    /// the workspace still holds its identification while this is set.
    pending: Option<(WindowFacts, Option<ResponseLine>)>,
}

/// The response and diagram of at most one window per this long are drawn (a replay identifies
/// windows far faster than a browser draws them): the latest, always the last one.
const LIVE_WINDOW: Duration = Duration::from_millis(250);

/// How often a `live_stats` line is published.
const LIVE_STATS: Duration = Duration::from_millis(500);

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
            live: None,
            kinds: None,
        }
    }

    /// Also runs the analysis of an experiment kind on every sample (`propid_kinds`).
    pub fn with_kinds(mut self, analysis: Option<propid_kinds::Analysis>) -> Worker<I> {
        self.kinds = analysis;
        self
    }

    /// Also publishes the web page's lines ([`super::live`]) when the publisher serves it;
    /// `link` is the sampler's copy of the link counters.
    pub fn with_live(mut self, link: Arc<Mutex<LinkStats>>) -> Worker<I> {
        if self.publisher.is_live() {
            self.live = Some(Live {
                link,
                digest: SampleDigest::default(),
                started: Instant::now(),
                last_stats: Instant::now(),
                last_window: None,
                pending: None,
            });
        }
        self
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
                let mut done = None;
                let identifier = &mut self.identifier;
                let live = self.live.is_some();
                let pulse = self
                    .window
                    .on_gap(count, |v| done = Some(identify_one(identifier, v, live)));
                if let Some(d) = done {
                    self.publish_model(d);
                }
                if pulse {
                    self.stats.pulses += 1;
                }
                self.emit(&Line::Event(Event::Gap { before, count }));
            }
            Item::Segment { boot_id } => {
                let mut done = None;
                let identifier = &mut self.identifier;
                let live = self.live.is_some();
                let cut = self
                    .window
                    .on_segment(|v| done = Some(identify_one(identifier, v, live)));
                if let Some(d) = done {
                    self.publish_model(d);
                }
                if let Some(w) = cut {
                    self.publish_cut(w);
                }
                self.stats.segments += 1;
                self.emit(&Line::Event(Event::Segment { boot_id }));
            }
            Item::ClockJump {
                index,
                step_us,
                expected_us,
            } => {
                let mut done = None;
                let identifier = &mut self.identifier;
                let live = self.live.is_some();
                let cut = self
                    .window
                    .on_clock_jump(|v| done = Some(identify_one(identifier, v, live)));
                if let Some(d) = done {
                    self.publish_model(d);
                }
                if let Some(w) = cut {
                    self.publish_cut(w);
                }
                self.stats.clock_jumps += 1;
                self.emit(&Line::Warning(Warning::ClockJump {
                    sample_index: index,
                    step_us,
                    expected_us,
                }));
            }
            Item::RateMismatch {
                hello_hz,
                measured_hz,
            } => self.emit(&Line::Warning(Warning::HelloRateMismatch {
                hello_hz,
                measured_hz,
            })),
            Item::Event(e) => {
                if EventCode::from_u8(e.code) == EventCode::ImpulseStart {
                    self.window.on_pulse_event(e.sample_index);
                }
                if let Some(line) = Line::device_event(&e) {
                    self.emit(&line);
                }
            }
            Item::Plan(n) => {
                if let Some(line) = Line::plan(n) {
                    self.emit(&line);
                }
            }
            Item::Notice(n) => self.emit(&Line::notice(n)),
            Item::Record(RecordNote::File { path }) => {
                let path = path.display().to_string();
                self.emit(&Line::Event(Event::Recording { path }));
            }
            Item::Record(RecordNote::Dropped { path }) => {
                let path = path.display().to_string();
                self.emit(&Line::Warning(Warning::OutputFailed {
                    sink: "record",
                    path: Some(&path),
                    message: DROPPED_MESSAGE,
                }));
            }
            Item::Record(RecordNote::Failed { path, error }) => {
                let (path, message) = (path.display().to_string(), error.to_string());
                self.emit(&Line::Warning(Warning::OutputFailed {
                    sink: "record",
                    path: Some(&path),
                    message: &message,
                }));
            }
        }
    }

    /// Closes the last window and publishes the gain schedule.
    pub fn finish(mut self) -> WorkerOutcome {
        let mut done = None;
        let identifier = &mut self.identifier;
        let live = self.live.is_some();
        let cut = self
            .window
            .finish(|v| done = Some(identify_one(identifier, v, live)));
        if let Some(d) = done {
            self.publish_model(d);
        }
        if let Some(w) = cut {
            self.publish_cut(w);
        }
        if let Some(line) = self.live.as_mut().and_then(|l| l.digest.take()) {
            self.emit_live(&Line::Samples(&line));
        }
        self.flush_live_window();
        let kinds = self.kinds.take().map(|mut a| {
            for p in a.finish() {
                self.emit(&Line::Kind(&p));
            }
            a.into_material()
        });
        self.publish_schedule();
        self.latencies_s.sort_by(f64::total_cmp);
        WorkerOutcome {
            publisher: self.publisher,
            stats: self.stats,
            latencies_s: self.latencies_s,
            error: self.error,
            kinds,
        }
    }

    /// A window closed with fewer than K pulses: named and counted (`window_interrupted`), so
    /// that every pulse counted is in a model, a refusal or one of these.
    fn publish_cut(&mut self, w: Interrupted) {
        self.stats.windows_interrupted += 1;
        self.emit(&Line::Warning(Warning::WindowInterrupted {
            operating_point: w.operating_point,
            pulses: w.pulses,
            t_s: w.t_s,
            closed_by: w.closed_by,
        }));
    }

    fn on_sample(&mut self, s: &SampleItem) {
        // Hot path: bookkeeping and identification only; reports are built after.
        let mut done: Option<Done> = None;
        let identifier = &mut self.identifier;
        let live = self.live.is_some();
        let outcome = self
            .window
            .on_sample(s, |v| done = Some(identify_one(identifier, v, live)));
        if outcome.pulse {
            self.stats.pulses += 1;
        }
        if live {
            self.on_live_sample(s, outcome.pulse);
        }
        if let Some(a) = self.kinds.as_mut() {
            let done = a.push(propid_kinds::Sample {
                index: s.index,
                t_us: s.t_us,
                throttle: s.throttle(),
                thrust: f64::from(s.thrust_n),
                rpm: f64::from(s.rpm),
                current: f64::from(s.current_a),
            });
            for p in done {
                self.emit(&Line::Kind(&p));
            }
        }
        if outcome.unannounced_lost > 0 {
            // Only the sampler's full queue drops samples without a gap notice.
            self.emit(&Line::Warning(Warning::OverflowGap {
                before: s.index,
                count: outcome.unannounced_lost,
            }));
        }
        if let Some(d) = done {
            self.publish_model(d);
        }
        if let Some(w) = outcome.cut {
            self.publish_cut(w);
        }
        if outcome.overflowed {
            self.emit(&Line::Warning(Warning::WindowFull {
                sample_index: s.index,
            }));
        }
    }

    /// The web page's samples and counters (with an HTTP sink only).
    fn on_live_sample(&mut self, s: &SampleItem, pulse: bool) {
        let Some(live) = self.live.as_mut() else {
            return;
        };
        let Some(line) = live.digest.push(s, pulse) else {
            return;
        };
        self.emit_live(&Line::Samples(&line));
        let Some(live) = self.live.as_mut() else {
            return;
        };
        if live.last_stats.elapsed() < LIVE_STATS {
            return;
        }
        live.last_stats = Instant::now();
        let link = live.link.lock().map(|l| l.clone()).unwrap_or_default();
        let elapsed_s = live.started.elapsed().as_secs_f64();
        let mut sorted = self.latencies_s.clone();
        sorted.sort_by(f64::total_cmp);
        let mut stats = StatsLine::new(
            &link,
            &self.stats,
            self.publisher.dropped_clients(),
            elapsed_s,
            &sorted,
        );
        stats.clients_refused = self.publisher.clients_refused();
        stats.mqtt = self.publisher.mqtt_stats();
        let line = Line::LiveStats(&stats);
        if let Err(e) = self.publisher.publish_live(&line) {
            self.error.get_or_insert(e);
        }
    }

    /// The web page's response and stabilization lines of a window's model (after its model
    /// line: they add nothing to its latency).
    fn publish_live_window(&mut self, facts: &WindowFacts, response: Option<ResponseLine>) {
        let Some(live) = self.live.as_mut() else {
            return;
        };
        if live.last_window.is_some_and(|t| t.elapsed() < LIVE_WINDOW) {
            live.pending = Some((*facts, response));
            return;
        }
        live.last_window = Some(Instant::now());
        live.pending = None;
        self.emit_live_window(facts, response);
    }

    /// The latest window's response and diagram if they are still pending (at the end).
    fn flush_live_window(&mut self) {
        if let Some((facts, response)) = self.live.as_mut().and_then(|l| l.pending.take()) {
            self.emit_live_window(&facts, response);
        }
    }

    fn emit_live_window(&mut self, facts: &WindowFacts, response: Option<ResponseLine>) {
        if let Some(mut r) = response {
            r.t_s = facts.t_s;
            r.operating_point = facts.operating_point;
            r.level = facts.level;
            self.emit_live(&Line::Response(&r));
        }
        if let Some(diagram) = self.identifier.stabilization() {
            let line = StabilizationLine {
                t_s: facts.t_s,
                operating_point: facts.operating_point,
                level: facts.level,
                diagram,
            };
            self.emit_live(&Line::Stabilization(&line));
        }
    }

    fn publish_model(&mut self, d: Done) {
        if let Some(live) = self.live.as_mut() {
            // a new identification: the workspace no longer holds the pending one's
            live.pending = None;
        }
        let report = match d.result.and_then(|()| self.identifier.report()) {
            Ok(r) => r,
            Err(error) => {
                self.stats.identify_errors += 1;
                self.emit(&Line::Warning(Warning::IdentificationFailed {
                    error: &error,
                    operating_point: d.facts.operating_point,
                    t_s: d.facts.t_s,
                }));
                return;
            }
        };
        let model = WindowModel {
            window: d.facts,
            path: propid_numerics::identify::PathTaken::Pulse,
            outliers: d.outliers,
            report,
        };
        let flaws = quality::judge(&model.report);
        if !flaws.is_empty() {
            // not the plant: published for inspection, never as a model nor in the schedule
            self.emit(&Line::Warning(Warning::ModelUnreliable {
                model: &model,
                reasons: &flaws,
            }));
            self.stats.models_unreliable += 1;
            self.publish_live_window(&d.facts, d.live);
            return;
        }
        self.emit(&Line::Model(&model));
        self.stats.models += 1;
        if let Some(a) = self.kinds.as_mut() {
            a.add_model(propid_kinds::ModelRow::new(
                model.window.t_s,
                model.window.operating_point,
                &model.report,
            ));
        }
        if let Some(t) = d.facts.last_received {
            if self.latencies_s.len() < LATENCY_CAP {
                self.latencies_s.push(t.elapsed().as_secs_f64());
            }
        }
        self.publish_live_window(&d.facts, d.live);
        let level = model.window.level;
        match self.schedule.iter_mut().find(|e| e.0 == level) {
            // the operating point stays the one first published for this number
            Some(e) => e.1 = ScheduleRow::new(e.1.operating_point, &model.report),
            None => self.schedule.push((
                level,
                ScheduleRow::new(model.window.operating_point, &model.report),
            )),
        }
        if self.live.is_some() {
            // the schedule so far, for the page (the final one is published to every sink)
            let rows = self.schedule_rows();
            self.emit_live(&Line::Schedule(&rows));
        }
    }

    /// The gain schedule, ordered by operating point (then by number).
    fn schedule_rows(&self) -> Vec<ScheduleRow> {
        let mut rows: Vec<&(u32, ScheduleRow)> = self.schedule.iter().collect();
        rows.sort_by(|a, b| {
            a.1.operating_point
                .total_cmp(&b.1.operating_point)
                .then(a.0.cmp(&b.0))
        });
        rows.into_iter().map(|(_, row)| row.clone()).collect()
    }

    fn publish_schedule(&mut self) {
        let models = self.schedule_rows();
        self.schedule.clear();
        self.emit(&Line::Schedule(&models));
    }

    fn emit_live(&mut self, line: &Line<'_>) {
        if let Err(e) = self.publisher.publish_live(line) {
            self.error.get_or_insert(e);
        }
    }

    fn emit(&mut self, line: &Line<'_>) {
        if let Err(e) = self.publisher.publish_line(line) {
            self.error.get_or_insert(e);
        }
    }
}

/// An identification done in the hot path, waiting to be published.
struct Done {
    facts: WindowFacts,
    result: Result<(), IdentifyError>,
    /// Isolated outlier samples left out of the window.
    outliers: usize,
    /// The web page's pulse responses (`live` only).
    live: Option<ResponseLine>,
}

/// The hot call and the facts needed to publish it later (no allocation); with `live` (an
/// HTTP sink) also what the web page draws of the window, which allocates.
fn identify_one<I: Identifier>(id: &mut I, v: &WindowView<'_>, live: bool) -> Done {
    let result = id.identify(v);
    let live = if live && result.is_ok() {
        id.response(v)
    } else {
        None
    };
    Done {
        facts: WindowFacts::from(v),
        result,
        outliers: id.outliers(),
        live,
    }
}

#[cfg(test)]
mod pinned;
#[cfg(test)]
mod tests;
