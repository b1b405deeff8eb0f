//! From a stream of device samples to a uniform record: the sample-index bookkeeping (gaps,
//! duplicates, resets, segments), the device clock, and the device events.
//!
//! Two layers:
//! - [`SampleAssembler`] turns (sample_index, t_us) pairs and device events into record
//!   positions `k` — [`Assembled`] items: a sample at `k`, `count` missing samples from `k`, a
//!   new segment at `k`, an event at `k`. It stores nothing per sample, so the daemon's worker can
//!   use it on a live stream.
//! - [`RecordBuilder`] stores the channels and produces the [`Record`].
//!
//! Rules (PROTOCOL.md §3, issue 3 item 2):
//! - The 32-bit `sample_index` and `t_us` are unwrapped ([`Unwrap32`]).
//! - A forward jump of `d > 1` in `sample_index` is a gap: `d − 1` samples are missing (NaN and
//!   marked in `Record::missing`), counted in `samples_lost`, never bridged. A gap longer than
//!   `max_gap_samples` is not filled: a new segment starts after it (still counted as lost).
//!   So is a gap that would take the filled samples past `max_gap_samples + 10 × samples
//!   received`: a few corrupt frames with absurd indices cannot make a small file expand into
//!   gigabytes of NaN.
//! - `d = 0` is a duplicate (dropped, counted); a backward jump is a device reset whose HELLO
//!   was not seen: a new segment.
//! - A HELLO with a new `boot_id` ends the segment; the next sample starts a new one. Later
//!   segments are marked by [`RecordEventKind::SegmentStart`]; the first starts at 0 implicitly.
//!   Segments are appended one after the other on the record's time axis: time across a
//!   segment boundary is *not* device time, and no analysis window may straddle one.
//! - EVENT IMPULSE_START / IMPULSE_END / WATCHDOG_TRIP become record events at the record
//!   position of their `sample_index` (events before the first sample wait for it).
//! - `dt`: the device clock over the sample count, `Σ (t_last − t_first) / Σ (idx_last −
//!   idx_first)` summed over segments (a least-squares-free average immune to jitter and to
//!   gaps); the nominal HELLO rate only when no segment spans two samples.

use serde::Serialize;

use super::clock::{Step, Unwrap32};
use super::IngestError;
use crate::protocol::message::{Event, EventCode, Hello, Message, Sample, SampleFlags};
use crate::protocol::Frame;
use crate::record::{names, Channel, Record, RecordEvent, RecordEventKind};

/// Assembly limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AssembleOptions {
    /// Longest gap filled with missing samples (default 65 536, a minute at 1 kHz); a longer
    /// one starts a new segment.
    pub max_gap_samples: u64,
}

impl Default for AssembleOptions {
    fn default() -> Self {
        Self {
            max_gap_samples: 1 << 16,
        }
    }
}

/// Counters of the assembly, published as part of [`IngestStats`](super::IngestStats).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct AssembleStats {
    /// Samples received and placed.
    pub samples: u64,
    /// Samples missing from index gaps (whatever their cause).
    pub samples_lost: u64,
    /// Number of gaps.
    pub gaps: u64,
    /// Gaps too long to fill (each started a new segment).
    pub large_gaps: u64,
    /// Repeated sample indices, dropped.
    pub duplicates: u64,
    /// Backward index jumps without a new HELLO (a reset), each starting a segment.
    pub resets_inferred: u64,
    /// Segments (boots), at least 1 once a sample arrived.
    pub segments: u64,
    /// Device clock wraps seen.
    pub clock_wraps: u64,
    /// Samples whose clock went backwards while the index went forward.
    pub clock_backwards: u64,
    /// Record events placed.
    pub events: u64,
    /// Events that could not be placed (before their segment, or too many pending).
    pub events_dropped: u64,
}

/// What the assembler says about the record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Assembled<T> {
    /// The sample `value` goes to record position `k`; `t_us` is the unwrapped device clock.
    Sample {
        /// Record position.
        k: usize,
        /// Unwrapped device time, µs (restarts with each segment).
        t_us: u64,
        /// The payload.
        value: T,
    },
    /// `count` samples from position `k` are missing.
    Missing {
        /// First missing position.
        k: usize,
        /// How many.
        count: usize,
    },
    /// A new segment (device boot) starts at `k`.
    SegmentStart {
        /// Position.
        k: usize,
    },
    /// A device event at position `k`.
    Event {
        /// Position.
        k: usize,
        /// Which.
        kind: RecordEventKind,
    },
}

