//! 0x41 HELLO (docs/PROTOCOL.md §3): the device's identity and state, with its ESC protocol and
//! capability codes; its layout, its CSV line (`# HELLO <name> fw <version> boot_id <hex>
//! rate_hz <rate>`) and its vector.

use std::fmt::Write as _;

use super::super::payload::{u16_at, u32_at, Writer};
use super::wire_message::{Vector, WireMessage};
use super::{floor_char_boundary, utf8_prefix, SampleFlags};

/// ESC protocol reported in HELLO.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum EscProtocol {
    /// 50 Hz PWM.
    Pwm50,
    /// 400 Hz PWM.
    Pwm400,
    /// OneShot125.
    OneShot125,
    /// DShot150.
    DShot150,
    /// DShot300.
    DShot300,
    /// DShot600.
    DShot600,
    /// DShot1200.
    DShot1200,
    /// No ESC (255).
    None,
    /// A code this version does not know.
    Other(u8),
}

impl EscProtocol {
    /// From the wire code.
    pub fn from_u8(v: u8) -> Self {
        match v {
            0 => Self::Pwm50,
            1 => Self::Pwm400,
            2 => Self::OneShot125,
            3 => Self::DShot150,
            4 => Self::DShot300,
            5 => Self::DShot600,
            6 => Self::DShot1200,
            255 => Self::None,
            o => Self::Other(o),
        }
    }

    /// The wire code.
    pub fn to_u8(self) -> u8 {
        match self {
            Self::Pwm50 => 0,
            Self::Pwm400 => 1,
            Self::OneShot125 => 2,
            Self::DShot150 => 3,
            Self::DShot300 => 4,
            Self::DShot600 => 5,
            Self::DShot1200 => 6,
            Self::None => 255,
            Self::Other(o) => o,
        }
    }
}

/// HELLO capability bits (`caps`).
pub mod caps {
    /// Device-timed impulses.
    pub const IMPULSE: u8 = 1 << 0;
    /// Throttle ramps.
    pub const RAMP: u8 = 1 << 1;
    /// Load-cell tare.
    pub const TARE: u8 = 1 << 2;
    /// SET_RATE.
    pub const SET_RATE: u8 = 1 << 3;
}

/// 0x41 HELLO: at boot, on HELLO_REQ and every second.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hello {
    /// Protocol minor version.
    pub proto_minor: u8,
    /// ESC protocol in use.
    pub esc_protocol: EscProtocol,
    /// Firmware version.
    pub fw_version: u16,
    /// Random per boot: a change means the device reset.
    pub boot_id: u32,
    /// Device clock now, µs.
    pub t_us: u32,
    /// Nominal sample rate, Hz.
    pub sample_rate_hz: u16,
    /// Channels present: bit `i` = SAMPLE flag bit `i + 1` (bit0 thrust … bit4 current).
    pub channels: u16,
    /// Motor pole count (0 unknown).
    pub motor_poles: u8,
    /// Capabilities, see [`caps`].
    pub caps: u8,
    /// Device name, NUL-padded ASCII.
    pub name: [u8; 16],
}

impl Hello {
    /// The name up to the first NUL (invalid UTF-8 is cut at the first bad byte).
    pub fn name_str(&self) -> &str {
        let end = self.name.iter().position(|&b| b == 0).unwrap_or(16);
        utf8_prefix(&self.name[..end])
    }

    /// A NUL-padded name field from `name` (truncated to 16 bytes at a char boundary).
    pub fn name_field(name: &str) -> [u8; 16] {
        let mut out = [0u8; 16];
        let cut = floor_char_boundary(name, 16);
        out[..cut].copy_from_slice(&name.as_bytes()[..cut]);
        out
    }

    /// True when the SAMPLE channel with this `*_VALID` flag is present.
    pub fn has_channel(&self, valid_flag: SampleFlags) -> bool {
        (self.channels << 1) & valid_flag.0 != 0
    }

    /// True when all bits of `cap` (see [`caps`]) are set.
    pub fn has_cap(&self, cap: u8) -> bool {
        self.caps & cap == cap
    }
}

