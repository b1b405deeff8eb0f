//! From a stream of device samples to a uniform record: the sample-index bookkeeping (gaps,
//! duplicates, resets, segments), the device clock, and the device events.
//!
//! Two layers:
//! - [`SampleAssembler`] turns (sample_index, t_us) pairs and device events into record
//!   positions `k` and says what happened, as typed [`Assembled`] items: a sample at `k`,
//!   `count` missing samples from `k` (a gap), a new segment at `k` and why ([`SegmentCause`]:
//!   the first, a new boot, the index going back, a gap too long to fill), a duplicate dropped,
//!   a clock wrap or step back, an event at `k` (or dropped). It stores nothing per sample, so
//!   the daemon's sampler uses it on a live stream and reads what it says from these items.
//! - [`RecordBuilder`] stores the channels and produces the [`Record`](crate::record::Record).
//!
//! Rules (docs/PROTOCOL.md §3, issue 3 item 2):
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
//! - **Clock jumps** (issue 27 item 7). Every sample's clock step `Δt` is held against its
//!   index step `Δi` and a period `P`: it agrees when `Δt > 0` and `|Δt − Δi·P|` is at most
//!   [`CLOCK_JUMP_PERIODS`] periods plus [`CLOCK_JUMP_REL`] of `Δi·P`. `P` is the HELLO's period, the period of the
//!   last step that agreed, or the period of the step just before when that one was a jump
//!   (a HELLO that lies about the rate costs one jump, not one per sample). A step that agrees
//!   with none is a jump ([`Assembled::ClockJump`], counted in `clock_jumps`; a backward one in
//!   `clock_backwards` too): the samples go on at their indices (the index is the device's
//!   count of periods, the clock the part that lied), the clock is re-based at the sample
//!   after it, and no span of time crosses it — neither the record's `dt` nor a daemon window
//!   (closed there). The first step of a segment without a HELLO rate has nothing to agree
//!   with and is taken.
//! - **Rate** ([`Assembled::RateMismatch`], once per segment): after [`RATE_CHECK_SAMPLES`]
//!   index steps that agreed, the rate they measure against the HELLO's: off by more than
//!   [`RATE_TOLERANCE`] (relative) is a HELLO that lies (the host sizes pulses from it). A
//!   HELLO rate of 0 is a lie too when the HELLO came in a TSP/1 frame ([`SampleAssembler::hello`]:
//!   a stand must state its rate), and no rate, not checked, when it is a CSV bench's
//!   ([`SampleAssembler::hello_csv`]: its made-up HELLO says 0 before it measured one).
//! - `dt`: the device clock over the sample count, `Σ (t_last − t_first) / Σ (idx_last −
//!   idx_first)` summed over segments and the spans between clock jumps (a least-squares-free
//!   average immune to jitter and to gaps); the nominal HELLO rate only when no segment spans
//!   two samples.

use serde::Serialize;

use super::clock::{Step, Unwrap32};
use crate::record::RecordEventKind;

/// A clock step agrees with a period `P` within this many periods (plus [`CLOCK_JUMP_REL`]):
/// a CSV bench's jitter placed on the nearest index is within one.
pub const CLOCK_JUMP_PERIODS: f64 = 2.0;
/// ... plus this fraction of the step's expected length (a long gap's clock may drift).
pub const CLOCK_JUMP_REL: f64 = 0.1;
/// Index steps that agreed, in a segment, before its measured rate is held against the HELLO's.
pub const RATE_CHECK_SAMPLES: u64 = 200;
/// Largest relative difference between the measured rate and the HELLO's (a crystal is off by
/// 10⁻⁴; a CSV bench's clock a few per cent).
pub const RATE_TOLERANCE: f64 = 0.1;

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
    /// Samples whose clock went backwards while the index went forward (clock jumps too).
    pub clock_backwards: u64,
    /// Clock steps that disagree with their index step (see the module documentation).
    pub clock_jumps: u64,
    /// Segments whose measured rate disagrees with the HELLO's.
    pub rate_mismatches: u64,
    /// Record events placed.
    pub events: u64,
    /// Events that could not be placed (before their segment, or too many pending).
    pub events_dropped: u64,
}

