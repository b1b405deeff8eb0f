//! CSV column names → canonical quantities and units (PROTOCOL.md §6), shared by the live
//! CSV decoder and by file readers (exported logs of commercial stands): the one alias table
//! and the one quantity → name table ([`Quantity::name`]) of the project.
//!
//! A header name is normalised before lookup (see [`normalise`]): a UTF-8 BOM and surrounding
//! space are dropped, letters lower-cased, `µ`/`μ` written `u`, `[`/`]` written `(`/`)`, and
//! spaces, `·`, `⋅`, `.`, `*` removed. `Torque (N·m)`, `torque(nm)` and `TORQUE [N.m]` all become
//! `torque(nm)`. The alias table then maps the normalised name to a [`ColumnSpec`]; the
//! conversion to canonical units (throttle fraction, s, N, N·m, rev/min, V, A) is affine,
//! `canonical = (raw - zero) * mul / div`, and some units need options ([`ConvOptions`]).

use crate::record::names;

/// Standard gravity, m/s² (for gram-force and kilogram-force).
pub const G0: f64 = 9.80665;
/// One pound-force in newtons.
pub const LBF_N: f64 = 4.448_221_615_260_5;

/// What a column measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Quantity {
    /// Time stamp.
    Time,
    /// Device sample index.
    Index,
    /// Applied throttle.
    Throttle,
    /// Thrust.
    Thrust,
    /// Torque.
    Torque,
    /// Mechanical rotor speed.
    Rpm,
    /// Supply voltage.
    Voltage,
    /// Supply current.
    Current,
}

impl Quantity {
    /// The one name table of the dialect: the §6 name of the quantity's column in the
    /// header-less order (`t_us,throttle,thrust_N,…`, plus `idx`), which for a channel is also
    /// its canonical record name ([`names`]).
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Time => "t_us",
            Quantity::Index => "idx",
            Quantity::Throttle => names::THROTTLE,
            Quantity::Thrust => names::THRUST,
            Quantity::Torque => names::TORQUE,
            Quantity::Rpm => names::RPM,
            Quantity::Voltage => names::VOLTAGE,
            Quantity::Current => names::CURRENT,
        }
    }

    /// Canonical channel name of the record (`None` for time and index, which are the time base).
    pub fn channel_name(self) -> Option<&'static str> {
        match self {
            Quantity::Time | Quantity::Index => None,
            q => Some(q.name()),
        }
    }

    /// Canonical unit text.
    pub fn canonical_unit(self) -> &'static str {
        match self {
            Quantity::Time => "s",
            Quantity::Index | Quantity::Throttle => "1",
            Quantity::Thrust => "N",
            Quantity::Torque => "N·m",
            Quantity::Rpm => "rev/min",
            Quantity::Voltage => "V",
            Quantity::Current => "A",
        }
    }
}

/// Unit of a source column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Unit {
    /// Seconds.
    Second,
    /// Milliseconds.
    Millisecond,
    /// Microseconds.
    Microsecond,
    /// A count (sample index).
    Count,
    /// TSP/1 throttle level 0..10000.
    ThrottleLevel,
    /// Percent 0..100.
    Percent,
    /// ESC pulse width, µs (needs the ESC's min/max µs).
    PulseMicrosecond,
    /// Newton.
    Newton,
    /// Gram-force.
    GramForce,
    /// Kilogram-force.
    KilogramForce,
    /// Pound-force.
    PoundForce,
    /// Newton metre.
    NewtonMetre,
    /// Mechanical rev/min.
    Rpm,
    /// Electrical rev/min (needs the motor's pole count).
    ElectricalRpm,
    /// Volt.
    Volt,
    /// Ampere.
    Ampere,
}

/// A column's quantity and unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ColumnSpec {
    /// What it measures.
    pub quantity: Quantity,
    /// In which unit.
    pub unit: Unit,
}

/// Options some units need.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ConvOptions {
    /// ESC pulse width at zero throttle, µs (for `throttle_us`, `ESC signal (µs)`).
    pub esc_min_us: Option<f64>,
    /// ESC pulse width at full throttle, µs.
    pub esc_max_us: Option<f64>,
    /// Motor magnet poles (for `erpm`): mechanical rpm = erpm · 2 / poles.
    pub motor_poles: Option<u32>,
}

/// A unit that cannot be converted without an option.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ConvError {
    /// ESC min/max µs missing or not `min < max`.
    #[error("a throttle in µs needs the ESC's min and max pulse width (min < max)")]
    NeedsEscRange,
    /// Pole count missing or zero/odd.
    #[error("an electrical rpm needs the motor's pole count (even, > 0)")]
    NeedsPoles,
}

/// `canonical = (raw - zero) * mul / div`: an affine map written so that the common unit
/// changes (`/1000`, `/10000`, `/100`) are a single correctly rounded division, matching what
/// the binary path computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Affine {
    /// Raw value that maps to 0.
    pub zero: f64,
    /// Multiplier.
    pub mul: f64,
    /// Divisor.
    pub div: f64,
}

