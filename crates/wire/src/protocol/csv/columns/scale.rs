//! A command's full scale ([`Scale`]): the scales a header's unit declares and the candidates
//! a file's values must choose among ([`Unit::command_scales`]); the rule that chooses lives
//! with the file reader, which alone sees all the values.

use super::{Affine, Unit};

impl Unit {
    /// The full scales a command column of this unit may have in an exported file:
    /// [`CommandScales::Declared`] when the header's unit says it (µs, %, 0..1, DShot),
    /// [`CommandScales::FromValues`] when its values must decide among candidates (a bare
    /// `throttle`, `ESC signal`, `pwm`, `cmd`); `None` for a unit that is not a command's.
    pub fn command_scales(self) -> Option<CommandScales> {
        use CommandScales::{Declared, FromValues};
        Some(match self {
            Unit::PulseMicrosecond => Declared(Scale::ESC_US),
            Unit::Percent => Declared(Scale::PERCENT),
            Unit::Fraction => Declared(Scale::FRACTION),
            Unit::DShot => Declared(Scale::DSHOT),
            // §6's name: its own 0..10000 is one candidate among those files use.
            Unit::ThrottleLevel => FromValues(&[
                Scale::FRACTION,
                Scale::PERCENT,
                Scale::RAW_ESC,
                Scale::ESC_US,
                Scale::TSP1_LEVEL,
                Scale::PWM16,
            ]),
            Unit::Command => FromValues(&[
                Scale::FRACTION,
                Scale::PERCENT,
                Scale::RAW_ESC,
                Scale::ESC_US,
                Scale::PWM16,
            ]),
            _ => return None,
        })
    }
}

/// A command's full scale: `raw_min` is throttle 0, `raw_max` throttle 1.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Scale {
    /// Raw value at zero throttle.
    pub raw_min: f64,
    /// Raw value at full throttle.
    pub raw_max: f64,
    /// The range and its kind, e.g. `0..2047 (DShot/raw ESC)`.
    pub label: &'static str,
    /// The unit as a header writes it (`µs`, `%`, `0..1`, `DShot`; for scales only values
    /// reveal, their kind: `raw ESC`, `TSP/1 level`, `16-bit PWM`).
    pub unit: &'static str,
}

impl Scale {
    /// Throttle as a fraction.
    pub const FRACTION: Scale = Scale::new(0.0, 1.0, "0..1", "0..1");
    /// Percent.
    pub const PERCENT: Scale = Scale::new(0.0, 100.0, "0..100 (%)", "%");
    /// An 11-bit ESC value: DShot's whole range (0 stop, 1..47 commands, 48..2047 throttle),
    /// or a raw ESC scale.
    pub const RAW_ESC: Scale = Scale::new(0.0, 2047.0, "0..2047 (DShot/raw ESC)", "raw ESC");
    /// DShot throttle proper: 48 is zero throttle.
    pub const DSHOT: Scale = Scale::new(48.0, 2047.0, "48..2047 (DShot)", "DShot");
    /// The usual ESC pulse width, µs (`--esc-us` gives another).
    pub const ESC_US: Scale = Scale::new(1000.0, 2000.0, "1000..2000 µs (ESC pulse)", "µs");
    /// TSP/1's throttle level (docs/PROTOCOL.md §6).
    pub const TSP1_LEVEL: Scale = Scale::new(0.0, 10000.0, "0..10000 (TSP/1 level)", "TSP/1 level");
    /// A 16-bit PWM compare value (Crazyflie motors).
    pub const PWM16: Scale = Scale::new(0.0, 65535.0, "0..65535 (16-bit PWM)", "16-bit PWM");

    const fn new(raw_min: f64, raw_max: f64, label: &'static str, unit: &'static str) -> Self {
        Self {
            raw_min,
            raw_max,
            label,
            unit,
        }
    }

    /// The map of this scale onto throttle 0..1.
    pub fn affine(&self) -> Affine {
        Affine {
            zero: self.raw_min,
            mul: 1.0,
            div: self.raw_max - self.raw_min,
        }
    }
}

/// How a command column's full scale is known.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CommandScales {
    /// The header's unit says it.
    Declared(Scale),
    /// The values must decide among these.
    FromValues(&'static [Scale]),
}