/// What the assembler says happened, item by item, in order.
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
    /// A gap: `count` samples from position `k` are missing (filled, never bridged).
    Missing {
        /// First missing position.
        k: usize,
        /// How many.
        count: usize,
    },
    /// A segment starts at `k` with the sample that follows.
    SegmentStart {
        /// Position.
        k: usize,
        /// Why.
        cause: SegmentCause,
    },
    /// The sample repeated the last index: dropped.
    Duplicate,
    /// The device clock wrapped (2³² µs) at the sample that follows.
    ClockWrap,
    /// The device clock went back while the index went forward (at the sample that follows;
    /// a [`Assembled::ClockJump`] follows).
    ClockBackwards,
    /// The device clock stepped by `step_us` where the index step says `expected_us`: the
    /// clock is re-based at the sample that follows (position `k`); no span of time crosses it.
    ClockJump {
        /// Position of the sample after the jump.
        k: usize,
        /// The clock's step, µs (negative: backwards).
        step_us: i64,
        /// The step the index step and the period expected, µs.
        expected_us: f64,
    },
    /// The segment's measured rate disagrees with the HELLO's (once per segment).
    RateMismatch {
        /// The HELLO's rate, Hz.
        hello_hz: u16,
        /// The rate the samples' clock measures, Hz.
        measured_hz: f64,
    },
    /// A device event at position `k`.
    Event {
        /// Position.
        k: usize,
        /// Which.
        kind: RecordEventKind,
    },
    /// A device event that could not be placed (before its segment, or too many pending).
    EventDropped {
        /// Which.
        kind: RecordEventKind,
    },
}

/// Why a segment starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SegmentCause {
    /// The first sample of the stream.
    First,
    /// The first sample after a HELLO with a new `boot_id`.
    NewBoot,
    /// The index went back without a new HELLO: a device reset whose HELLO was not seen.
    IndexBackwards,
    /// A gap too long to fill: `lost` samples are counted as lost, not filled.
    GapTooLong {
        /// Samples lost in the gap.
        lost: u64,
    },
}

/// What a HELLO did to the stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HelloEffect {
    /// The first HELLO, before any sample: the first segment will be this boot's.
    FirstBoot,
    /// The boot already known.
    SameBoot,
    /// Adopted without a split: the first HELLO of a stream joined mid-segment, or the HELLO
    /// of a reset already inferred from the index going back.
    Adopted,
    /// A new boot: the segment ended; the next sample starts a new one.
    NewBoot,
}

impl HelloEffect {
    /// True when the HELLO starts a segment (the first boot, or a new one).
    pub fn starts_segment(self) -> bool {
        matches!(self, Self::FirstBoot | Self::NewBoot)
    }
}

#[derive(Debug, Clone, Copy)]
struct Segment {
    k0: usize,
    idx: Unwrap32,
    clock: Unwrap32,
    idx_first: u64,
    t_first: u64,
    /// Time and index steps of the segment's spans closed by clock jumps.
    spans: (u64, u64),
    /// Period (µs) of the last step that agreed.
    agreed: Option<f64>,
    /// Period (µs) of the step just before, when it was a jump.
    jumped: Option<f64>,
    /// The rate was held against the HELLO's.
    rate_checked: bool,
}

impl Segment {
    /// Time and index steps measured in this segment (clock jumps left out).
    fn measured(&self) -> (u64, u64) {
        (
            self.spans.0 + (self.clock.value() - self.t_first),
            self.spans.1 + (self.idx.value() - self.idx_first),
        )
    }
}

