//! 0x42 SAMPLE (docs/PROTOCOL.md §3): one measurement, its flags, and the throttle scale of the
//! wire; its layout, its CSV row (`t_us,throttle,thrust_N,torque_Nm,rpm,voltage_V,current_A*HH`,
//! §6's header-less order with its checksum) and its vector.

use std::fmt::Write as _;

use super::super::csv::line::append_checksum;
use super::super::payload::{f32_at, u16_at, u32_at, Writer};
use super::wire_message::{Vector, WireMessage};

/// SAMPLE flags (docs/PROTOCOL.md §3), a `u16` bit set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, serde::Serialize)]
pub struct SampleFlags(pub u16);

impl SampleFlags {
    /// bit0: motor armed.
    pub const ARMED: Self = Self(1 << 0);
    /// bit1: thrust is measured.
    pub const THRUST_VALID: Self = Self(1 << 1);
    /// bit2: torque is measured.
    pub const TORQUE_VALID: Self = Self(1 << 2);
    /// bit3: rotor speed is measured.
    pub const RPM_VALID: Self = Self(1 << 3);
    /// bit4: supply voltage is measured.
    pub const VOLTAGE_VALID: Self = Self(1 << 4);
    /// bit5: current is measured.
    pub const CURRENT_VALID: Self = Self(1 << 5);
    /// bit6: a device-timed impulse is running.
    pub const IMPULSE_ACTIVE: Self = Self(1 << 6);
    /// bit7: a throttle ramp is running.
    pub const RAMP_ACTIVE: Self = Self(1 << 7);
    /// bit8: the watchdog tripped.
    pub const WATCHDOG_TRIPPED: Self = Self(1 << 8);
    /// bit9: a limit cut the motor off.
    pub const LIMIT_CUTOFF: Self = Self(1 << 9);
    /// bit10: a new thrust conversion since the last SAMPLE.
    pub const THRUST_FRESH: Self = Self(1 << 10);
    /// bit11: a new rpm measurement since the last SAMPLE.
    pub const RPM_FRESH: Self = Self(1 << 11);
    /// bit12: ESC telemetry is stale.
    pub const ESC_TELEM_STALE: Self = Self(1 << 12);
    /// bit13: the ADC saturated.
    pub const ADC_SATURATED: Self = Self(1 << 13);

    /// The raw bits.
    pub fn bits(self) -> u16 {
        self.0
    }

    /// True when every bit of `other` is set.
    pub fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// Set the bits of `other`.
    pub fn insert(&mut self, other: Self) {
        self.0 |= other.0;
    }

    /// Clear the bits of `other`.
    pub fn remove(&mut self, other: Self) {
        self.0 &= !other.0;
    }
}

impl std::ops::BitOr for SampleFlags {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

/// Throttle full scale on the wire: 10000 = 100.00 %.
pub const THROTTLE_FULL_SCALE: u16 = 10_000;

/// Throttle fraction (0..1) from the wire level (0..10000). Values above full scale are kept
/// (the caller decides whether they are an error).
pub fn throttle_fraction(level: u16) -> f64 {
    level as f64 / THROTTLE_FULL_SCALE as f64
}

/// Wire level (0..10000) from a throttle fraction, rounded, clamped to 0..=10000 (NaN → 0).
pub fn throttle_level(fraction: f64) -> u16 {
    let v = (fraction * THROTTLE_FULL_SCALE as f64).round();
    if v.is_nan() || v <= 0.0 {
        0
    } else if v >= THROTTLE_FULL_SCALE as f64 {
        THROTTLE_FULL_SCALE
    } else {
        v as u16
    }
}

/// 0x42 SAMPLE: one per sample period.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// +1 per sample taken; a jump is a device-side drop.
    pub sample_index: u32,
    /// Device clock at the ADC instant, µs (wraps every 2³² µs ≈ 71.6 min).
    pub t_us: u32,
    /// Throttle applied during this sample period, 0..10000.
    pub throttle: u16,
    /// Flags, see [`SampleFlags`].
    pub flags: SampleFlags,
    /// Thrust, N.
    pub thrust_n: f32,
    /// Torque, N·m.
    pub torque_nm: f32,
    /// Rotor speed, rev/min (mechanical).
    pub rpm: f32,
    /// Supply voltage, V.
    pub voltage_v: f32,
    /// Current, A.
    pub current_a: f32,
}