impl Affine {
    fn ratio(mul: f64, div: f64) -> Self {
        Self {
            zero: 0.0,
            mul,
            div,
        }
    }

    /// Apply to a raw value.
    pub fn apply(&self, raw: f64) -> f64 {
        (raw - self.zero) * self.mul / self.div
    }
}

impl ColumnSpec {
    /// The conversion of this column to canonical units.
    pub fn conversion(&self, o: &ConvOptions) -> Result<Affine, ConvError> {
        let r = |mul: f64, div: f64| Ok(Affine::ratio(mul, div));
        match self.unit {
            Unit::Second | Unit::Count | Unit::Newton | Unit::NewtonMetre | Unit::Rpm => {
                r(1.0, 1.0)
            }
            Unit::Volt | Unit::Ampere => r(1.0, 1.0),
            Unit::Millisecond => r(1.0, 1e3),
            Unit::Microsecond => r(1.0, 1e6),
            Unit::ThrottleLevel => r(1.0, 1e4),
            Unit::Percent => r(1.0, 1e2),
            Unit::GramForce => r(G0, 1e3),
            Unit::KilogramForce => r(G0, 1.0),
            Unit::PoundForce => r(LBF_N, 1.0),
            Unit::PulseMicrosecond => match (o.esc_min_us, o.esc_max_us) {
                (Some(lo), Some(hi)) if lo.is_finite() && hi.is_finite() && hi > lo => Ok(Affine {
                    zero: lo,
                    mul: 1.0,
                    div: hi - lo,
                }),
                _ => Err(ConvError::NeedsEscRange),
            },
            Unit::ElectricalRpm => match o.motor_poles {
                Some(p) if p > 0 && p % 2 == 0 => r(2.0, p as f64),
                _ => Err(ConvError::NeedsPoles),
            },
        }
    }
}

/// Normalise a header name for lookup (see the module documentation).
pub fn normalise(name: &str) -> String {
    let name = name.trim_start_matches('\u{feff}').trim();
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        match c {
            'µ' | 'μ' => out.push('u'),
            '[' => out.push('('),
            ']' => out.push(')'),
            ' ' | '\t' | '·' | '⋅' | '.' | '*' => {}
            c => out.extend(c.to_lowercase()),
        }
    }
    out
}

/// The alias table: normalised name → quantity and unit. The TSP/1 names of §6 first, then
/// the names of exported logs (RCbenchmark / Tyto Series 1580/1585, hobby benches).
const ALIASES: &[(&str, Quantity, Unit)] = {
    use Quantity as Q;
    use Unit as U;
    &[
        ("t_us", Q::Time, U::Microsecond),
        ("t_ms", Q::Time, U::Millisecond),
        ("t_s", Q::Time, U::Second),
        ("time(s)", Q::Time, U::Second),
        ("time(ms)", Q::Time, U::Millisecond),
        ("time(us)", Q::Time, U::Microsecond),
        ("time_s", Q::Time, U::Second),
        ("time_ms", Q::Time, U::Millisecond),
        ("time_us", Q::Time, U::Microsecond),
        ("idx", Q::Index, U::Count),
        ("index", Q::Index, U::Count),
        ("sample_index", Q::Index, U::Count),
        ("throttle", Q::Throttle, U::ThrottleLevel),
        ("throttle_pct", Q::Throttle, U::Percent),
        ("throttle(%)", Q::Throttle, U::Percent),
        ("throttle_us", Q::Throttle, U::PulseMicrosecond),
        ("throttle(us)", Q::Throttle, U::PulseMicrosecond),
        ("escsignal(us)", Q::Throttle, U::PulseMicrosecond),
        ("esc(us)", Q::Throttle, U::PulseMicrosecond),
        ("pwm(us)", Q::Throttle, U::PulseMicrosecond),
        ("thrust_n", Q::Thrust, U::Newton),
        ("thrust_g", Q::Thrust, U::GramForce),
        ("thrust_gf", Q::Thrust, U::GramForce),
        ("thrust_kgf", Q::Thrust, U::KilogramForce),
        ("thrust(n)", Q::Thrust, U::Newton),
        ("thrust(g)", Q::Thrust, U::GramForce),
        ("thrust(gf)", Q::Thrust, U::GramForce),
        ("thrust(kg)", Q::Thrust, U::KilogramForce),
        ("thrust(kgf)", Q::Thrust, U::KilogramForce),
        ("thrust(lbf)", Q::Thrust, U::PoundForce),
        ("weight(g)", Q::Thrust, U::GramForce),
        ("torque_nm", Q::Torque, U::NewtonMetre),
        ("torque(nm)", Q::Torque, U::NewtonMetre),
        ("rpm", Q::Rpm, U::Rpm),
        ("erpm", Q::Rpm, U::ElectricalRpm),
        ("rpm(rpm)", Q::Rpm, U::Rpm),
        ("speed(rpm)", Q::Rpm, U::Rpm),
        ("motorspeed(rpm)", Q::Rpm, U::Rpm),
        ("motoropticalspeed(rpm)", Q::Rpm, U::Rpm),
        // RCbenchmark's "electrical" speed is the commutation frequency already divided by
        // the pole pairs configured in its app: a mechanical rpm (it equals the optical speed
        // in the exports we have).
        ("motorelectricalspeed(rpm)", Q::Rpm, U::Rpm),
        ("voltage_v", Q::Voltage, U::Volt),
        ("voltage(v)", Q::Voltage, U::Volt),
        ("vbat(v)", Q::Voltage, U::Volt),
        ("current_a", Q::Current, U::Ampere),
        ("current(a)", Q::Current, U::Ampere),
    ]
};