#[derive(Debug, Clone, Copy)]
struct Segment {
    k0: usize,
    idx: Unwrap32,
    clock: Unwrap32,
    idx_first: u64,
    t_first: u64,
}

const MAX_PENDING_EVENTS: usize = 64;

/// Sample-index and clock bookkeeping; see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct SampleAssembler {
    opts: AssembleOptions,
    seg: Option<Segment>,
    boot_id: Option<u32>,
    next_k: usize,
    pending: Vec<(u32, RecordEventKind)>,
    span_t_us: u64,
    span_samples: u64,
    nominal_rate_hz: Option<u16>,
    /// The current segment began at an inferred reset after the last HELLO: the HELLO of
    /// that new boot, when it comes, must not split it again.
    reset_since_hello: bool,
    /// Missing samples filled in so far.
    filled: u64,
    stats: AssembleStats,
}

impl SampleAssembler {
    /// A new assembler.
    pub fn new(opts: AssembleOptions) -> Self {
        Self {
            opts,
            ..Self::default()
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> &AssembleStats {
        &self.stats
    }

    /// Record length so far (next position).
    pub fn len(&self) -> usize {
        self.next_k
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.next_k == 0
    }

    /// Sample period from the device clock (see the module documentation), else from the
    /// nominal HELLO rate; `None` when neither is known.
    pub fn dt_s(&self) -> Option<f64> {
        let (mut t, mut n) = (self.span_t_us, self.span_samples);
        if let Some(s) = &self.seg {
            t += s.clock.value() - s.t_first;
            n += s.idx.value() - s.idx_first;
        }
        if n > 0 && t > 0 {
            Some(t as f64 / n as f64 / 1e6)
        } else {
            self.nominal_dt_s()
        }
    }

    /// Sample period from the last HELLO's nominal rate.
    pub fn nominal_dt_s(&self) -> Option<f64> {
        self.nominal_rate_hz
            .filter(|&r| r > 0)
            .map(|r| 1.0 / r as f64)
    }

    /// A HELLO: a new `boot_id` ends the current segment.
    pub fn hello(&mut self, boot_id: u32, sample_rate_hz: u16) {
        self.nominal_rate_hz = Some(sample_rate_hz);
        if self.boot_id.is_some_and(|b| b != boot_id) && !self.reset_since_hello {
            self.end_segment();
        }
        self.boot_id = Some(boot_id);
        self.reset_since_hello = false;
    }

    /// A device event referring to `sample_index`.
    pub fn event<T>(
        &mut self,
        kind: RecordEventKind,
        sample_index: u32,
        on: &mut impl FnMut(Assembled<T>),
    ) {
        match &self.seg {
            Some(s) => self.place_event(*s, kind, sample_index, on),
            None if self.pending.len() < MAX_PENDING_EVENTS => {
                self.pending.push((sample_index, kind))
            }
            None => self.stats.events_dropped += 1,
        }
    }

    fn place_event<T>(
        &mut self,
        s: Segment,
        kind: RecordEventKind,
        sample_index: u32,
        on: &mut impl FnMut(Assembled<T>),
    ) {
        let rel = s.idx.project(sample_index).map(|v| v - s.idx_first as i64);
        match rel {
            Some(r) if r >= 0 => {
                self.stats.events += 1;
                on(Assembled::Event {
                    k: s.k0 + r as usize,
                    kind,
                });
            }
            _ => self.stats.events_dropped += 1,
        }
    }

    /// A sample with its device `sample_index` and clock `t_us`.
    pub fn sample<T>(
        &mut self,
        sample_index: u32,
        t_us: u32,
        value: T,
        on: &mut impl FnMut(Assembled<T>),
    ) {
        let Some(seg) = self.seg.as_mut() else {
            return self.start_segment(sample_index, t_us, value, on);
        };
        let before = *seg;
        let d = match seg.idx.step(sample_index) {
            Step::Backward => {
                self.stats.resets_inferred += 1;
                self.reset_since_hello = true;
                self.end_segment();
                return self.start_segment(sample_index, t_us, value, on);
            }
            Step::Forward(0) => {
                self.stats.duplicates += 1;
                return;
            }
            Step::Forward(d) => d,
        };
        let lost = d - 1;
        let budget = self.opts.max_gap_samples + 10 * self.stats.samples;
        if lost > self.opts.max_gap_samples || self.filled + lost > budget {
            self.stats.samples_lost += lost;
            self.stats.large_gaps += 1;
            // The segment ends at its last sample, not at the far side of the gap.
            self.seg = Some(before);
            self.end_segment();
            return self.start_segment(sample_index, t_us, value, on);
        }
        let wraps = seg.clock.wraps();
        if seg.clock.step(t_us) == Step::Backward {
            self.stats.clock_backwards += 1;
        }
        self.stats.clock_wraps += seg.clock.wraps() - wraps;
        let t = seg.clock.value();
        if lost > 0 {
            self.filled += lost;
            self.stats.samples_lost += lost;
            self.stats.gaps += 1;
            on(Assembled::Missing {
                k: self.next_k,
                count: lost as usize,
            });
            self.next_k += lost as usize;
        }
        self.emit_sample(t, value, on);
    }

    fn emit_sample<T>(&mut self, t_us: u64, value: T, on: &mut impl FnMut(Assembled<T>)) {
        self.stats.samples += 1;
        on(Assembled::Sample {
            k: self.next_k,
            t_us,
            value,
        });
        self.next_k += 1;
    }

    fn start_segment<T>(
        &mut self,
        sample_index: u32,
        t_us: u32,
        value: T,
        on: &mut impl FnMut(Assembled<T>),
    ) {
        let idx = Unwrap32::start(sample_index);
        let clock = Unwrap32::start(t_us);
        let s = Segment {
            k0: self.next_k,
            idx,
            clock,
            idx_first: idx.value(),
            t_first: clock.value(),
        };
        self.seg = Some(s);
        self.stats.segments += 1;
        if self.next_k > 0 {
            on(Assembled::SegmentStart { k: self.next_k });
        }
        for (i, kind) in std::mem::take(&mut self.pending) {
            self.place_event(s, kind, i, on);
        }
        self.emit_sample(clock.value(), value, on);
    }

    fn end_segment(&mut self) {
        if let Some(s) = self.seg.take() {
            self.span_t_us += s.clock.value() - s.t_first;
            self.span_samples += s.idx.value() - s.idx_first;
        }
    }
}

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

    /// Samples so far (missing ones included).
    pub fn len(&self) -> usize {
        self.store.missing.len()
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.store.missing.is_empty()
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
            Message::Hello(h) => self.push_hello(h),
            Message::Event(e) => self.push_event(e),
            _ => {}
        }
    }

