//! Sampler-side stream bookkeeping, pure: the device clock, sample-index gaps and boot segments.
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/link/src/tracker.rs`.

use propid_wire::stream::assemble::{AssembleOptions, AssembleStats, Assembled, SampleAssembler};
use propid_wire::stream::clock::Unwrap32;
use propid_wire::stream::SegmentCause;

/// What the tracker says about one SAMPLE.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    /// Unwrapped device sample index within the segment.
    pub index: u64,
    /// Unwrapped device time, µs (restarts with each segment).
    pub t_us: u64,
    /// Samples lost just before this one (0 = contiguous). With `new_segment` set, a gap too
    /// long to mask: counted, but the window must not bridge it.
    pub lost_before: u64,
    /// This sample starts a new segment (first sample, a new boot, the index went backwards,
    /// or a gap beyond the largest one).
    pub new_segment: bool,
    /// The new segment this sample starts was not announced by a HELLO: announce it now (see
    /// the module documentation, "Announcing"). Implies `new_segment`.
    pub announce: bool,
    /// The same index as the previous sample: a duplicate, to be dropped.
    pub duplicate: bool,
    /// The device clock jumped just before this sample (`step_us` as stepped, `expected_us`
    /// as the index step says): the window must not span it.
    pub clock_jump: Option<(i64, f64)>,
    /// The segment's measured rate disagrees with the HELLO's (`hello_hz`, `measured_hz`;
    /// once per segment).
    pub rate_mismatch: Option<(u16, f64)>,
}

/// Clock, gap and segment tracking for one link; see the module documentation.
#[derive(Debug, Clone)]
pub struct Tracker {
    asm: SampleAssembler,
    /// Device index of the current segment (the assembler decides; this only numbers).
    index: Unwrap32,
    /// Device clock of the current segment, for placing events.
    clock: Unwrap32,
    /// Samples lost to index gaps (large gaps included).
    pub samples_lost: u64,
    /// Gaps seen (large gaps included).
    pub gaps: u64,
    /// Gaps beyond the largest one: each ended its segment instead of being masked.
    pub large_gaps: u64,
    /// A HELLO announced a segment whose first sample has not come yet.
    announced: bool,
    /// Duplicate samples dropped (same index as the previous one).
    pub duplicates: u64,
    /// Backward index jumps without a new HELLO (inferred device resets).
    pub resets: u64,
    /// Device clock wraps seen.
    wraps: u64,
}

impl Default for Tracker {
    fn default() -> Self {
        Tracker::new(AssembleOptions::default())
    }
}

impl Tracker {
    /// A tracker with ingest's rules and limits `opts`.
    pub fn new(opts: AssembleOptions) -> Self {
        Tracker {
            asm: SampleAssembler::new(opts),
            index: Unwrap32::default(),
            clock: Unwrap32::default(),
            samples_lost: 0,
            gaps: 0,
            large_gaps: 0,
            announced: false,
            duplicates: 0,
            resets: 0,
            wraps: 0,
        }
    }

    /// A HELLO in a TSP/1 frame arrived; returns true when its `boot_id` starts a new segment (the first HELLO
    /// before any sample, or a new boot): the segment is announced here, whether or not a
    /// sample ever follows. The first HELLO of a stream joined mid-segment, and the HELLO of a
    /// reset already inferred from the index, are adopted without a split.
    /// The HELLO's rate is the one the assembler holds clock steps and the measured rate
    /// against (its clock-jump and rate rules); 0 is a lie ([`SampleAssembler::hello`]).
    pub fn hello(&mut self, boot_id: u32, sample_rate_hz: u16) -> bool {
        let starts = self.asm.hello(boot_id, sample_rate_hz).starts_segment();
        self.announced |= starts;
        starts
    }

    /// A CSV bench's HELLO, as [`Self::hello`]: a rate of 0 is "not measured yet"
    /// ([`SampleAssembler::hello_csv`]).
    pub fn hello_csv(&mut self, boot_id: u32, sample_rate_hz: u16) -> bool {
        let starts = self.asm.hello_csv(boot_id, sample_rate_hz).starts_segment();
        self.announced |= starts;
        starts
    }

    /// Places one SAMPLE (`sample_index`, `t_us` as sent).
    pub fn sample(&mut self, raw_index: u32, raw_t_us: u32) -> Placed {
        let mut p = Placed {
            index: 0,
            t_us: 0,
            lost_before: 0,
            new_segment: false,
            announce: false,
            duplicate: false,
            clock_jump: None,
            rate_mismatch: None,
        };
        let mut t_us = None;
        let mut wraps = 0;
        let mut cause = None;
        self.asm.sample(raw_index, raw_t_us, (), &mut |a| match a {
            Assembled::Sample { t_us: t, .. } => t_us = Some(t),
            Assembled::Missing { count, .. } => p.lost_before += count as u64,
            Assembled::SegmentStart { cause: c, .. } => cause = Some(c),
            Assembled::Duplicate => p.duplicate = true,
            Assembled::ClockWrap => wraps += 1,
            Assembled::ClockJump {
                step_us,
                expected_us,
                ..
            } => p.clock_jump = Some((step_us, expected_us)),
            Assembled::RateMismatch {
                hello_hz,
                measured_hz,
            } => p.rate_mismatch = Some((hello_hz, measured_hz)),
            Assembled::ClockBackwards
            | Assembled::Event { .. }
            | Assembled::EventDropped { .. } => {}
        });
        self.wraps += wraps;
        if p.duplicate {
            self.duplicates += 1;
            p.index = self.index.value();
            p.t_us = self.event_time(raw_t_us);
            return p;
        }
        if p.lost_before > 0 {
            self.gaps += 1;
        }
        match cause {
            Some(c) => {
                p.new_segment = true;
                p.announce = !std::mem::take(&mut self.announced);
                match c {
                    SegmentCause::GapTooLong { lost } => {
                        p.lost_before = lost;
                        self.gaps += 1;
                        self.large_gaps += 1;
                    }
                    SegmentCause::IndexBackwards => self.resets += 1,
                    SegmentCause::First | SegmentCause::NewBoot => {}
                }
                self.index = Unwrap32::start(raw_index);
                self.clock = Unwrap32::start(raw_t_us);
            }
            None => {
                self.index.step(raw_index);
                if p.clock_jump.is_some() {
                    // re-based as the assembler's: events are placed on the new clock
                    self.clock = Unwrap32::start(raw_t_us);
                } else {
                    self.clock.step(raw_t_us);
                }
            }
        }
        self.samples_lost += p.lost_before;
        p.index = self.index.value();
        p.t_us = t_us.unwrap_or_else(|| self.clock.value());
        p
    }

    /// Device clock wraps seen.
    pub fn clock_wraps(&self) -> u64 {
        self.wraps
    }

    /// The assembler's counters (the same as `propid identify` reports for a recording).
    pub fn assemble_stats(&self) -> &AssembleStats {
        self.asm.stats()
    }

    /// Unwraps an event's sample index in the current segment's numbering (within half a
    /// wrap of the last sample, before or after; as sent before the first sample).
    pub fn event_index(&self, raw_index: u32) -> u64 {
        project(&self.index, raw_index)
    }

    /// Unwraps an event's device time in the current segment's numbering.
    pub fn event_time(&self, raw_t_us: u32) -> u64 {
        project(&self.clock, raw_t_us)
    }
}

/// `raw` unwrapped next to `u`'s last reading (never below 0); `raw` itself before any reading.
fn project(u: &Unwrap32, raw: u32) -> u64 {
    u.project(raw).map_or(u64::from(raw), |v| v.max(0) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_wire::protocol::message::{EscProtocol, Frame, Hello, Message};
    use propid_wire::stream::assemble::RecordBuilder;
    use rand::{Rng, SeedableRng};

    #[test]
    fn contiguous_samples_have_no_gap() {
        let mut t = Tracker::default();
        assert!(t.hello(7, 0));
        let p = t.sample(0, 100);
        assert!(p.new_segment);
        for i in 1..10u32 {
            let p = t.sample(i, 100 + i * 1000);
            assert_eq!(p.lost_before, 0);
            assert!(!p.new_segment);
            assert_eq!((p.index, p.t_us), (u64::from(i), u64::from(100 + i * 1000)));
        }
        assert_eq!(t.samples_lost, 0);
        assert_eq!(t.assemble_stats().segments, 1);
    }

    #[test]
    fn index_jump_is_a_counted_gap() {
        let mut t = Tracker::default();
        t.hello(1, 0);
        t.sample(10, 0);
        let p = t.sample(11, 1000);
        assert_eq!(p.lost_before, 0);
        let p = t.sample(15, 5000);
        assert_eq!((p.index, p.lost_before, p.new_segment), (15, 3, false));
        t.sample(16, 6000);
        let p = t.sample(20, 10_000);
        assert_eq!(p.lost_before, 3);
        assert_eq!((t.gaps, t.samples_lost, t.large_gaps), (2, 6, 0));
    }

    #[test]
    fn gap_of_exactly_the_largest_size_is_masked_one_more_starts_a_segment() {
        let max = AssembleOptions::default().max_gap_samples;
        let mut t = Tracker::default();
        t.hello(1, 0);
        t.sample(0, 0);
        let edge = (max + 1) as u32;
        let p = t.sample(edge, edge * 1000);
        assert_eq!((p.lost_before, p.new_segment), (max, false));
        let p = t.sample(edge + max as u32 + 2, 0);
        assert_eq!((p.lost_before, p.new_segment), (max + 1, true));
        assert_eq!(
            (t.gaps, t.large_gaps, t.assemble_stats().segments),
            (2, 1, 2)
        );
        assert_eq!(t.samples_lost, 2 * max + 1);
    }

    #[test]
    fn jump_beyond_the_largest_gap_is_counted_but_never_bridged() {
        // a frame whose absurd index passed the CRC, then the stream goes on as before
        let mut t = Tracker::default();
        t.hello(1, 0);
        for i in 0..5u32 {
            t.sample(i, i * 1000);
        }
        let p = t.sample(2_000_000_000, 5000);
        assert!(p.new_segment, "not bridged inside the segment");
        assert_eq!(p.lost_before, 2_000_000_000 - 5);
        assert_eq!(p.index, 2_000_000_000);
        // back to the real numbering: the index went backwards, a reset (another segment)
        let p = t.sample(5, 5000);
        assert!(p.new_segment);
        assert_eq!((p.index, p.lost_before), (5, 0));
        let p = t.sample(6, 6000);
        assert_eq!((p.index, p.lost_before, p.new_segment), (6, 0, false));
        assert_eq!(
            (t.large_gaps, t.resets, t.assemble_stats().segments),
            (1, 1, 3)
        );
        // the same counts as ingest's assembler: one rule for live and offline
        assert_eq!(t.assemble_stats().samples_lost, t.samples_lost);
    }

    #[test]
    fn many_gaps_beyond_the_fill_budget_start_segments() {
        // budget: max_gap + 10 × samples received, over the whole stream
        let mut t = Tracker::new(AssembleOptions {
            max_gap_samples: 1000,
        });
        t.hello(1, 0);
        for i in 0..10u32 {
            t.sample(i, i);
        }
        let p = t.sample(910, 910); // 900 filled ≤ 1000 + 100
        assert!(!p.new_segment && p.lost_before == 900);
        let p = t.sample(1161, 1161); // 900 + 250 > 1000 + 110
        assert!(p.new_segment && p.lost_before == 250);
        assert_eq!((t.samples_lost, t.large_gaps), (1150, 1));
    }

    #[test]
    fn clock_wrap_is_unwrapped_without_a_gap() {
        let mut t = Tracker::default();
        t.hello(1, 0);
        let start = u32::MAX - 2500;
        let mut last = 0u64;
        for i in 0..10u32 {
            let p = t.sample(i, start.wrapping_add(i * 1000));
            assert_eq!(p.lost_before, 0);
            if i > 0 {
                assert_eq!(p.t_us - last, 1000);
            }
            last = p.t_us;
        }
        assert_eq!(t.clock_wraps(), 1);
        assert_eq!(t.event_time(start.wrapping_add(9500)), last + 500);
        assert_eq!(t.event_index(12), 12);
    }

    #[test]
    fn sample_index_wrap_is_no_gap() {
        let mut t = Tracker::default();
        t.hello(1, 0);
        t.sample(u32::MAX - 1, 0);
        t.sample(u32::MAX, 1);
        let p = t.sample(0, 2);
        assert_eq!(p.lost_before, 0);
        assert!(!p.new_segment);
        assert_eq!(p.index, 1u64 << 32);
        assert_eq!(t.event_index(1), (1u64 << 32) + 1);
    }

    #[test]
    fn new_boot_id_starts_a_segment_same_id_does_not() {
        let mut t = Tracker::default();
        assert!(t.hello(1, 0));
        t.sample(100, 0);
        assert!(!t.hello(1, 0));
        t.sample(101, 1000);
        assert!(t.hello(2, 0));
        let p = t.sample(0, 50);
        assert!(p.new_segment);
        assert_eq!(p.lost_before, 0, "a reboot is not a gap");
        assert_eq!(t.assemble_stats().segments, 2);
    }

    #[test]
    fn first_hello_after_joining_mid_stream_is_no_new_segment() {
        let mut t = Tracker::default();
        t.sample(500, 0);
        assert!(!t.hello(9, 0));
        let p = t.sample(501, 1);
        assert!(!p.new_segment);
        assert!(t.hello(10, 0));
    }

    #[test]
    fn repeated_index_is_a_dropped_duplicate_not_a_restart() {
        let mut t = Tracker::default();
        t.hello(1, 0);
        t.sample(10, 0);
        let p = t.sample(10, 0);
        assert!(p.duplicate && !p.new_segment);
        let p = t.sample(11, 1000);
        assert!(!p.duplicate && !p.new_segment);
        assert_eq!((p.index, p.lost_before), (11, 0));
        assert_eq!(
            (t.duplicates, t.assemble_stats().segments, t.samples_lost),
            (1, 1, 0)
        );
    }

    #[test]
    fn index_going_back_without_hello_is_a_new_segment() {
        let mut t = Tracker::default();
        t.hello(1, 0);
        t.sample(500, 0);
        let p = t.sample(3, 10);
        assert!(p.new_segment);
        assert_eq!(p.lost_before, 0);
        assert_eq!(t.samples_lost, 0);
        let p = t.sample(4, 20);
        assert!(!p.new_segment);
        assert_eq!(p.lost_before, 0);
        assert!(!t.hello(2, 0), "the restarted device's HELLO is adopted");
        assert!(!t.sample(5, 30).new_segment);
        assert_eq!(t.assemble_stats().segments, 2);
    }

    /// Every segment is announced once: by the HELLO that starts it, else by its first
    /// sample; a HELLO of a new boot with nothing after it (a reset at the end of a run) too.
    #[test]
    fn each_segment_is_announced_once_a_last_hello_included() {
        let mut t = Tracker::default();
        let mut announced = Vec::new();
        let sample = |t: &mut Tracker, i: u32, a: &mut Vec<&str>| {
            let p = t.sample(i, i * 1000);
            assert!(!p.announce || p.new_segment);
            if p.announce {
                a.push("sample");
            }
        };
        sample(&mut t, 0, &mut announced); // no HELLO: the first sample announces
        sample(&mut t, 1, &mut announced);
        assert!(!t.hello(4, 0), "joined mid-stream: adopted");
        sample(&mut t, 2, &mut announced);
        sample(&mut t, 0, &mut announced); // the index going back: announced by the sample
        if t.hello(5, 0) {
            announced.push("hello"); // not: the inferred reset's HELLO is adopted
        }
        if t.hello(6, 0) {
            announced.push("hello"); // a new boot, announced by its HELLO ...
        }
        sample(&mut t, 0, &mut announced); // ... not again by its first sample
        sample(&mut t, 1, &mut announced);
        if t.hello(7, 0) {
            announced.push("hello"); // a reset as the last thing received
        }
        assert_eq!(announced, ["sample", "sample", "hello", "hello"]);
        // the record holds three segments of samples; the fourth boot has none
        assert_eq!(t.assemble_stats().segments, 3);
    }

    fn hello_frame(boot_id: u32) -> Frame {
        Frame {
            seq: 0,
            msg: Message::Hello(Hello {
                proto_minor: 0,
                esc_protocol: EscProtocol::from_u8(5),
                fw_version: 1,
                boot_id,
                t_us: 0,
                sample_rate_hz: 1000,
                channels: 1,
                motor_poles: 14,
                caps: 0,
                name: [0; 16],
            }),
        }
    }

    #[test]
    fn live_tracker_and_offline_record_place_random_streams_alike() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        for _ in 0..50 {
            let opts = AssembleOptions {
                max_gap_samples: rng.gen_range(1..200),
            };
            let mut t = Tracker::new(opts);
            let mut b = RecordBuilder::new(opts);
            let (mut idx, mut clock) = (rng.gen::<u32>(), rng.gen::<u32>());
            let mut positions = 0u64;
            let mut started = 0u64;
            let mut last: Option<Placed> = None;
            for _ in 0..400 {
                let r: f64 = rng.gen();
                if r < 0.02 {
                    let boot = rng.gen_range(1..4);
                    b.push_frame(&hello_frame(boot));
                    t.hello(boot, 0);
                    continue;
                }
                idx = match r {
                    r if r < 0.10 => idx,                                      // duplicate
                    r if r < 0.20 => idx.wrapping_add(rng.gen_range(2..300)),  // gap
                    r if r < 0.23 => idx.wrapping_sub(rng.gen_range(1..1000)), // reset
                    r if r < 0.25 => idx.wrapping_add(rng.gen_range(1 << 20..1 << 30)),
                    _ => idx.wrapping_add(1),
                };
                clock = clock.wrapping_add(rng.gen_range(0..3_000_000));
                b.push_point(idx, clock, [Some(0.5), None, None, None, None, None]);
                let p = t.sample(idx, clock);
                if p.duplicate {
                    continue;
                }
                started += u64::from(p.new_segment);
                if !p.new_segment {
                    positions += p.lost_before;
                    let prev = last.expect("a sample before");
                    assert_eq!(p.index, prev.index + p.lost_before + 1);
                } else {
                    assert_eq!(p.index, u64::from(idx));
                }
                positions += 1;
                last = Some(p);
            }
            let s = *b.assembler().stats();
            assert_eq!(b.len() as u64, positions, "same record positions");
            assert_eq!(s.samples_lost, t.samples_lost);
            assert_eq!(s.gaps + s.large_gaps, t.gaps);
            assert_eq!(s.segments, started, "the same segments started");
            assert_eq!(s.duplicates, t.duplicates);
            assert_eq!(s.clock_wraps, t.clock_wraps());
        }
    }
}
