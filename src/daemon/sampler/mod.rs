//! The sampler: reads the source, decodes TSP/1, places samples, drives the plan, never blocks.
//!
//! One loop, each turn bounded by the source's read timeout (≤ 50 ms):
//! 1. read whatever bytes are there (`Ok(0)` = nothing yet); copy them for the raw recording
//!    (its own thread writes the file: [`super::recorder`]; the sampler does no file I/O);
//! 2. push them through the link's [`Wire`] decoder — binary TSP/1 (fixed buffer, counts every
//!    drop by kind) or the CSV fallback made to look like it ([`super::csv_link`]);
//! 3. for each frame: HELLO → new segment if its `boot_id` changed; SAMPLE → unwrapped clock and
//!    index, gaps handed on as [`Item::Gap`], the sample queued; EVENT → queued; every frame is
//!    shown to the experiment plan (ACKs, state);
//! 4. ask the plan for due commands (heartbeats every 100 ms, pulses, re-sends) and write them.
//!
//! Queueing to the worker uses `try_send` on a bounded channel when the source is live: a full
//! queue drops the item and counts an overflow, so the sampler never waits for the worker and
//! never falls behind the device. A dropped SAMPLE is also counted in `samples_lost` (the
//! worker never gets it, exactly as if the link had lost it), and the worker sees the hole it
//! leaves as a jump in the sample index ([`super::window::Window`] checks continuity): it is
//! masked as missing, never bridged. For a recording (replay) there is no device to fall behind
//! and the sampler waits instead (lossless).
//!
//! `[device] protocol`: with `"auto"` the first bytes are held until the wire format is decided
//! ([`Wire`]); the experiment plan starts then, so its first command is written in the format
//! the device speaks. `"tsp"` and `"csv"` skip the detection. A CSV bench that never
//! acknowledges the handshake's PING is *passive* (docs/PROTOCOL.md §6): the plan is dropped, a
//! `passive_bench` warning is published, and the bench is sampled and identified from its
//! throttle column.
//!
//! On disconnection (unplug) the sampler publishes a notice and reopens the same path with
//! exponential backoff (a symlink is resolved again at every attempt); a link that stays open
//! but silent for `[device] stall_timeout_ms` is *stalled*: STOP is tried, a `link_stalled`
//! warning published, the port closed and reopened, with backoff while it stays silent, and a
//! `link_resumed` event when bytes return ([`link`]; a passive CSV bench too). After either
//! the plan is told: it asks the device (HELLO_REQ) whether it is the same boot and goes on,
//! or, reset, ends — or re-arms with `[experiment] rearm_on_reset`, at most `max_rearms`
//! times. A plan over on a fault (device reset, stall, watchdog trip, refusal) sends STOP at
//! once (its heartbeats are over) and ends the run 500 ms later (the link still read
//! meanwhile), with [`SamplerOutcome::plan_halted`]: exit 8. On shutdown it sends STOP (re-sent
//! every 50 ms with the same seq) until the device acknowledges it or the stop timeout passes.

mod handler;
mod link;

use crossbeam_channel::Sender;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::config::WireProtocol;
use super::csv_link::CsvLinkOptions;
use super::item::{Item, Notice, PlanNote};
use super::recorder::{Recorder, CLOSE_TIMEOUT};
use super::shutdown::Shutdown;
use super::source::{Backoff, Source, SourceError};
use super::stats::LinkStats;
use super::tracker::Tracker;
use super::wire::Wire;
use super::DaemonError;
use handler::Handler;
use propid_wire::protocol::detect::WireFormat;
use propid_wire::protocol::message::{Frame, Message};
use propid_wire::protocol::MAX_FRAME_LEN;

/// Where the experiment stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanStatus {
    /// Still running.
    Running,
    /// Finished: ramped down and disarmed. The run ends.
    Done,
    /// Over (device reset, watchdog trip, refusal, stop): no more commands, sampling goes on.
    Halted,
    /// The device stopped acknowledging commands. The run ends with an error.
    LinkFailed,
}

