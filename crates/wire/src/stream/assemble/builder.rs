//! The record side of assembly: [`RecordBuilder`] stores what the [`SampleAssembler`] places
//! (channels, the missing mask, events) and produces the [`Record`].
//!
//! The channel set is fixed by the first sample: throttle plus every channel valid in it. A
//! later sample where one of these is not valid (or not finite) is marked missing as a whole
//! (the record allows NaN only at missing samples) and counted in `invalid_samples`. Link
//! frames lost are counted from jumps of the 16-bit `seq` between successive device frames.
//! A builder may keep the rows of one span of positions only ([`RecordBuilder::keep`]: a long
//! recording read in bounded memory), or hand its rows over as it goes
//! ([`RecordBuilder::take_rows`]); every counter is still the whole stream's.

use serde::Serialize;

use super::{AssembleOptions, AssembleStats, Assembled, SampleAssembler, SegmentCause};
use crate::protocol::message::{Event, EventCode, Hello, Message, Sample, SampleFlags};
use crate::protocol::Frame;
use crate::record::{names, Channel, Record, RecordEvent, RecordEventKind};
use crate::stream::IngestError;

/// Record channels in order: throttle, then the measured channels with their SAMPLE flag.
pub const CHANNELS: [(&str, &str, SampleFlags); 6] = [
    (names::THROTTLE, "1", SampleFlags(0)),
    (names::THRUST, "N", SampleFlags::THRUST_VALID),
    (names::TORQUE, "N·m", SampleFlags::TORQUE_VALID),
    (names::RPM, "rev/min", SampleFlags::RPM_VALID),
    (names::VOLTAGE, "V", SampleFlags::VOLTAGE_VALID),
    (names::CURRENT, "A", SampleFlags::CURRENT_VALID),
];

/// One sample's values in [`CHANNELS`] order; `None` = not measured.
pub type Values = [Option<f64>; 6];

/// The values of a SAMPLE, per its `*_VALID` flags (throttle is always valid).
pub fn sample_values(s: &Sample) -> Values {
    [
        Some(s.throttle_fraction()),
        s.thrust().map(f64::from),
        s.torque().map(f64::from),
        s.rotor_rpm().map(f64::from),
        s.voltage().map(f64::from),
        s.current().map(f64::from),
    ]
}

/// Counters of the record building.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct BuildStats {
    /// Samples whose recorded channels were not all valid and finite: marked missing.
    pub invalid_samples: u64,
    /// SAMPLEs without THRUST_FRESH: the load cell's value was held, not newly converted.
    pub thrust_held: u64,
    /// Device frames lost on the link, from jumps of the 16-bit `seq` between successive
    /// device frames (restarted by a HELLO with a new `boot_id`). Sample-index gaps without a
    /// `seq` jump were dropped by the device itself.
    pub link_frames_lost: u64,
}

/// Builds a [`Record`] from frames (or generic points), streaming.
///
/// The channel set is fixed by the first sample: throttle plus every channel valid in it.
/// A later sample where one of these is not valid (or not finite) is marked missing as a
/// whole (the record allows NaN only at missing samples) and counted in `invalid_samples`.
#[derive(Debug, Clone, Default)]
pub struct RecordBuilder {
    asm: SampleAssembler,
    store: Store,
    last_seq: Option<u16>,
    boot_id: Option<u32>,
}

/// The growing record columns.
#[derive(Debug, Clone, Default)]
struct Store {
    present: Option<[bool; 6]>,
    data: [Vec<f64>; 6],
    missing: Vec<bool>,
    events: Vec<RecordEvent>,
    t0_us: Option<u64>,
    stats: BuildStats,
    /// Positions stored, `[from, to)`; `None`: all. Rows outside are placed and counted only.
    keep: Option<(usize, usize)>,
    /// Position of the next row (the stream's length so far).
    next: usize,
    /// Positions of events after the kept span not yet reached by a row (an event placed past
    /// the stream's last row is counted as dropped, kept or not).
    late: Vec<usize>,
}

/// Rows handed over by [`RecordBuilder::take_rows`], in [`CHANNELS`] order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Rows {
    /// Position of the first row.
    pub start: usize,
    /// Which of [`CHANNELS`] the record has (`None` before the first sample).
    pub present: Option<[bool; 6]>,
    /// One column per channel of [`CHANNELS`] (NaN where missing or not recorded).
    pub data: [Vec<f64>; 6],
    /// Missing rows.
    pub missing: Vec<bool>,
}

