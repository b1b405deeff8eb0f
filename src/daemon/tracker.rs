//! Sampler-side stream bookkeeping, pure: the device clock, sample-index gaps and boot segments.
//!
//! - **Clock unwrap.** `t_us` is a 32-bit microsecond counter that wraps every 2³² µs ≈ 71.6 min.
//!   A reading smaller than the previous one by more than half the range is a wrap, and adds
//!   2³² to the offset; a smaller backwards step is kept as it is (the device clock is
//!   monotonic; a tiny backwards step can only be a corrupted frame that passed the CRC, and
//!   must not be turned into a 71-minute jump). The same rule unwraps `sample_index`.
//! - **Gaps.** Within a segment, the next sample must have index `last + 1`. A larger index is
//!   a gap of `index − last − 1` lost samples: counted and handed on, never bridged. The same
//!   index again is a duplicate: dropped and counted (the rule of
//!   [`crate::ingest::assemble::SampleAssembler`], so live, replay and `propid identify`
//!   segment a stream alike). A smaller index (with no new HELLO) means the device restarted
//!   and its HELLO was lost: a new segment.
//! - **Segments.** A HELLO whose `boot_id` differs from the current one starts a new segment
//!   (the device reset: disarmed, counters restarted). The host never re-arms by itself; the
//!   experiment plan is told and decides (it reports, it does not re-arm).

/// Unwraps a 32-bit wrapping counter into 64 bits.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Unwrap32 {
    last: Option<u32>,
    offset: u64,
    wraps: u64,
}

impl Unwrap32 {
    /// Unwraps `raw`; see the module docs for the rule.
    pub fn unwrap(&mut self, raw: u32) -> u64 {
        if let Some(last) = self.last {
            if raw < last && last - raw > u32::MAX / 2 {
                self.offset += 1 << 32;
                self.wraps += 1;
            }
        }
        self.last = Some(raw);
        self.offset + u64::from(raw)
    }

    /// Wraps seen so far.
    pub fn wraps(&self) -> u64 {
        self.wraps
    }
}

/// What the tracker says about one SAMPLE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Placed {
    /// Unwrapped sample index within the segment.
    pub index: u64,
    /// Unwrapped device time, µs.
    pub t_us: u64,
    /// Samples lost just before this one (0 = contiguous).
    pub lost_before: u64,
    /// This sample starts a new segment (first sample, or the index went backwards).
    pub new_segment: bool,
    /// The same index as the previous sample: a duplicate, to be dropped.
    pub duplicate: bool,
}

/// Clock, gap and segment tracking for one link.
#[derive(Debug, Clone, Default)]
pub struct Tracker {
    boot_id: Option<u32>,
    clock: Unwrap32,
    index: Unwrap32,
    last_index: Option<u64>,
    segment_pending: bool,
    /// Samples lost to index gaps.
    pub samples_lost: u64,
    /// Gaps seen.
    pub gaps: u64,
    /// Segments started.
    pub segments: u64,
    /// Duplicate samples dropped (same index as the previous one).
    pub duplicates: u64,
}

impl Tracker {
    /// A HELLO arrived; returns true when its `boot_id` starts a new segment.
    /// The first HELLO of a stream joined mid-segment adopts its boot without a restart.
    pub fn hello(&mut self, boot_id: u32) -> bool {
        if self.boot_id == Some(boot_id) {
            return false;
        }
        if self.boot_id.is_none() && self.last_index.is_some() {
            self.boot_id = Some(boot_id);
            return false;
        }
        self.boot_id = Some(boot_id);
        self.restart();
        true
    }

    /// Places one SAMPLE (`sample_index`, `t_us` as sent).
    pub fn sample(&mut self, raw_index: u32, raw_t_us: u32) -> Placed {
        let mut new_segment = std::mem::take(&mut self.segment_pending);
        let mut index = self.index.unwrap(raw_index);
        if self.last_index == Some(index) {
            self.segment_pending = new_segment;
            self.duplicates += 1;
            return Placed {
                index,
                t_us: self.event_time(raw_t_us),
                lost_before: 0,
                new_segment: false,
                duplicate: true,
            };
        }
        if matches!(self.last_index, Some(last) if index < last) {
            // Backwards or repeated with no new HELLO: the device restarted (its boot HELLO
            // was lost). Its boot id is unknown: the next HELLO is adopted, not a new segment.
            self.restart();
            self.boot_id = None;
            self.segment_pending = false;
            new_segment = true;
            index = self.index.unwrap(raw_index);
        }
        let t_us = self.clock.unwrap(raw_t_us);
        let mut lost_before = 0;
        match self.last_index {
            Some(last) => {
                lost_before = index - last - 1;
                if lost_before > 0 {
                    self.gaps += 1;
                    self.samples_lost += lost_before;
                }
            }
            None => new_segment = true,
        }
        if new_segment {
            self.segments += 1;
        }
        self.last_index = Some(index);
        Placed {
            index,
            t_us,
            lost_before,
            new_segment,
            duplicate: false,
        }
    }