impl WireMessage for Hello {
    const TYPE: u8 = 0x41;
    const NAME: &'static str = "HELLO";
    const MIN_LEN: usize = 34;

    fn parse(p: &[u8]) -> Self {
        let mut name = [0u8; 16];
        name.copy_from_slice(&p[18..34]);
        Hello {
            proto_minor: p[0],
            esc_protocol: EscProtocol::from_u8(p[1]),
            fw_version: u16_at(p, 2),
            boot_id: u32_at(p, 4),
            t_us: u32_at(p, 8),
            sample_rate_hz: u16_at(p, 12),
            channels: u16_at(p, 14),
            motor_poles: p[16],
            caps: p[17],
            name,
        }
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u8(self.proto_minor);
        w.u8(self.esc_protocol.to_u8());
        w.u16(self.fw_version);
        w.u32(self.boot_id);
        w.u32(self.t_us);
        w.u16(self.sample_rate_hz);
        w.u16(self.channels);
        w.u8(self.motor_poles);
        w.u8(self.caps);
        w.bytes(&self.name);
    }

    fn write_csv_line(&self, s: &mut String) -> bool {
        let _ = write!(
            s,
            "# HELLO {} fw {} boot_id {:08x} rate_hz {}",
            self.name_str(),
            self.fw_version,
            self.boot_id,
            self.sample_rate_hz
        );
        true
    }

    /// Lenient about order and extra words (without `boot_id` boot 0, without `rate_hz` rate
    /// 0 = unknown), strict about numbers (a malformed one: not a HELLO).
    fn read_csv_line(text: &str) -> Option<Self> {
        let mut words = text.split_whitespace();
        if words.next()? != "HELLO" {
            return None;
        }
        let mut hello = Hello {
            proto_minor: 0,
            esc_protocol: EscProtocol::None,
            fw_version: 0,
            boot_id: 0,
            t_us: 0,
            sample_rate_hz: 0,
            channels: 0,
            motor_poles: 0,
            caps: 0,
            name: [0; 16],
        };
        let mut first = true;
        while let Some(w) = words.next() {
            match w {
                "fw" => hello.fw_version = words.next()?.parse().ok()?,
                "boot_id" => hello.boot_id = u32::from_str_radix(words.next()?, 16).ok()?,
                "rate_hz" => hello.sample_rate_hz = words.next()?.parse().ok()?,
                name if first => hello.name = Hello::name_field(name),
                _ => {}
            }
            first = false;
        }
        Some(hello)
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 0,
            msg: Hello {
                proto_minor: 2,
                esc_protocol: EscProtocol::DShot300,
                fw_version: 0x0102,
                boot_id: 0xDEAD_BEEF,
                t_us: 99,
                sample_rate_hz: 1000,
                channels: 0x1F,
                motor_poles: 14,
                caps: 0x0F,
                name: Hello::name_field("sim-stand"),
            },
            wire: "03 01 41 01 0a 02 04 02 01 ef be ad de 63 01 01 04 e8 03 1f 0c 0e 0f 73 69 6d 2d
                   73 74 61 6e 64 01 01 01 01 01 01 03 83 d2 00",
            csv: Some("# HELLO sim-stand fw 258 boot_id deadbeef rate_hz 1000"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hello_channels_are_flags_shifted_right() {
        let h = Hello {
            proto_minor: 0,
            esc_protocol: EscProtocol::DShot600,
            fw_version: 1,
            boot_id: 7,
            t_us: 0,
            sample_rate_hz: 1000,
            channels: 0b00101, // thrust, rpm
            motor_poles: 14,
            caps: caps::IMPULSE | caps::TARE,
            name: Hello::name_field("stand"),
        };
        assert!(h.has_channel(SampleFlags::THRUST_VALID));
        assert!(!h.has_channel(SampleFlags::TORQUE_VALID));
        assert!(h.has_channel(SampleFlags::RPM_VALID));
        assert!(h.has_cap(caps::TARE) && !h.has_cap(caps::RAMP));
        assert_eq!(h.name_str(), "stand");
    }
}