impl RecordBuilder {
    /// A new builder.
    pub fn new(opts: AssembleOptions) -> Self {
        Self {
            asm: SampleAssembler::new(opts),
            ..Self::default()
        }
    }

    /// The assembler (for its counters and `dt_s`).
    pub fn assembler(&self) -> &SampleAssembler {
        &self.asm
    }

    /// Record-building counters.
    pub fn stats(&self) -> &BuildStats {
        &self.store.stats
    }

    /// Samples so far (missing ones included; stored or not).
    pub fn len(&self) -> usize {
        self.store.next
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.store.next == 0
    }

    /// Store the rows at positions `[from, to)` only (and the events among them, moved to
    /// positions from `from`); the record [`finish`](Self::finish) gives then starts at
    /// position `from` (its `t0_s` is `from` periods later) and holds at most `to − from` rows.
    /// Counters stay the whole stream's. Call before the first sample.
    pub fn keep(&mut self, from: usize, to: usize) {
        self.store.keep = Some((from, to.max(from)));
    }

    /// The span [`keep`](Self::keep) set, if any.
    pub fn kept(&self) -> Option<(usize, usize)> {
        self.store.keep
    }

    /// Hands over the rows stored so far; from here on the builder stores the rows after them
    /// (and no events: a builder whose rows are taken gives no record of its events).
    pub fn take_rows(&mut self) -> Rows {
        let st = &mut self.store;
        let start = st.keep.map_or(0, |k| k.0);
        st.keep = Some((st.next, usize::MAX));
        st.events.clear();
        Rows {
            start,
            present: st.present,
            data: std::mem::take(&mut st.data),
            missing: std::mem::take(&mut st.missing),
        }
    }

    /// Feed one decoded frame (SAMPLE, HELLO and EVENT matter; others are ignored).
    pub fn push_frame(&mut self, f: &Frame) {
        if f.msg.is_command() {
            return; // a host frame (an echo, a loopback): not part of the device's stream
        }
        if let Message::Hello(h) = &f.msg {
            if self.boot_id.is_some_and(|b| b != h.boot_id) {
                self.last_seq = None;
            }
            self.boot_id = Some(h.boot_id);
        }
        if let Some(last) = self.last_seq {
            let jump = f.seq.wrapping_sub(last);
            // A jump of half the range or more is a restart, not a loss.
            if (2..0x8000).contains(&jump) {
                self.store.stats.link_frames_lost += (jump - 1) as u64;
            }
        }
        self.last_seq = Some(f.seq);
        match &f.msg {
            Message::Sample(s) => {
                if !s.flags.contains(SampleFlags::THRUST_FRESH) {
                    self.store.stats.thrust_held += 1;
                }
                self.push_point(s.sample_index, s.t_us, sample_values(s));
            }
            Message::Hello(h) => {
                self.asm.hello(h.boot_id, h.sample_rate_hz);
            }
            Message::Event(e) => self.push_event(e),
            _ => {}
        }
    }

    /// A HELLO met outside a frame (a CSV bench's line): a new `boot_id` ends the segment; a
    /// rate of 0 is "not measured yet" ([`SampleAssembler::hello_csv`]).
    pub fn push_hello(&mut self, h: &Hello) {
        self.asm.hello_csv(h.boot_id, h.sample_rate_hz);
    }

    /// A device EVENT met outside a frame (a CSV bench's line): impulse edges and watchdog
    /// trips become record events at the position of their `sample_index`.
    pub fn push_event(&mut self, e: &Event) {
        let kind = match e.code {
            EventCode::ImpulseStart => RecordEventKind::ImpulseStart,
            EventCode::ImpulseEnd => RecordEventKind::ImpulseEnd,
            EventCode::WatchdogTrip => RecordEventKind::WatchdogTrip,
            _ => return,
        };
        let store = &mut self.store;
        self.asm.event(kind, e.sample_index, &mut |a| store.put(a));
    }

    /// Feed one point: device index, device clock (µs) and values.
    pub fn push_point(&mut self, sample_index: u32, t_us: u32, values: Values) {
        let store = &mut self.store;
        self.asm
            .sample(sample_index, t_us, values, &mut |a| store.put(a));
    }