/// The host-side experiment as the sampler drives it (implemented over `propid_wire::experiment` in
/// [`super::plan`]). Pure: it is given the host time and the device's frames, and says what to
/// send and what happened.
pub trait Plan: Send {
    /// The link was (re)opened.
    fn on_connect(&mut self, now_us: u64);
    /// The link stalled (nothing heard for the stall timeout): queue a STOP, stop commanding.
    fn on_stall(&mut self, now_us: u64);
    /// A frame from the device.
    fn on_frame(&mut self, now_us: u64, frame: &Frame);
    /// Timers (heartbeats, re-sends, waits).
    fn poll(&mut self, now_us: u64);
    /// Stop the motor now (shutdown): the plan sends STOP.
    fn abort(&mut self, now_us: u64);
    /// The device's measured sample rate disagrees with its HELLO's (the assembler's rule):
    /// the plan, which sizes pulses from the HELLO's, stops.
    fn on_rate_mismatch(&mut self, _now_us: u64, _hello_hz: u16, _measured_hz: f64) {}
    /// Drains what the plan wants sent (`(seq, message)`; a re-send keeps its seq) and what it
    /// reports.
    fn next(&mut self, send: &mut dyn FnMut(u16, &Message), notes: &mut dyn FnMut(PlanNote));
    /// Where the plan stands.
    fn status(&self) -> PlanStatus;
}

/// Sampler settings.
#[derive(Debug, Clone)]
pub struct SamplerConfig {
    /// Longest time to send STOP at shutdown.
    pub stop_timeout: Duration,
    /// Stop after this long (graceful, with STOP).
    pub max_run: Option<Duration>,
    /// First reconnect delay.
    pub reconnect_initial: Duration,
    /// Longest reconnect delay.
    pub reconnect_max: Duration,
    /// Expected wire format.
    pub protocol: WireProtocol,
    /// How a CSV bench is read.
    pub csv: CsvLinkOptions,
    /// With `protocol = "auto"`, a live link that stays silent this long gets a `no_data`
    /// warning and the plan starts anyway (in binary TSP/1, whose HELLO_REQ makes a device
    /// speak); [`SILENCE_TIMEOUT`] in a run.
    pub silence_timeout: Duration,
    /// `[device] stall_timeout_ms`: a live link silent this long (after its first byte) is
    /// stalled (None = no watchdog).
    pub stall_timeout: Option<Duration>,
}

/// docs/PROTOCOL.md §1: expect a boot banner and a HELLO within 3 s of opening.
pub const SILENCE_TIMEOUT: Duration = Duration::from_secs(3);

/// What the sampler hands back.
pub struct SamplerOutcome {
    /// Link counters.
    pub stats: LinkStats,
    /// Why it stopped with an error, if it did.
    pub error: Option<DaemonError>,
    /// The plan ended on a fault (device reset, watchdog trip, refusal) and the run stopped.
    pub plan_halted: bool,
    /// The recording failed (the run went on): reported at the end, exit 7.
    pub record_error: Option<DaemonError>,
}

/// How long the link is still read after the plan ended on a fault, before the run ends.
const HALT_DRAIN: Duration = Duration::from_millis(500);

/// STOP re-send period (docs/PROTOCOL.md §4: re-send after 50 ms without ACK).
const RESEND: Duration = Duration::from_millis(50);

/// Seq of the shutdown STOP when no plan assigns one.
const STOP_SEQ: u16 = 0xFFF0;

/// The sampler thread's state.
pub struct Sampler {
    source: Box<dyn Source>,
    wire: Wire,
    handler: Handler,
    record: Option<Recorder>,
    shutdown: Shutdown,
    cfg: SamplerConfig,
    start: Instant,
    buf: Box<[u8; 4096]>,
    cmd: [u8; MAX_FRAME_LEN],
    /// When the link was (re)opened.
    connected_at: Instant,
    /// When the last byte arrived.
    last_rx: Instant,
    /// A byte arrived since the link was (re)opened.
    heard_since_connect: bool,
    /// A `link_stalled` warning was published and no byte has arrived since.
    stalled: bool,
    /// The backoff of the reopens of a link silent since a stall ([`link`]).
    stall_backoff: Option<Backoff>,
    /// The plan was told the link is up.
    plan_started: bool,
    /// The plan ended on a fault.
    plan_halted: bool,
    /// When the plan was first seen over on a fault.
    halted_at: Option<Instant>,
    /// The web page's copy of the link counters, refreshed every [`LIVE_STATS`] (`--http`).
    live: Option<(Arc<Mutex<LinkStats>>, Instant)>,
}

/// How often the web page's copy of the link counters is refreshed.
const LIVE_STATS: Duration = Duration::from_millis(500);