/// Look a header name up in the alias table (after [`normalise`]).
pub fn lookup(name: &str) -> Option<ColumnSpec> {
    let n = normalise(name);
    ALIASES
        .iter()
        .find(|(a, _, _)| *a == n)
        .map(|&(_, quantity, unit)| ColumnSpec { quantity, unit })
}

/// The column order of a header-less TSP/1 CSV stream:
/// `t_us,throttle,thrust_N[,torque_Nm,rpm,voltage_V,current_A]`.
pub const DEFAULT_ORDER: [ColumnSpec; 7] = [
    ColumnSpec {
        quantity: Quantity::Time,
        unit: Unit::Microsecond,
    },
    ColumnSpec {
        quantity: Quantity::Throttle,
        unit: Unit::ThrottleLevel,
    },
    ColumnSpec {
        quantity: Quantity::Thrust,
        unit: Unit::Newton,
    },
    ColumnSpec {
        quantity: Quantity::Torque,
        unit: Unit::NewtonMetre,
    },
    ColumnSpec {
        quantity: Quantity::Rpm,
        unit: Unit::Rpm,
    },
    ColumnSpec {
        quantity: Quantity::Voltage,
        unit: Unit::Volt,
    },
    ColumnSpec {
        quantity: Quantity::Current,
        unit: Unit::Ampere,
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exported_log_names_map_to_quantities() {
        let cases = [
            ("\u{feff}Time (s)", Quantity::Time, Unit::Second),
            (
                "ESC signal (µs)",
                Quantity::Throttle,
                Unit::PulseMicrosecond,
            ),
            ("Thrust (N)", Quantity::Thrust, Unit::Newton),
            ("Thrust (gf)", Quantity::Thrust, Unit::GramForce),
            ("Thrust (kgf)", Quantity::Thrust, Unit::KilogramForce),
            ("Torque (N·m)", Quantity::Torque, Unit::NewtonMetre),
            ("Voltage (V)", Quantity::Voltage, Unit::Volt),
            ("Current (A)", Quantity::Current, Unit::Ampere),
            ("Motor Electrical Speed (RPM)", Quantity::Rpm, Unit::Rpm),
            ("weight[g]", Quantity::Thrust, Unit::GramForce),
            ("thrust_N", Quantity::Thrust, Unit::Newton),
            ("erpm", Quantity::Rpm, Unit::ElectricalRpm),
            ("throttle_pct", Quantity::Throttle, Unit::Percent),
        ];
        for (name, q, u) in cases {
            assert_eq!(
                lookup(name),
                Some(ColumnSpec {
                    quantity: q,
                    unit: u
                }),
                "{name}"
            );
        }
        assert_eq!(lookup("AccX (g)"), None);
        assert_eq!(lookup("Servo 1 (µs)"), None);
    }

    #[test]
    fn conversions_to_canonical_units() {
        let o = ConvOptions {
            esc_min_us: Some(1000.0),
            esc_max_us: Some(2000.0),
            motor_poles: Some(14),
        };
        let conv = |name: &str, raw: f64| lookup(name).unwrap().conversion(&o).unwrap().apply(raw);
        assert!((conv("ESC signal (µs)", 1500.0) - 0.5).abs() < 1e-12);
        assert!((conv("Thrust (gf)", 1000.0) - G0).abs() < 1e-12);
        assert!((conv("thrust_kgf", 1.0) - G0).abs() < 1e-12);
        assert!((conv("erpm", 7000.0) - 1000.0).abs() < 1e-9);
        assert!((conv("t_us", 2_500_000.0) - 2.5).abs() < 1e-12);
        assert!((conv("throttle", 3500.0) - 0.35).abs() < 1e-12);
        let none = ConvOptions::default();
        let us = lookup("throttle_us").unwrap();
        assert_eq!(us.conversion(&none), Err(ConvError::NeedsEscRange));
        let e = lookup("erpm").unwrap();
        assert_eq!(e.conversion(&none), Err(ConvError::NeedsPoles));
    }
}