    /// A HELLO met outside a frame (a CSV bench's line): a new `boot_id` ends the segment.
    pub fn push_hello(&mut self, h: &Hello) {
        self.asm.hello(h.boot_id, h.sample_rate_hz);
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
        let len = st.missing.len();
        // Events may point past the last sample received (an edge announced, then the stream
        // ended): those cannot be placed.
        let before = st.events.len();
        st.events.retain(|e| e.sample < len);
        let unplaced = (before - st.events.len()) as u64;
        let mut stats = *self.asm.stats();
        stats.events -= unplaced;
        stats.events_dropped += unplaced;
        st.events.sort_by_key(|e| e.sample);
        let channels = CHANNELS
            .iter()
            .zip(st.data)
            .zip(present)
            .filter(|(_, p)| *p)
            .map(|(((name, unit, _), data), _)| Channel {
                name: name.to_string(),
                unit: unit.to_string(),
                data,
            })
            .collect();
        let record = Record {
            dt_s,
            t0_s: st.t0_us.unwrap_or(0) as f64 * 1e-6,
            channels,
            missing: st.missing,
            events: st.events,
        };
        Ok((record, stats, st.stats))
    }
}

impl Store {
    fn put(&mut self, a: Assembled<Values>) {
        match a {
            Assembled::Sample { t_us, value, .. } => {
                self.t0_us.get_or_insert(t_us);
                let present = *self.present.get_or_insert(value.map(|v| v.is_some()));
                let ok = (0..6).all(|c| !present[c] || value[c].is_some_and(f64::is_finite));
                if !ok {
                    self.stats.invalid_samples += 1;
                }
                for (d, v) in self.data.iter_mut().zip(value) {
                    d.push(if ok { v.unwrap_or(f64::NAN) } else { f64::NAN });
                }
                self.missing.push(!ok);
            }
            Assembled::Missing { count, .. } => {
                for d in &mut self.data {
                    d.resize(d.len() + count, f64::NAN);
                }
                self.missing.resize(self.missing.len() + count, true);
            }
            Assembled::SegmentStart { k } => self.events.push(RecordEvent {
                sample: k,
                kind: RecordEventKind::SegmentStart,
            }),
            Assembled::Event { k, kind } => self.events.push(RecordEvent { sample: k, kind }),
        }
    }
}

#[cfg(test)]
mod tests;