impl Sampler {
    /// A sampler over `source`, queueing to `tx`, optionally driving `plan` and recording.
    pub fn new(
        source: Box<dyn Source>,
        tx: Sender<Item>,
        plan: Option<Box<dyn Plan>>,
        record: Option<Recorder>,
        shutdown: Shutdown,
        cfg: SamplerConfig,
    ) -> Sampler {
        let lossless = !source.is_live();
        Sampler {
            source,
            wire: Wire::new(cfg.protocol, cfg.csv),
            handler: Handler {
                tx,
                lossless,
                tracker: Tracker::default(),
                stats: LinkStats::default(),
                overflow_lost: 0,
                plan,
                awaiting_stop: None,
                stop_acked: false,
                now_us: 0,
            },
            record,
            shutdown,
            cfg,
            start: Instant::now(),
            buf: Box::new([0u8; 4096]),
            cmd: [0u8; MAX_FRAME_LEN],
            connected_at: Instant::now(),
            last_rx: Instant::now(),
            heard_since_connect: false,
            stalled: false,
            stall_backoff: None,
            plan_started: false,
            plan_halted: false,
            halted_at: None,
            live: None,
        }
    }

    /// Also keeps `slot` a copy of the link counters, every [`LIVE_STATS`] (never waiting for
    /// the lock: a busy slot is skipped until the next turn).
    pub fn with_live_stats(mut self, slot: Arc<Mutex<LinkStats>>) -> Sampler {
        self.live = Some((slot, Instant::now()));
        self
    }

    /// Refreshes the live copy of the counters when it is due.
    fn share_stats(&mut self) {
        let due = matches!(&self.live, Some((_, at)) if at.elapsed() >= LIVE_STATS);
        if !due {
            return;
        }
        self.finish_stats();
        if let Some((slot, at)) = &mut self.live {
            if let Ok(mut s) = slot.try_lock() {
                s.clone_from(&self.handler.stats);
                *at = Instant::now();
            }
        }
    }

    /// Runs until the source ends, the plan finishes, the run time is up or a stop is requested.
    pub fn run(mut self) -> SamplerOutcome {
        let error = self.run_loop().err();
        let handler = &mut self.handler;
        if let Some(f) = self.wire.finish(&mut |f, w| handler.on_frame(f, w)) {
            self.decided(f);
        }
        if let Some(r) = self.record.as_mut() {
            let handler = &mut self.handler;
            r.finish(CLOSE_TIMEOUT, &mut |n| handler.send(Item::Record(n)));
        }
        self.finish_stats();
        SamplerOutcome {
            stats: self.handler.stats,
            error,
            plan_halted: self.plan_halted,
            record_error: self.record.as_ref().and_then(Recorder::error),
        }
    }

    /// Hands the recording's waiting bytes to its thread when due and what it reports to the
    /// worker.
    fn forward_record_notes(&mut self) {
        let Some(r) = self.record.as_mut() else {
            return;
        };
        let handler = &mut self.handler;
        r.tick(&mut |n| handler.send(Item::Record(n)));
    }

    fn run_loop(&mut self) -> Result<(), DaemonError> {
        let live = self.source.is_live();
        if let Some(f) = self.wire.format() {
            self.decided(f);
        }
        loop {
            self.forward_record_notes();
            self.share_stats();
            if self.shutdown.requested() || self.time_up() {
                if live {
                    self.stop_device()?;
                }
                return Ok(());
            }
            match self.read_once() {
                Ok(()) => {}
                Err(SourceError::Finished { .. }) => return Ok(()),
                Err(SourceError::Disconnected { .. }) => self.reconnect()?,
                Err(e @ SourceError::Open { .. }) => return Err(e.into()),
            }
            if live {
                self.check_stall()?;
                self.check_silence();
                self.drive_plan()?;
            }
            match self.handler.plan.as_ref().map(|p| p.status()) {
                Some(PlanStatus::Done) => return Ok(()),
                Some(PlanStatus::Halted) if !self.shutdown.requested() => {
                    // A device reset, a watchdog trip or a refusal ended the plan (its warning
                    // is queued): STOP at once (the plan's heartbeats are over), and the run is
                    // over, with a fault, so that a supervisor sees it; after HALT_DRAIN, so
                    // that what the device says about it (its HELLO, its events) is still read
                    // and published.
                    if self.halted_at.is_none() {
                        self.halted_at = Some(Instant::now());
                        let _ = self.stop_device();
                    }
                    if self.halted_at.is_some_and(|t| t.elapsed() >= HALT_DRAIN) {
                        self.plan_halted = true;
                        return Ok(());
                    }
                }
                Some(PlanStatus::LinkFailed)
                    if self.wire.format() == Some(WireFormat::Csv) && self.wire.csv_acks() == 0 =>
                {
                    // docs/PROTOCOL.md §6: a bench that never acknowledges is passive
                    self.handler.plan = None;
                    self.handler.send(Item::Notice(Notice::PassiveBench));
                }
                Some(PlanStatus::LinkFailed) => {
                    let _ = self.stop_device();
                    return Err(DaemonError::LinkFailed {
                        link: self.source.describe(),
                    });
                }
                _ => {}
            }
        }
    }