/// Whether a clock step `dt` µs over `di` index steps agrees with period `p` µs.
fn agrees(dt: i64, di: u64, p: f64) -> bool {
    let expected = di as f64 * p;
    dt > 0 && (dt as f64 - expected).abs() <= CLOCK_JUMP_PERIODS * p + CLOCK_JUMP_REL * expected
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
    /// The last HELLO was a CSV bench's: a rate of 0 there means "not measured yet".
    csv_hello: bool,
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
            let (st, sn) = s.measured();
            t += st;
            n += sn;
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

    /// A HELLO in a TSP/1 frame: a new `boot_id` ends the current segment (see
    /// [`HelloEffect`]); its rate is held against the measured one, 0 included (a lie).
    pub fn hello(&mut self, boot_id: u32, sample_rate_hz: u16) -> HelloEffect {
        self.csv_hello = false;
        self.place_hello(boot_id, sample_rate_hz)
    }

    /// A CSV bench's HELLO (its `# HELLO` line, or the one made up for a bench that never
    /// says one): as [`Self::hello`], but a rate of 0 means "not measured yet", not checked.
    pub fn hello_csv(&mut self, boot_id: u32, sample_rate_hz: u16) -> HelloEffect {
        self.csv_hello = true;
        self.place_hello(boot_id, sample_rate_hz)
    }

    fn place_hello(&mut self, boot_id: u32, sample_rate_hz: u16) -> HelloEffect {
        self.nominal_rate_hz = Some(sample_rate_hz);
        let effect = match self.boot_id {
            Some(b) if b == boot_id => HelloEffect::SameBoot,
            Some(_) if self.reset_since_hello => HelloEffect::Adopted,
            Some(_) => {
                self.end_segment();
                HelloEffect::NewBoot
            }
            None if self.is_empty() => HelloEffect::FirstBoot,
            None => HelloEffect::Adopted,
        };
        self.boot_id = Some(boot_id);
        self.reset_since_hello = false;
        effect
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
            None => {
                self.stats.events_dropped += 1;
                on(Assembled::EventDropped { kind });
            }
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
            _ => {
                self.stats.events_dropped += 1;
                on(Assembled::EventDropped { kind });
            }
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
        let nominal = self.nominal_dt_s().map(|p| p * 1e6);
        let Some(seg) = self.seg.as_mut() else {
            let cause = if self.is_empty() {
                SegmentCause::First
            } else {
                SegmentCause::NewBoot
            };
            return self.start_segment(cause, sample_index, t_us, value, on);
        };
        let before = *seg;
        let d = match seg.idx.step(sample_index) {
            Step::Backward => {
                self.stats.resets_inferred += 1;
                self.reset_since_hello = true;
                self.end_segment();
                let cause = SegmentCause::IndexBackwards;
                return self.start_segment(cause, sample_index, t_us, value, on);
            }
            Step::Forward(0) => {
                self.stats.duplicates += 1;
                return on(Assembled::Duplicate);
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
            let cause = SegmentCause::GapTooLong { lost };
            return self.start_segment(cause, sample_index, t_us, value, on);
        }
        let step_us = seg.clock.project(t_us).unwrap_or(0) - seg.clock.value() as i64;
        let period = step_us as f64 / d as f64;
        let ok = [nominal, seg.agreed, seg.jumped]
            .iter()
            .flatten()
            .any(|&p| agrees(step_us, d, p))
            || (step_us > 0 && nominal.is_none() && seg.agreed.is_none());
        let mut jump = None;
        if ok {
            let wraps = seg.clock.wraps();
            seg.clock.step(t_us);
            let wrapped = seg.clock.wraps() - wraps;
            self.stats.clock_wraps += wrapped;
            if wrapped > 0 {
                on(Assembled::ClockWrap);
            }
            seg.agreed = Some(period);
            seg.jumped = None;
        } else {
            if step_us < 0 {
                self.stats.clock_backwards += 1;
                on(Assembled::ClockBackwards);
            }
            self.stats.clock_jumps += 1;
            let expected_us = d as f64 * nominal.or(seg.agreed).unwrap_or(f64::NAN);
            jump = Some((step_us, expected_us));
            // re-based: the spans so far kept, the jump left out, the index runs on
            let (st, sn) = seg.measured();
            seg.spans = (st, sn - d);
            seg.clock = Unwrap32::start(t_us);
            seg.t_first = seg.clock.value();
            seg.idx_first = seg.idx.value();
            seg.jumped = (step_us > 0).then_some(period);
        }
        let mismatch = self.check_rate();
        let t = self.seg.as_ref().map_or(0, |s| s.clock.value());
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
        if let Some((step_us, expected_us)) = jump {
            on(Assembled::ClockJump {
                k: self.next_k,
                step_us,
                expected_us,
            });
        }
        if let Some((hello_hz, measured_hz)) = mismatch {
            on(Assembled::RateMismatch {
                hello_hz,
                measured_hz,
            });
        }
        self.emit_sample(t, value, on);
    }

    /// The segment's measured rate against the HELLO's, once [`RATE_CHECK_SAMPLES`] index
    /// steps agreed: `Some((hello, measured))` when they disagree (once per segment). A rate
    /// of 0 disagrees with any, except in a CSV bench's HELLO (not measured yet).
    fn check_rate(&mut self) -> Option<(u16, f64)> {
        let hello = self.nominal_rate_hz.filter(|&r| r > 0 || !self.csv_hello)?;
        let seg = self.seg.as_mut()?;
        let (t, n) = seg.measured();
        if seg.rate_checked || n < RATE_CHECK_SAMPLES || t == 0 {
            return None;
        }
        seg.rate_checked = true;
        let measured = n as f64 * 1e6 / t as f64;
        if (measured / f64::from(hello) - 1.0).abs() <= RATE_TOLERANCE {
            return None;
        }
        self.stats.rate_mismatches += 1;
        Some((hello, measured))
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
        cause: SegmentCause,
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
            spans: (0, 0),
            agreed: None,
            jumped: None,
            rate_checked: false,
        };
        self.seg = Some(s);
        self.stats.segments += 1;
        on(Assembled::SegmentStart {
            k: self.next_k,
            cause,
        });
        for (i, kind) in std::mem::take(&mut self.pending) {
            self.place_event(s, kind, i, on);
        }
        self.emit_sample(clock.value(), value, on);
    }

    fn end_segment(&mut self) {
        if let Some(s) = self.seg.take() {
            let (t, n) = s.measured();
            self.span_t_us += t;
            self.span_samples += n;
        }
    }
}

mod builder;

pub use builder::{sample_values, BuildStats, RecordBuilder, Rows, Values, CHANNELS};

#[cfg(test)]
mod tests;
