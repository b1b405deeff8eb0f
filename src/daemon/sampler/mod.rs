//! The sampler: reads the source, decodes TSP/1, places samples, drives the plan, never blocks.
//!
//! One loop, each turn bounded by the source's read timeout (≤ 50 ms):
//! 1. read whatever bytes are there (`Ok(0)` = nothing yet); append them to the raw recording;
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
//! acknowledges the handshake's PING is *passive* (PROTOCOL.md §6): the plan is dropped, a
//! `passive_bench` warning is published, and the bench is sampled and identified from its
//! throttle column.
//!
//! On disconnection (unplug) the sampler publishes a notice and reopens the same path with
//! exponential backoff; the plan is told, does a HELLO handshake again and never re-arms by
//! itself. On shutdown it sends STOP (re-sent every 50 ms with the same seq) until the device
//! acknowledges it or the stop timeout passes.

use crossbeam_channel::{Sender, TrySendError};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::time::{Duration, Instant};

use super::config::WireProtocol;
use super::csv_link::CsvLinkOptions;
use super::item::{EventItem, Item, Notice, PlanNote, SampleItem};
use super::shutdown::Shutdown;
use super::source::{Backoff, Source, SourceError};
use super::stats::LinkStats;
use super::tracker::Tracker;
use super::wire::Wire;
use super::DaemonError;
use propid_wire::protocol::detect::WireFormat;
use propid_wire::protocol::message::{msg_type, Frame, Message};
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
    /// A frame from the device.
    fn on_frame(&mut self, now_us: u64, frame: &Frame);
    /// Timers (heartbeats, re-sends, waits).
    fn poll(&mut self, now_us: u64);
    /// Stop the motor now (shutdown): the plan sends STOP.
    fn abort(&mut self, now_us: u64);
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
}

/// PROTOCOL.md §1: expect a boot banner and a HELLO within 3 s of opening.
pub const SILENCE_TIMEOUT: Duration = Duration::from_secs(3);

/// What the sampler hands back.
pub struct SamplerOutcome {
    /// Link counters.
    pub stats: LinkStats,
    /// Why it stopped with an error, if it did.
    pub error: Option<DaemonError>,
}

/// STOP re-send period (PROTOCOL.md §4: re-send after 50 ms without ACK).
const RESEND: Duration = Duration::from_millis(50);

/// Seq of the shutdown STOP when no plan assigns one.
const STOP_SEQ: u16 = 0xFFF0;

/// Frame handling, separate from the decoder so both can be borrowed at once.
struct Handler {
    tx: Sender<Item>,
    lossless: bool,
    tracker: Tracker,
    stats: LinkStats,
    /// Samples dropped because the queue was full (part of `samples_lost`).
    overflow_lost: u64,
    plan: Option<Box<dyn Plan>>,
    segment_announced: bool,
    awaiting_stop: Option<u16>,
    stop_acked: bool,
    now_us: u64,
}

impl Handler {
    fn send(&mut self, item: Item) {
        if self.lossless {
            let _ = self.tx.send(item);
            return;
        }
        match self.tx.try_send(item) {
            Ok(()) => {}
            Err(TrySendError::Full(item)) => {
                self.stats.overflows += 1;
                if matches!(item, Item::Sample(_)) {
                    self.overflow_lost += 1;
                }
            }
            Err(TrySendError::Disconnected(_)) => {}
        }
    }

    fn on_frame(&mut self, frame: Frame) {
        match &frame.msg {
            Message::Hello(h) if self.tracker.hello(h.boot_id) => {
                self.segment_announced = true;
                self.send(Item::Segment { boot_id: h.boot_id });
            }
            Message::Sample(s) => {
                self.stats.samples += 1;
                let placed = self.tracker.sample(s.sample_index, s.t_us);
                if placed.new_segment && !std::mem::take(&mut self.segment_announced) {
                    self.send(Item::Segment { boot_id: 0 });
                }
                // After a new segment: a gap too long to mask (announced, not bridged).
                if placed.lost_before > 0 {
                    self.send(Item::Gap {
                        before: placed.index,
                        count: placed.lost_before,
                    });
                }
                if placed.duplicate {
                    // dropped (counted in `duplicates`), as ingest does
                    if let Some(plan) = self.plan.as_mut() {
                        plan.on_frame(self.now_us, &frame);
                    }
                    return;
                }
                let item = SampleItem {
                    index: placed.index,
                    t_us: placed.t_us,
                    throttle_raw: s.throttle,
                    flags: s.flags.bits(),
                    thrust_n: valid(s.thrust_n, s.flags.bits(), 1 << 1),
                    torque_nm: valid(s.torque_nm, s.flags.bits(), 1 << 2),
                    rpm: valid(s.rpm, s.flags.bits(), 1 << 3),
                    received: Instant::now(),
                };
                self.send(Item::Sample(item));
            }
            Message::Event(e) => {
                let item = EventItem {
                    code: e.code.to_u8(),
                    arg: e.arg,
                    t_us: self.tracker.event_time(e.t_us),
                    sample_index: self.tracker.event_index(e.sample_index),
                };
                self.send(Item::Event(item));
            }
            Message::Ack(a)
                if Some(a.cmd_seq) == self.awaiting_stop && a.cmd_type == msg_type::STOP =>
            {
                self.stop_acked = true;
            }
            _ => {}
        }
        if let Some(plan) = self.plan.as_mut() {
            plan.on_frame(self.now_us, &frame);
        }
    }
}

