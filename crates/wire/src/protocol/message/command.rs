//! The host → device commands (docs/PROTOCOL.md §4): ARM and its key, SET_THROTTLE, IMPULSE,
//! SET_RATE, and the payload-less HELLO_REQ, DISARM, STOP, HEARTBEAT, TARE (unit structs: their
//! `Message` variants carry nothing); the layout, CSV command line (§6) and vector of each.

use std::io::Write;

use super::super::payload::{u16_at, u32_at, Writer};
use super::wire_message::{CsvArgError, CsvArgs, CsvCommandForm, Vector, WireMessage};

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

impl WireMessage for Arm {
    const TYPE: u8 = 0x02;
    const NAME: &'static str = "ARM";
    const MIN_LEN: usize = 6;
    const CSV_COMMAND: CsvCommandForm = CsvCommandForm::Reads("ARM");

    fn parse(p: &[u8]) -> Self {
        Arm {
            watchdog_ms: u16_at(p, 0),
            key: u32_at(p, 2),
        }
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u16(self.watchdog_ms);
        w.u32(self.key);
    }

    /// `ARM <watchdog_ms>` (the key is implied).
    fn write_csv_args(&self, w: &mut dyn Write) -> std::io::Result<()> {
        write!(w, " {}", self.watchdog_ms)
    }

    fn parse_csv_args(args: &mut CsvArgs<'_>) -> Result<Self, CsvArgError> {
        Ok(Arm::new(CsvArgs::u16(args.required()?)?))
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 7,
            msg: Arm::new(500),
            wire: "04 01 02 07 09 f4 01 41 52 4d 21 dd 96 00",
            csv: Some("ARM 500"),
        }
    }
}

impl WireMessage for SetThrottle {
    const TYPE: u8 = 0x04;
    const NAME: &'static str = "SET_THROTTLE";
    const MIN_LEN: usize = 4;
    const CSV_COMMAND: CsvCommandForm = CsvCommandForm::Reads("THR");

    fn parse(p: &[u8]) -> Self {
        SetThrottle {
            level: u16_at(p, 0),
            ramp_ms: u16_at(p, 2),
        }
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u16(self.level);
        w.u16(self.ramp_ms);
    }

    /// `THR <level> <ramp_ms>`; read without a ramp it is a step.
    fn write_csv_args(&self, w: &mut dyn Write) -> std::io::Result<()> {
        write!(w, " {} {}", self.level, self.ramp_ms)
    }

    fn parse_csv_args(args: &mut CsvArgs<'_>) -> Result<Self, CsvArgError> {
        let level = CsvArgs::u16(args.required()?)?;
        let ramp_ms = args.optional().map(CsvArgs::u16).transpose()?.unwrap_or(0);
        Ok(SetThrottle { level, ramp_ms })
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 8,
            msg: SetThrottle {
                level: 3500,
                ramp_ms: 0,
            },
            wire: "04 01 04 08 03 ac 0d 01 03 6b 79 00",
            csv: Some("THR 3500 0"),
        }
    }
}

impl WireMessage for Impulse {
    const TYPE: u8 = 0x05;
    const NAME: &'static str = "IMPULSE";
    const MIN_LEN: usize = 6;
    const CSV_COMMAND: CsvCommandForm = CsvCommandForm::Reads("IMP");

    fn parse(p: &[u8]) -> Self {
        Impulse {
            level: u16_at(p, 0),
            width_us: u32_at(p, 2),
        }
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u16(self.level);
        w.u32(self.width_us);
    }

    /// `IMP <level> <width_us>`.
    fn write_csv_args(&self, w: &mut dyn Write) -> std::io::Result<()> {
        write!(w, " {} {}", self.level, self.width_us)
    }

    fn parse_csv_args(args: &mut CsvArgs<'_>) -> Result<Self, CsvArgError> {
        let (level, width) = (args.required()?, args.required()?);
        let level = CsvArgs::u16(level)?;
        let width_us = CsvArgs::u32(width)?;
        Ok(Impulse { level, width_us })
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 9,
            msg: Impulse {
                level: 6000,
                width_us: 20_000,
            },
            wire: "04 01 05 09 05 70 17 20 4e 01 03 18 b6 00",
            csv: Some("IMP 6000 20000"),
        }
    }
}

impl WireMessage for SetRate {
    const TYPE: u8 = 0x08;
    const NAME: &'static str = "SET_RATE";
    const MIN_LEN: usize = 2;

    fn parse(p: &[u8]) -> Self {
        SetRate {
            sample_rate_hz: u16_at(p, 0),
        }
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.u16(self.sample_rate_hz);
    }

    fn vector() -> Vector<Self> {
        Vector {
            seq: 3,
            msg: SetRate {
                sample_rate_hz: 2000,
            },
            wire: "04 01 08 03 05 d0 07 32 58 00",
            csv: None,
        }
    }
}

/// Payload-less commands: each one's unit struct, type code, name, CSV form and vector.
macro_rules! unit_commands {
    ($(
        $(#[$doc:meta])*
        $t:ident {
            code: $code:expr,
            name: $name:expr,
            csv: $csv:expr,
            vector: ($seq:expr, $wire:expr, $line:expr) $(,)?
        }
    )*) => {$(
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
        pub struct $t;

        impl WireMessage for $t {
            const TYPE: u8 = $code;
            const NAME: &'static str = $name;
            const MIN_LEN: usize = 0;
            const CSV_COMMAND: CsvCommandForm = $csv;

            fn parse(_: &[u8]) -> Self {
                $t
            }

            fn write(&self, _: &mut Writer<'_>) {}

            fn parse_csv_args(_: &mut CsvArgs<'_>) -> Result<Self, CsvArgError> {
                Ok($t)
            }

            fn vector() -> Vector<Self> {
                Vector {
                    seq: $seq,
                    msg: $t,
                    wire: $wire,
                    csv: $line,
                }
            }
        }
    )*};
}

unit_commands! {
    /// 0x01 HELLO_REQ: ask for a HELLO (CSV `PING`).
    HelloReq {
        code: 0x01,
        name: "HELLO_REQ",
        csv: CsvCommandForm::Reads("PING"),
        vector: (4, "04 01 01 04 03 26 22 00", Some("PING")),
    }
    /// 0x03 DISARM.
    Disarm {
        code: 0x03,
        name: "DISARM",
        csv: CsvCommandForm::Reads("DISARM"),
        vector: (5, "04 01 03 05 03 46 8e 00", Some("DISARM")),
    }
    /// 0x06 STOP: stop everything (CSV `STOP`, also the single byte `!`).
    Stop {
        code: 0x06,
        name: "STOP",
        csv: CsvCommandForm::Reads("STOP"),
        vector: (10, "04 01 06 0a 03 33 34 00", Some("STOP")),
    }
    /// 0x07 HEARTBEAT: reset the watchdog (CSV `PING`, which reads as HELLO_REQ: any valid
    /// command resets the watchdog).
    Heartbeat {
        code: 0x07,
        name: "HEARTBEAT",
        csv: CsvCommandForm::WritesAs("PING"),
        vector: (6, "04 01 07 06 03 4f c7 00", Some("PING")),
    }
    /// 0x09 TARE: tare the load cell (no CSV form).
    Tare {
        code: 0x09,
        name: "TARE",
        csv: CsvCommandForm::None,
        vector: (11, "04 01 09 0b 03 2c 67 00", None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arm_key_is_ascii_arm_bang() {
        assert_eq!(ARM_KEY.to_le_bytes(), *b"ARM!");
    }
}