impl Sample {
    /// Applied throttle as a fraction 0..1.
    pub fn throttle_fraction(&self) -> f64 {
        throttle_fraction(self.throttle)
    }

    /// True when the motor is armed.
    pub fn is_armed(&self) -> bool {
        self.flags.contains(SampleFlags::ARMED)
    }

    /// The value when its `*_VALID` flag is set, else `None`.
    fn valid(&self, flag: SampleFlags, v: f32) -> Option<f32> {
        self.flags.contains(flag).then_some(v)
    }

    /// Thrust (N) if valid.
    pub fn thrust(&self) -> Option<f32> {
        self.valid(SampleFlags::THRUST_VALID, self.thrust_n)
    }

    /// Torque (N·m) if valid.
    pub fn torque(&self) -> Option<f32> {
        self.valid(SampleFlags::TORQUE_VALID, self.torque_nm)
    }

    /// Rotor speed (rev/min) if valid.
    pub fn rotor_rpm(&self) -> Option<f32> {
        self.valid(SampleFlags::RPM_VALID, self.rpm)
    }

    /// Supply voltage (V) if valid.
    pub fn voltage(&self) -> Option<f32> {
        self.valid(SampleFlags::VOLTAGE_VALID, self.voltage_v)
    }

    /// Current (A) if valid.
    pub fn current(&self) -> Option<f32> {
        self.valid(SampleFlags::CURRENT_VALID, self.current_a)
    }
}

impl WireMessage for Sample {
    const TYPE: u8 = 0x42;
    const NAME: &'static str = "SAMPLE";
    const MIN_LEN: usize = 32;

    fn parse(p: &[u8]) -> Self {
        Sample {
            sample_index: u32_at(p, 0),
            t_us: u32_at(p, 4),
            throttle: u16_at(p, 8),
            flags: SampleFlags(u16_at(p, 10)),
            thrust_n: f32_at(p, 12),
            torque_nm: f32_at(p, 16),
            rpm: f32_at(p, 20),
            voltage_v: f32_at(p, 24),
            current_a: f32_at(p, 28),
        }
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u32(self.sample_index);
        w.u32(self.t_us);
        w.u16(self.throttle);
        w.u16(self.flags.0);
        w.f32(self.thrust_n);
        w.f32(self.torque_nm);
        w.f32(self.rpm);
        w.f32(self.voltage_v);
        w.f32(self.current_a);
    }

    /// A header-less data row with its checksum (read back through the CSV header machinery,
    /// not as a message).
    fn write_csv_line(&self, s: &mut String) -> bool {
        let _ = write!(
            s,
            "{},{},{:.4},{:.5},{:.1},{:.3},{:.3}",
            self.t_us,
            self.throttle,
            self.thrust_n,
            self.torque_nm,
            self.rpm,
            self.voltage_v,
            self.current_a
        );
        append_checksum(s);
        true
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 0x1234,
            msg: Sample {
                sample_index: 123_456,
                t_us: 4_000_000_123,
                throttle: 1500,
                flags: SampleFlags(0x003F),
                thrust_n: 4.25,
                torque_nm: 0.061,
                rpm: 12000.0,
                voltage_v: 16.80,
                current_a: 12.34,
            },
            wire: "08 01 42 34 12 40 e2 01 08 7b 28 6b ee dc 05 3f 01 01 07 88 40 23 db 79
                   3d 0e 80 3b 46 66 66 86 41 a4 70 45 41 07 39 00",
            csv: Some("4000000123,1500,4.2500,0.06100,12000.0,16.800,12.340*12"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn throttle_conversions() {
        assert_eq!(throttle_fraction(3500), 0.35);
        assert_eq!(throttle_level(0.35), 3500);
        assert_eq!(throttle_level(-1.0), 0);
        assert_eq!(throttle_level(2.0), 10_000);
        assert_eq!(throttle_level(f64::NAN), 0);
    }

    #[test]
    fn sample_flag_helpers() {
        let s = Sample {
            flags: SampleFlags::ARMED | SampleFlags::THRUST_VALID,
            thrust_n: 1.5,
            rpm: 100.0,
            ..Sample::default()
        };
        assert!(s.is_armed());
        assert_eq!(s.thrust(), Some(1.5));
        assert_eq!(s.rotor_rpm(), None);
        let mut f = s.flags;
        f.remove(SampleFlags::ARMED);
        f.insert(SampleFlags::RPM_VALID);
        assert_eq!(f.bits(), 0b1010);
    }
}