    /// Device clock wraps seen.
    pub fn clock_wraps(&self) -> u64 {
        self.clock.wraps()
    }

    /// Unwraps an event's sample index in the current segment's numbering.
    pub fn event_index(&self, raw_index: u32) -> u64 {
        let mut u = self.index;
        u.unwrap(raw_index)
    }

    /// Unwraps an event's device time in the current segment's numbering.
    pub fn event_time(&self, raw_t_us: u32) -> u64 {
        let mut u = self.clock;
        u.unwrap(raw_t_us)
    }

    fn restart(&mut self) {
        let wraps = self.clock.wraps;
        self.clock = Unwrap32 {
            wraps,
            ..Default::default()
        };
        self.index = Unwrap32::default();
        self.last_index = None;
        self.segment_pending = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwrap_counts_wraps_and_ignores_small_backsteps() {
        let mut u = Unwrap32::default();
        assert_eq!(u.unwrap(u32::MAX - 10), u64::from(u32::MAX - 10));
        assert_eq!(u.unwrap(5), (1u64 << 32) + 5);
        assert_eq!(u.wraps(), 1);
        assert_eq!(u.unwrap(3), (1u64 << 32) + 3, "small backstep is no wrap");
        assert_eq!(u.wraps(), 1);
    }

    #[test]
    fn contiguous_samples_have_no_gap() {
        let mut t = Tracker::default();
        assert!(t.hello(7));
        let p = t.sample(0, 100);
        assert!(p.new_segment);
        for i in 1..10u32 {
            let p = t.sample(i, 100 + i * 1000);
            assert_eq!(p.lost_before, 0);
            assert!(!p.new_segment);
        }
        assert_eq!(t.samples_lost, 0);
        assert_eq!(t.segments, 1);
    }

    #[test]
    fn index_jump_is_a_counted_gap() {
        let mut t = Tracker::default();
        t.hello(1);
        t.sample(10, 0);
        let p = t.sample(11, 1000);
        assert_eq!(p.lost_before, 0);
        let p = t.sample(15, 5000);
        assert_eq!((p.index, p.lost_before), (15, 3));
        t.sample(16, 6000);
        let p = t.sample(20, 10_000);
        assert_eq!(p.lost_before, 3);
        assert_eq!((t.gaps, t.samples_lost), (2, 6));
    }

    #[test]
    fn clock_wrap_is_unwrapped_without_a_gap() {
        let mut t = Tracker::default();
        t.hello(1);
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
    }

    #[test]
    fn sample_index_wrap_is_no_gap() {
        let mut t = Tracker::default();
        t.hello(1);
        t.sample(u32::MAX - 1, 0);
        t.sample(u32::MAX, 1);
        let p = t.sample(0, 2);
        assert_eq!(p.lost_before, 0);
        assert!(!p.new_segment);
        assert_eq!(p.index, 1u64 << 32);
    }

    #[test]
    fn new_boot_id_starts_a_segment_same_id_does_not() {
        let mut t = Tracker::default();
        assert!(t.hello(1));
        t.sample(100, 0);
        assert!(!t.hello(1));
        t.sample(101, 1000);
        assert!(t.hello(2));
        let p = t.sample(0, 50);
        assert!(p.new_segment);
        assert_eq!(p.lost_before, 0, "a reboot is not a gap");
        assert_eq!(t.segments, 2);
    }

    #[test]
    fn first_hello_after_joining_mid_stream_is_no_new_segment() {
        let mut t = Tracker::default();
        t.sample(500, 0);
        assert!(!t.hello(9));
        let p = t.sample(501, 1);
        assert!(!p.new_segment);
        assert!(t.hello(10));
    }

    #[test]
    fn repeated_index_is_a_dropped_duplicate_not_a_restart() {
        let mut t = Tracker::default();
        t.hello(1);
        t.sample(10, 0);
        let p = t.sample(10, 0);
        assert!(p.duplicate && !p.new_segment);
        let p = t.sample(11, 1000);
        assert!(!p.duplicate && !p.new_segment);
        assert_eq!((p.index, p.lost_before), (11, 0));
        assert_eq!((t.duplicates, t.segments, t.samples_lost), (1, 1, 0));
    }

    #[test]
    fn index_going_back_without_hello_is_a_new_segment() {
        let mut t = Tracker::default();
        t.hello(1);
        t.sample(500, 0);
        let p = t.sample(3, 10);
        assert!(p.new_segment);
        assert_eq!(p.lost_before, 0);
        assert_eq!(t.samples_lost, 0);
        let p = t.sample(4, 20);
        assert!(!p.new_segment);
        assert_eq!(p.lost_before, 0);
        assert!(!t.hello(2), "the restarted device's HELLO is adopted");
        assert!(!t.sample(5, 30).new_segment);
        assert_eq!(t.segments, 2);
    }
}