    /// The wire format is known: a CSV link is announced, and the plan starts (live links).
    fn decided(&mut self, format: WireFormat) {
        if format == WireFormat::Csv {
            self.handler.send(Item::Notice(Notice::CsvLink));
        }
        self.start_plan(false);
    }

    /// `protocol = "auto"` and nothing heard since the link opened: warn once and start the
    /// plan anyway (see [`SamplerConfig::silence_timeout`]).
    fn check_silence(&mut self) {
        if self.plan_started
            || self.wire.format().is_some()
            || self.connected_at.elapsed() < self.cfg.silence_timeout
        {
            return;
        }
        self.handler.send(Item::Notice(Notice::NoData));
        self.start_plan(true);
    }

    /// Tells the plan the link is up, once the wire format is known (or `force`d after a
    /// silence); live links only.
    fn start_plan(&mut self, force: bool) {
        if !self.source.is_live() || (self.wire.format().is_none() && !force) {
            return;
        }
        self.plan_started = true;
        let now = self.now_us();
        if let Some(p) = self.handler.plan.as_mut() {
            p.on_connect(now);
        }
    }

    fn now_us(&self) -> u64 {
        self.start.elapsed().as_micros() as u64
    }

    fn time_up(&self) -> bool {
        self.cfg.max_run.is_some_and(|m| self.start.elapsed() >= m)
    }

    /// One read, its recording and its frames.
    fn read_once(&mut self) -> Result<(), SourceError> {
        let n = self.source.read(&mut self.buf[..])?;
        if n == 0 {
            return Ok(());
        }
        if let Some(r) = self.record.as_mut() {
            r.write(&self.buf[..n]); // copied for the recorder thread: never waits
        }
        self.handler.stats.bytes += n as u64;
        self.heard();
        self.last_rx = Instant::now();
        self.heard_since_connect = true;
        self.handler.now_us = self.now_us();
        let handler = &mut self.handler;
        if let Some(f) = self
            .wire
            .push(&self.buf[..n], &mut |f, w| handler.on_frame(f, w))
        {
            self.decided(f);
        }
        Ok(())
    }

    /// Sends the plan's due commands and queues its notes.
    fn drive_plan(&mut self) -> Result<(), DaemonError> {
        let now = self.now_us();
        let Some(plan) = self.handler.plan.as_mut() else {
            return Ok(());
        };
        plan.poll(now);
        match self.send_plan_output() {
            None => Ok(()),
            Some(SourceError::Disconnected { .. }) => self.reconnect(),
            Some(e) => Err(e.into()),
        }
    }

    /// Writes what the plan wants sent; returns the first write error.
    fn send_plan_output(&mut self) -> Option<SourceError> {
        let plan = self.handler.plan.as_mut()?;
        let mut failed = None;
        let mut notes: Vec<PlanNote> = Vec::new();
        let source = &mut self.source;
        let cmd = &mut self.cmd;
        let wire = &mut self.wire;
        let awaiting = &mut self.handler.awaiting_stop;
        plan.next(
            &mut |seq, msg| {
                if matches!(msg, Message::Stop) && awaiting.is_none() {
                    *awaiting = Some(seq);
                }
                if failed.is_some() {
                    return;
                }
                let Some(n) = wire.encode(seq, msg, &mut cmd[..]) else {
                    return; // no CSV form (the plan sends none such)
                };
                if let Err(e) = source.write_all(&cmd[..n]) {
                    failed = Some(e);
                }
            },
            &mut |n| notes.push(n),
        );
        for n in notes {
            self.handler.send(Item::Plan(n));
        }
        failed
    }

    fn finish_stats(&mut self) {
        let s = &mut self.handler.stats;
        s.wire = self.wire.name().to_string();
        s.frames_ok = self.wire.frames_ok();
        s.empty_frames = self.wire.empty_frames();
        for (k, v) in self.wire.dropped() {
            s.frames_dropped.insert(k.to_string(), v);
        }
        s.samples_lost = self.handler.tracker.samples_lost + self.handler.overflow_lost;
        s.gaps = self.handler.tracker.gaps;
        s.large_gaps = self.handler.tracker.large_gaps;
        s.clock_wraps = self.handler.tracker.clock_wraps();
        s.duplicates = self.handler.tracker.duplicates;
        s.record_bytes_written = self.record.as_ref().map(Recorder::bytes_written);
        s.record_bytes_dropped = self.record.as_ref().map(Recorder::bytes_dropped);
    }
}

#[cfg(test)]
mod tests;
