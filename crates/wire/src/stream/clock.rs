//! Unwrapping the 32-bit device clock (µs, wraps every 2³² µs ≈ 71.6 min) and the 32-bit
//! sample index into 64-bit counters.
//!
//! Successive readings are assumed less than half a wrap apart (35.8 min of clock, 2³¹ samples),
//! so the forward distance is `(now − last) mod 2³²`; a distance of 2³¹ or more means the value
//! went *backwards*, which the caller treats as a reset.

/// A 32-bit counter unwrapped into 64 bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Unwrap32 {
    last_raw: u32,
    value: u64,
    wraps: u64,
    started: bool,
}

/// Result of feeding one reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// The first reading, or a forward step of this many counts.
    Forward(u64),
    /// The reading is earlier than the last one (not applied).
    Backward,
}

impl Unwrap32 {
    /// Start from `raw`.
    pub fn start(raw: u32) -> Self {
        Self {
            last_raw: raw,
            value: raw as u64,
            wraps: 0,
            started: true,
        }
    }

    /// Feed the next reading.
    pub fn step(&mut self, raw: u32) -> Step {
        if !self.started {
            *self = Self::start(raw);
            return Step::Forward(0);
        }
        let d = raw.wrapping_sub(self.last_raw);
        if d >= 1 << 31 {
            return Step::Backward;
        }
        if raw < self.last_raw {
            self.wraps += 1;
        }
        self.last_raw = raw;
        self.value += d as u64;
        Step::Forward(d as u64)
    }

    /// The unwrapped value of the last reading.
    pub fn value(&self) -> u64 {
        self.value
    }

    /// How many times the raw counter wrapped.
    pub fn wraps(&self) -> u64 {
        self.wraps
    }

    /// The unwrapped value `raw` would have, if it lies within half a wrap of the last
    /// reading (before or after); `None` before the first reading.
    pub fn project(&self, raw: u32) -> Option<i64> {
        self.started
            .then(|| self.value as i64 + raw.wrapping_sub(self.last_raw) as i32 as i64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwraps_across_the_32_bit_boundary() {
        let mut c = Unwrap32::start(u32::MAX - 500);
        assert_eq!(c.step(u32::MAX - 100), Step::Forward(400));
        assert_eq!(c.step(399), Step::Forward(500));
        assert_eq!(c.value(), u32::MAX as u64 + 400);
        assert_eq!(c.wraps(), 1);
        assert_eq!(c.step(300), Step::Backward);
        assert_eq!(c.value(), u32::MAX as u64 + 400);
        assert_eq!(c.project(389), Some(u32::MAX as i64 + 390));
        assert_eq!(c.project(409), Some(u32::MAX as i64 + 410));
    }
}
