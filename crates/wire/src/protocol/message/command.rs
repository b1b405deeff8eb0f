//! The payloads of host → device commands (docs/PROTOCOL.md §4): ARM and its key, SET_THROTTLE,
//! IMPULSE, SET_RATE (the other commands carry none).

/// The ARM key, bytes "ARM!" read little-endian.
pub const ARM_KEY: u32 = 0x214D_5241;

/// 0x02 ARM.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Arm {
    /// Watchdog, ms (100..5000).
    pub watchdog_ms: u16,
    /// Must be [`ARM_KEY`].
    pub key: u32,
}

impl Arm {
    /// ARM with the right key.
    pub fn new(watchdog_ms: u16) -> Self {
        Self {
            watchdog_ms,
            key: ARM_KEY,
        }
    }
}

/// 0x04 SET_THROTTLE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SetThrottle {
    /// Level 0..10000.
    pub level: u16,
    /// Ramp duration, ms (0 = step).
    pub ramp_ms: u16,
}

/// 0x05 IMPULSE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Impulse {
    /// Absolute pulse level 0..10000 (below the setpoint: a negative pulse).
    pub level: u16,
    /// Pulse width, µs.
    pub width_us: u32,
}

/// 0x08 SET_RATE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SetRate {
    /// New nominal sample rate, Hz.
    pub sample_rate_hz: u16,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arm_key_is_ascii_arm_bang() {
        assert_eq!(ARM_KEY.to_le_bytes(), *b"ARM!");
    }
}