/// A measurement whose VALID flag is clear is "not measured": NaN.
fn valid(v: f32, flags: u16, bit: u16) -> f32 {
    if flags & bit != 0 {
        v
    } else {
        f32::NAN
    }
}

/// The sampler thread's state.
pub struct Sampler {
    source: Box<dyn Source>,
    wire: Wire,
    handler: Handler,
    record: Option<BufWriter<File>>,
    shutdown: Shutdown,
    cfg: SamplerConfig,
    start: Instant,
    buf: Box<[u8; 4096]>,
    cmd: [u8; MAX_FRAME_LEN],
    /// When the link was (re)opened.
    connected_at: Instant,
    /// The plan was told the link is up.
    plan_started: bool,
}

impl Sampler {
    /// A sampler over `source`, queueing to `tx`, optionally driving `plan` and recording.
    pub fn new(
        source: Box<dyn Source>,
        tx: Sender<Item>,
        plan: Option<Box<dyn Plan>>,
        record: Option<File>,
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
                segment_announced: false,
                awaiting_stop: None,
                stop_acked: false,
                now_us: 0,
            },
            record: record.map(|f| BufWriter::with_capacity(1 << 16, f)),
            shutdown,
            cfg,
            start: Instant::now(),
            buf: Box::new([0u8; 4096]),
            cmd: [0u8; MAX_FRAME_LEN],
            connected_at: Instant::now(),
            plan_started: false,
        }
    }

    /// Runs until the source ends, the plan finishes, the run time is up or a stop is requested.
    pub fn run(mut self) -> SamplerOutcome {
        let error = self.run_loop().err();
        let handler = &mut self.handler;
        if let Some(f) = self.wire.finish(&mut |f| handler.on_frame(f)) {
            self.decided(f);
        }
        if let Some(r) = self.record.as_mut() {
            let _ = r.flush();
        }
        self.finish_stats();
        SamplerOutcome {
            stats: self.handler.stats,
            error,
        }
    }

    fn run_loop(&mut self) -> Result<(), DaemonError> {
        let live = self.source.is_live();
        if let Some(f) = self.wire.format() {
            self.decided(f);
        }
        loop {
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
                self.check_silence();
                self.drive_plan()?;
            }
            match self.handler.plan.as_ref().map(|p| p.status()) {
                Some(PlanStatus::Done) => return Ok(()),
                Some(PlanStatus::LinkFailed)
                    if self.wire.format() == Some(WireFormat::Csv) && self.wire.csv_acks() == 0 =>
                {
                    // PROTOCOL.md §6: a bench that never acknowledges is passive
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
            if r.write_all(&self.buf[..n]).is_err() {
                self.record = None; // a full disk must not stop the stand; stats show bytes
            }
        }
        self.handler.stats.bytes += n as u64;
        self.handler.now_us = self.now_us();
        let handler = &mut self.handler;
        if let Some(f) = self.wire.push(&self.buf[..n], &mut |f| handler.on_frame(f)) {
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

    /// Reopens the source with backoff until it works or a stop is requested.
    fn reconnect(&mut self) -> Result<(), DaemonError> {
        self.handler.send(Item::Notice(Notice::Disconnected));
        let mut backoff = Backoff::new(self.cfg.reconnect_initial, self.cfg.reconnect_max);
        loop {
            if self.shutdown.requested() || self.time_up() {
                return Ok(()); // the main loop sees the request; STOP cannot reach anyone
            }
            sleep_unless(&self.shutdown, backoff.next_delay());
            match self.source.reconnect() {
                Ok(()) => break,
                Err(SourceError::Finished { .. }) => return Ok(()),
                Err(_) => continue,
            }
        }
        self.handler.stats.reconnects += 1;
        self.handler.send(Item::Notice(Notice::Reconnected));
        self.connected_at = Instant::now();
        self.start_plan(false);
        Ok(())
    }

    /// Sends STOP until acknowledged or the stop timeout passes: through the plan when there is
    /// one (so it stops its heartbeats and pulses), re-sent every 50 ms with the same seq.
    fn stop_device(&mut self) -> Result<(), DaemonError> {
        let now = self.now_us();
        self.handler.awaiting_stop = None;
        if let Some(p) = self.handler.plan.as_mut() {
            p.abort(now);
        }
        let _ = self.send_plan_output();
        let seq = match self.handler.awaiting_stop {
            Some(seq) => seq,
            None => {
                // No plan, or the plan was over: a STOP of our own.
                self.handler.awaiting_stop = Some(STOP_SEQ);
                STOP_SEQ
            }
        };
        let n = self
            .wire
            .encode(seq, &Message::Stop, &mut self.cmd[..])
            .unwrap_or(0);
        let frame: [u8; MAX_FRAME_LEN] = self.cmd;
        let deadline = Instant::now() + self.cfg.stop_timeout;
        let mut next_send = Instant::now();
        while !self.handler.stop_acked && Instant::now() < deadline {
            if Instant::now() >= next_send {
                if self.source.write_all(&frame[..n]).is_err() {
                    break;
                }
                next_send += RESEND;
            }
            if self.read_once().is_err() {
                break;
            }
        }
        let _ = self.send_plan_output();
        let notice = if self.handler.stop_acked {
            Notice::Stopped
        } else {
            Notice::StopUnacknowledged
        };
        self.handler.send(Item::Notice(notice));
        Ok(())
    }

    fn finish_stats(&mut self) {
        let s = &mut self.handler.stats;
        s.wire = self.wire.name().to_string();
        s.frames_ok = self.wire.frames_ok();
        for (k, v) in self.wire.dropped() {
            s.frames_dropped.insert(k.to_string(), v);
        }
        s.samples_lost = self.handler.tracker.samples_lost + self.handler.overflow_lost;
        s.gaps = self.handler.tracker.gaps;
        s.large_gaps = self.handler.tracker.large_gaps;
        s.segments = self.handler.tracker.segments;
        s.clock_wraps = self.handler.tracker.clock_wraps();
        s.duplicates = self.handler.tracker.duplicates;
    }
}

/// Sleeps `d`, waking early when a stop is requested.
fn sleep_unless(shutdown: &Shutdown, d: Duration) {
    let end = Instant::now() + d;
    while !shutdown.requested() {
        let now = Instant::now();
        if now >= end {
            return;
        }
        std::thread::sleep((end - now).min(Duration::from_millis(10)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daemon::source::{ScriptedSource, Step};
    use propid_sim::record::{record, RecordSummary};
    use propid_sim::SimConfig;
    use propid_wire::protocol::message::{Hello, Sample, SampleFlags};
    use propid_wire::protocol::{encode_frame, Decoder, EscProtocol};

    fn cfg() -> SamplerConfig {
        SamplerConfig {
            stop_timeout: Duration::from_millis(100),
            max_run: None,
            reconnect_initial: Duration::from_millis(1),
            reconnect_max: Duration::from_millis(2),
            protocol: WireProtocol::Auto,
            csv: CsvLinkOptions::default(),
            silence_timeout: SILENCE_TIMEOUT,
        }
    }

    /// A recording of the simulated stand (`propid sim --record`: firmware + plan, faster than
    /// real time): one operating point, `pulses` pulses; and what it holds.
    fn stand(pulses: u32) -> (Vec<u8>, RecordSummary) {
        let mut cfg = SimConfig::default();
        cfg.experiment.levels = vec![0.4];
        cfg.experiment.pulses_per_level = pulses;
        let mut bytes = Vec::new();
        let sum = record(&cfg, 60.0, &mut bytes).unwrap();
        assert!(sum.finished);
        (bytes, sum)
    }

    /// SAMPLE frames the recording holds intact.
    fn samples_sent(sum: &RecordSummary) -> u64 {
        sum.firmware.samples - sum.faults.samples_lost()
    }

    #[test]
    fn csv_stream_is_decoded_by_auto_and_by_csv() {
        let mut csv = String::from("t_us,throttle,thrust_N\n");
        for k in 0..100 {
            let thr = if k % 25 == 10 { 3500 } else { 3000 };
            csv += &format!("{},{thr},1.0\n", 5_000 + k * 1000);
        }
        for protocol in [WireProtocol::Auto, WireProtocol::Csv] {
            let src = ScriptedSource::new(vec![Step::Data(csv.clone().into_bytes())]);
            let (tx, rx) = crossbeam_channel::bounded(1024);
            let c = SamplerConfig { protocol, ..cfg() };
            let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), c).run();
            assert!(out.error.is_none(), "{:?}", out.error);
            assert_eq!(out.stats.wire, "csv");
            assert_eq!(out.stats.samples, 100);
            assert_eq!(out.stats.frames_ok, 101);
            assert_eq!(out.stats.samples_lost, 0);
            let items: Vec<Item> = rx.try_iter().collect();
            let notices = items
                .iter()
                .filter(|i| **i == Item::Notice(Notice::CsvLink));
            assert_eq!(notices.count(), 1);
            let samples: Vec<&SampleItem> = items
                .iter()
                .filter_map(|i| match i {
                    Item::Sample(s) => Some(s),
                    _ => None,
                })
                .collect();
            assert_eq!(samples.len(), 100);
            let pulses = samples
                .iter()
                .filter(|s| s.flags & crate::daemon::item::flags::IMPULSE_ACTIVE != 0)
                .count();
            assert_eq!(pulses, 4);
            assert!(samples.iter().enumerate().all(|(k, s)| s.index == k as u64));
        }
    }

    #[test]
    fn binary_stream_passes_detection() {
        let (bytes, sum) = stand(1);
        let src = ScriptedSource::new(vec![Step::Data(bytes)]);
        let (tx, _rx) = crossbeam_channel::bounded(1 << 16);
        let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), cfg()).run();
        assert!(out.error.is_none());
        assert_eq!(out.stats.samples, samples_sent(&sum));
        assert_eq!(out.stats.frames_ok, sum.decode.frames_ok);
    }

    #[test]
    fn hangup_reconnects_and_counts_everything_once() {
        let (bytes, sum) = stand(2);
        let half = bytes.len() / 2;
        let mut src = ScriptedSource::new(vec![
            Step::Data(bytes[..half].to_vec()),
            Step::Stall,
            Step::Hangup,
            Step::Data(bytes[half..].to_vec()),
        ]);
        src.refuse_reconnects = 2;
        let (tx, rx) = crossbeam_channel::bounded(1 << 16);
        let s = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), cfg());
        let out = s.run();
        assert!(out.error.is_none());
        assert_eq!(out.stats.reconnects, 1);
        assert_eq!(out.stats.samples, samples_sent(&sum));
        assert_eq!(out.stats.frames_ok, sum.decode.frames_ok);
        assert_eq!(out.stats.samples_lost, 0);
        let notices: Vec<Notice> = rx
            .try_iter()
            .filter_map(|i| match i {
                Item::Notice(n) => Some(n),
                _ => None,
            })
            .collect();
        assert_eq!(notices, vec![Notice::Disconnected, Notice::Reconnected]);
    }

    #[test]
    fn full_queue_is_counted_as_overflow_never_waited_for() {
        let (bytes, sum) = stand(2);
        // what the sampler queues for this stream: the first HELLO's segment, every SAMPLE
        // and every EVENT (ACKs, LOGs and repeated HELLOs of the same boot are not queued)
        let mut items = 1u64;
        Decoder::new().push(&bytes, |f| {
            if matches!(f.msg, Message::Sample(_) | Message::Event(_)) {
                items += 1;
            }
        });
        let src = ScriptedSource::new(vec![Step::Data(bytes)]);
        let (tx, rx) = crossbeam_channel::bounded(16);
        let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), cfg()).run();
        let queued: Vec<Item> = rx.try_iter().collect();
        assert_eq!(queued.len(), 16);
        // every sample and event beyond the 16 queued items was dropped and counted
        assert_eq!(out.stats.overflows, items - 16);
        assert_eq!(out.stats.samples, samples_sent(&sum));
        // every dropped sample is lost to the worker: counted in samples_lost
        let queued_samples = queued
            .iter()
            .filter(|i| matches!(i, Item::Sample(_)))
            .count() as u64;
        assert_eq!(out.stats.samples_lost, samples_sent(&sum) - queued_samples);
    }

    fn frame(seq: u16, msg: Message) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(seq, &msg, &mut buf);
        buf[..n].to_vec()
    }

    fn sample(index: u32) -> Message {
        Message::Sample(Sample {
            sample_index: index,
            t_us: index.wrapping_mul(1000),
            throttle: 4000,
            flags: SampleFlags(SampleFlags::THRUST_VALID.bits()),
            thrust_n: 1.0,
            torque_nm: f32::NAN,
            rpm: f32::NAN,
            voltage_v: f32::NAN,
            current_a: f32::NAN,
        })
    }

    #[test]
    fn index_jump_beyond_the_largest_gap_is_a_new_segment_not_a_bridged_gap() {
        let hello = Message::Hello(Hello {
            proto_minor: 0,
            esc_protocol: EscProtocol::from_u8(5),
            fw_version: 1,
            boot_id: 77,
            t_us: 0,
            sample_rate_hz: 1000,
            channels: 1,
            motor_poles: 14,
            caps: 0,
            name: Hello::name_field("t"),
        });
        let mut bytes = frame(0, hello);
        let indices = [0u32, 1, 2, 3, 200_000, 200_001];
        for (seq, &i) in indices.iter().enumerate() {
            bytes.extend(frame(seq as u16 + 1, sample(i)));
        }
        let src = ScriptedSource::new(vec![Step::Data(bytes)]);
        let (tx, rx) = crossbeam_channel::bounded(64);
        let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), cfg()).run();
        let kinds: Vec<String> = rx
            .try_iter()
            .map(|i| match i {
                Item::Sample(s) => format!("sample {}", s.index),
                Item::Gap { before, count } => format!("gap {count} before {before}"),
                Item::Segment { boot_id } => format!("segment {boot_id}"),
                other => format!("{other:?}"),
            })
            .collect();
        assert_eq!(
            kinds,
            [
                "segment 77",
                "sample 0",
                "sample 1",
                "sample 2",
                "sample 3",
                "segment 0",
                "gap 199996 before 200000",
                "sample 200000",
                "sample 200001",
            ]
        );
        let s = &out.stats;
        assert_eq!((s.samples, s.samples_lost), (6, 199_996));
        assert_eq!((s.gaps, s.large_gaps, s.segments), (1, 1, 2));
    }

    /// A live link that never says anything.
    struct Silent;
    impl Source for Silent {
        fn read(&mut self, _: &mut [u8]) -> Result<usize, SourceError> {
            std::thread::sleep(Duration::from_millis(2));
            Ok(0)
        }
        fn write_all(&mut self, _: &[u8]) -> Result<(), SourceError> {
            Ok(())
        }
        fn reconnect(&mut self) -> Result<(), SourceError> {
            Ok(())
        }
        fn is_live(&self) -> bool {
            true
        }
        fn describe(&self) -> String {
            "silent".into()
        }
    }

    /// A plan that only counts how often it was told the link is up.
    struct Counting(std::sync::Arc<std::sync::atomic::AtomicUsize>);
    impl Plan for Counting {
        fn on_connect(&mut self, _: u64) {
            self.0.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        }
        fn on_frame(&mut self, _: u64, _: &Frame) {}
        fn poll(&mut self, _: u64) {}
        fn abort(&mut self, _: u64) {}
        fn next(&mut self, _: &mut dyn FnMut(u16, &Message), _: &mut dyn FnMut(PlanNote)) {}
        fn status(&self) -> PlanStatus {
            PlanStatus::Running
        }
    }

    #[test]
    fn a_silent_auto_link_is_reported_once_and_the_plan_starts_anyway() {
        let connects = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let plan: Box<dyn Plan> = Box::new(Counting(connects.clone()));
        let (tx, rx) = crossbeam_channel::bounded(64);
        let c = SamplerConfig {
            silence_timeout: Duration::from_millis(30),
            max_run: Some(Duration::from_millis(150)),
            ..cfg()
        };
        let out = Sampler::new(
            Box::new(Silent),
            tx,
            Some(plan),
            None,
            Shutdown::manual(),
            c,
        )
        .run();
        assert!(out.error.is_none());
        assert_eq!(out.stats.wire, "undecided");
        let items: Vec<Item> = rx.try_iter().collect();
        assert_eq!(
            items,
            vec![
                Item::Notice(Notice::NoData),
                Item::Notice(Notice::StopUnacknowledged)
            ]
        );
        assert_eq!(connects.load(std::sync::atomic::Ordering::SeqCst), 1);
    }

    #[test]
    fn shutdown_sends_stop_and_reports_it_unacknowledged_without_a_device() {
        let src = ScriptedSource::new(vec![Step::Stall; 1000]);
        let (tx, rx) = crossbeam_channel::bounded(64);
        let stop = Shutdown::manual();
        stop.request();
        let out = Sampler::new(Box::new(src), tx, None, None, stop, cfg()).run();
        assert!(out.error.is_none());
        let items: Vec<Item> = rx.try_iter().collect();
        assert_eq!(items, vec![Item::Notice(Notice::StopUnacknowledged)]);
    }
}