    /// The record so far. Errors: no sample, or no sample period known.
    pub fn finish(self) -> Result<(Record, AssembleStats, BuildStats), IngestError> {
        let mut st = self.store;
        let present = st.present.ok_or(IngestError::NoSamples)?;
        let dt_s = self.asm.dt_s().ok_or(IngestError::NoTimebase)?;
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(IngestError::BadSamplePeriod(dt_s));
        }
        let len = st.next;
        // Events may point past the last sample received (an edge announced, then the stream
        // ended): those cannot be placed.
        let before = st.events.len();
        st.events.retain(|e| e.sample < len);
        let unplaced =
            (before - st.events.len() + st.late.iter().filter(|&&k| k >= len).count()) as u64;
        let mut stats = *self.asm.stats();
        stats.events -= unplaced;
        stats.events_dropped += unplaced;
        st.events.sort_by_key(|e| e.sample);
        let mut t0_s = st.t0_us.unwrap_or(0) as f64 * 1e-6;
        if let Some((from, _)) = st.keep.filter(|k| k.0 > 0) {
            t0_s += from as f64 * dt_s;
            for e in &mut st.events {
                e.sample -= from;
            }
        }
        let channels = CHANNELS
            .iter()
            .zip(st.data)
            .zip(present)
            .filter(|(_, p)| *p)
            .map(|(((name, unit, _), data), _)| Channel::read(*name, *unit, data))
            .collect();
        let record = Record {
            dt_s,
            t0_s,
            channels,
            missing: st.missing,
            events: st.events,
        };
        Ok((record, stats, st.stats))
    }
}

impl Store {
    /// Whether position `k` is stored.
    fn keeps(&self, k: usize) -> bool {
        match self.keep {
            None => true,
            Some((from, to)) => (from..to).contains(&k),
        }
    }

    /// How many of the `count` positions from `k` are stored.
    fn kept_of(&self, k: usize, count: usize) -> usize {
        match self.keep {
            None => count,
            Some((from, to)) => (k + count).min(to).saturating_sub(k.max(from)),
        }
    }

    /// An event at position `k`: stored inside the kept span; after it only remembered until
    /// a row reaches it (placed or not is known at the end).
    fn put_event(&mut self, e: RecordEvent) {
        match self.keep {
            Some((from, to)) if e.sample < from || e.sample >= to => {
                if e.sample >= to {
                    self.late.push(e.sample);
                }
            }
            _ => self.events.push(e),
        }
    }

    fn put(&mut self, a: Assembled<Values>) {
        match a {
            Assembled::Sample { k, t_us, value } => {
                self.t0_us.get_or_insert(t_us);
                let present = *self.present.get_or_insert(value.map(|v| v.is_some()));
                let ok = (0..6).all(|c| !present[c] || value[c].is_some_and(f64::is_finite));
                if !ok {
                    self.stats.invalid_samples += 1;
                }
                if self.keeps(k) {
                    for (d, v) in self.data.iter_mut().zip(value) {
                        d.push(if ok { v.unwrap_or(f64::NAN) } else { f64::NAN });
                    }
                    self.missing.push(!ok);
                }
                self.next = k + 1;
                if !self.late.is_empty() {
                    self.late.retain(|&e| e > k);
                }
            }
            Assembled::Missing { k, count } => {
                let n = self.kept_of(k, count);
                for d in &mut self.data {
                    d.resize(d.len() + n, f64::NAN);
                }
                self.missing.resize(self.missing.len() + n, true);
                self.next = k + count;
            }
            // the first segment starts at 0 implicitly
            Assembled::SegmentStart {
                cause: SegmentCause::First,
                ..
            } => {}
            Assembled::SegmentStart { k, .. } => self.put_event(RecordEvent {
                sample: k,
                kind: RecordEventKind::SegmentStart,
            }),
            Assembled::Event { k, kind } => self.put_event(RecordEvent { sample: k, kind }),
            // counted by the assembler; the samples keep their places
            Assembled::Duplicate
            | Assembled::ClockWrap
            | Assembled::ClockBackwards
            | Assembled::ClockJump { .. }
            | Assembled::RateMismatch { .. }
            | Assembled::EventDropped { .. } => {}
        }
    }
}
