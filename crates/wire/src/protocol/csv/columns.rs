//! CSV column names → canonical quantities and units (docs/PROTOCOL.md §6), shared by the live
//! CSV decoder and by file readers (exported logs of commercial stands): the one alias table,
//! the one unit table and the one quantity → name table ([`Quantity::name`]) of the project.
//!
//! A header name is normalised before lookup (see [`normalise`]): a UTF-8 BOM and surrounding
//! space are dropped, letters lower-cased, `µ`/`μ` written `u`, `[`/`]` written `(`/`)`, and
//! spaces, `·`, `⋅`, `.`, `*` removed. `Torque (N·m)`, `torque(nm)` and `TORQUE [N.m]` all become
//! `torque(nm)`. [`lookup`] then finds the name in the table of whole names ([`NAMES`]: the §6
//! names without a unit suffix and command names without a unit), else splits it into a
//! quantity word and a unit suffix, `word(unit)`, `word_unit` or `word / unit`, and looks both
//! up ([`WORDS`], [`UNITS`]): `Thrust (gf)`, `thrust_lbf`, `Torque (N·mm)`, `Motor Speed
//! (rad/s)`, `Thrust / N`. A qualifier may precede the word (`Battery Voltage (V)`, `Motor
//! RPM`), unless it makes the column no reading (`Target RPM`, `Max Current (A)`). Words joined
//! by `_` where a header has a space read as one (`load_cell_N`); a command with a qualifier
//! and no unit (`Motor Command`, `motor_cmd`) is a command whose scale its values decide;
//! German benches' words are known (`Zeit`, `Gas`, `Schub`, `Drehzahl`, ...). Of single
//! letters only `t` (time) and `F` (force, the load cell's) are read, with a unit.
//!
//! The conversion to canonical units (throttle fraction, s, N, N·m, rev/min, V, A) is affine,
//! `canonical = (raw - zero) * mul / div`; some units need options ([`ConvOptions`]). A
//! command's full scale is not always in its unit: [`Unit::command_scales`] says which scales
//! a command column may have (declared by its header's unit, or to be decided from its values
//! by a file reader, which alone sees them all).

use crate::record::names;

/// Standard gravity, m/s² (for gram-force and kilogram-force).
pub const G0: f64 = 9.80665;
/// One pound-force in newtons.
pub const LBF_N: f64 = 4.448_221_615_260_5;
/// One ounce-force inch in newton metres.
pub const OZF_IN_NM: f64 = LBF_N / 16.0 * 0.0254;

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

    /// A short key for reports (`source.units` of identify): `time`, `index`, `throttle`,
    /// `thrust`, `torque`, `rpm`, `voltage`, `current`.
    pub fn key(self) -> &'static str {
        match self {
            Quantity::Time => "time",
            Quantity::Index => "index",
            Quantity::Throttle => "throttle",
            Quantity::Thrust => "thrust",
            Quantity::Torque => "torque",
            Quantity::Rpm => "rpm",
            Quantity::Voltage => "voltage",
            Quantity::Current => "current",
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
    /// Minutes.
    Minute,
    /// A time-of-day or date-time stamp (`18:55:23.120`, `2024-08-13 18:55:23.120`), read as
    /// seconds ([`parse_clock`](super::line::parse_clock)).
    Clock,
    /// A count (sample index).
    Count,
    /// The §6 name `throttle`: TSP/1 level 0..10000 on the wire; in an exported file its scale
    /// is decided from its values ([`Unit::command_scales`]).
    ThrottleLevel,
    /// Percent 0..100.
    Percent,
    /// Fraction 0..1.
    Fraction,
    /// ESC pulse width, µs (needs the ESC's min/max µs).
    PulseMicrosecond,
    /// DShot throttle value, 48..2047 (0 stops the motor).
    DShot,
    /// A command without a unit (`ESC signal`, `pwm`, `cmd`): its scale comes from an option
    /// or, in a file, from its values.
    Command,
    /// Newton.
    Newton,
    /// Millinewton.
    Millinewton,
    /// Gram-force.
    GramForce,
    /// Kilogram-force.
    KilogramForce,
    /// Pound-force.
    PoundForce,
    /// Ounce-force (1/16 lbf).
    OunceForce,
    /// Newton metre.
    NewtonMetre,
    /// Newton millimetre.
    NewtonMillimetre,
    /// Newton centimetre.
    NewtonCentimetre,
    /// Millinewton metre.
    MillinewtonMetre,
    /// Kilogram-force centimetre (a common torque unit of small stands' exports).
    KilogramForceCentimetre,
    /// Gram-force centimetre.
    GramForceCentimetre,
    /// Ounce-force inch.
    OunceForceInch,
    /// Pound-force inch.
    PoundForceInch,
    /// Pound-force foot.
    PoundForceFoot,
    /// Mechanical rev/min.
    Rpm,
    /// Thousands of mechanical rev/min.
    KiloRpm,
    /// Electrical rev/min (needs the motor's pole count).
    ElectricalRpm,
    /// Radian per second.
    RadianPerSecond,
    /// Revolutions per second.
    Hertz,
    /// Volt.
    Volt,
    /// Millivolt.
    Millivolt,
    /// Ampere.
    Ampere,
    /// Milliampere.
    Milliampere,
}

impl Unit {
    /// The unit as a person writes it (for reports, e.g. identify's `source.units`).
    pub fn symbol(self) -> &'static str {
        match self {
            Unit::Second => "s",
            Unit::Millisecond => "ms",
            Unit::Minute => "min",
            Unit::Clock => "date-time",
            Unit::Microsecond | Unit::PulseMicrosecond => "µs",
            Unit::Count => "1",
            Unit::ThrottleLevel => "TSP/1 level",
            Unit::Percent => "%",
            Unit::Fraction => "0..1",
            Unit::DShot => "DShot",
            Unit::Command => "none",
            Unit::Newton => "N",
            Unit::Millinewton => "mN",
            Unit::GramForce => "gf",
            Unit::KilogramForce => "kgf",
            Unit::PoundForce => "lbf",
            Unit::OunceForce => "ozf",
            Unit::NewtonMetre => "N·m",
            Unit::NewtonMillimetre => "N·mm",
            Unit::NewtonCentimetre => "N·cm",
            Unit::MillinewtonMetre => "mN·m",
            Unit::KilogramForceCentimetre => "kgf·cm",
            Unit::GramForceCentimetre => "gf·cm",
            Unit::OunceForceInch => "ozf·in",
            Unit::PoundForceInch => "lbf·in",
            Unit::PoundForceFoot => "lbf·ft",
            Unit::Rpm => "RPM",
            Unit::KiloRpm => "kRPM",
            Unit::ElectricalRpm => "eRPM",
            Unit::RadianPerSecond => "rad/s",
            Unit::Hertz => "Hz",
            Unit::Volt => "V",
            Unit::Millivolt => "mV",
            Unit::Ampere => "A",
            Unit::Milliampere => "mA",
        }
    }
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
    /// A command without a unit: its scale is not known.
    #[error("a command without a unit needs its range (min and max)")]
    NeedsRange,
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
    /// The identity (a column without a known unit).
    pub const IDENTITY: Affine = Affine::ratio(1.0, 1.0);

    const fn ratio(mul: f64, div: f64) -> Self {
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

    /// Canonical units per raw unit (`mul / div`).
    pub fn factor(&self) -> f64 {
        self.mul / self.div
    }
}

impl ColumnSpec {
    /// The conversion of this column to canonical units.
    pub fn conversion(&self, o: &ConvOptions) -> Result<Affine, ConvError> {
        let r = |mul: f64, div: f64| Ok(Affine::ratio(mul, div));
        match self.unit {
            Unit::Second
            | Unit::Clock
            | Unit::Count
            | Unit::Newton
            | Unit::NewtonMetre
            | Unit::Rpm => r(1.0, 1.0),
            Unit::Volt | Unit::Ampere | Unit::Fraction => r(1.0, 1.0),
            Unit::Millisecond
            | Unit::NewtonMillimetre
            | Unit::Millivolt
            | Unit::Milliampere
            | Unit::Millinewton
            | Unit::MillinewtonMetre => r(1.0, 1e3),
            Unit::NewtonCentimetre => r(1.0, 1e2),
            Unit::KilogramForceCentimetre => r(G0, 1e2),
            Unit::GramForceCentimetre => r(G0, 1e5),
            Unit::KiloRpm => r(1e3, 1.0),
            Unit::Microsecond => r(1.0, 1e6),
            Unit::Minute => r(60.0, 1.0),
            Unit::ThrottleLevel => r(1.0, 1e4),
            Unit::Percent => r(1.0, 1e2),
            Unit::GramForce => r(G0, 1e3),
            Unit::KilogramForce => r(G0, 1.0),
            Unit::PoundForce => r(LBF_N, 1.0),
            Unit::OunceForce => r(LBF_N, 16.0),
            Unit::OunceForceInch => r(OZF_IN_NM, 1.0),
            Unit::PoundForceInch => r(LBF_N * 0.0254, 1.0),
            Unit::PoundForceFoot => r(LBF_N * 0.3048, 1.0),
            Unit::RadianPerSecond => r(60.0, std::f64::consts::TAU),
            Unit::Hertz => r(60.0, 1.0),
            Unit::DShot => Ok(Scale::DSHOT.affine()),
            Unit::Command => Err(ConvError::NeedsRange),
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
            ' ' | '\t' | '·' | '⋅' | '•' | '∙' | '.' | '*' => {}
            c => out.extend(c.to_lowercase()),
        }
    }
    out
}

use Quantity as Q;
use Unit as U;

/// Whole names (normalised): §6 names without a unit suffix, and command names without a unit.
/// `throttle` is §6's 0..10000 on the wire; in a file, like `ESC signal` or `pwm`, its scale is
/// decided from its values ([`Unit::command_scales`]).
pub const NAMES: &[(&str, Quantity, Unit)] = &[
    ("idx", Q::Index, U::Count),
    ("index", Q::Index, U::Count),
    ("sample_index", Q::Index, U::Count),
    ("timestamp", Q::Time, U::Clock),
    ("datetime", Q::Time, U::Clock),
    ("date/time", Q::Time, U::Clock),
    ("date_time", Q::Time, U::Clock),
    ("clock", Q::Time, U::Clock),
    // An Arduino's clock functions, the usual names of a hobby logger's time column.
    ("millis", Q::Time, U::Millisecond),
    ("micros", Q::Time, U::Microsecond),
    // A time column named by its unit alone.
    ("sec", Q::Time, U::Second),
    ("secs", Q::Time, U::Second),
    ("seconds", Q::Time, U::Second),
    ("ms", Q::Time, U::Millisecond),
    ("msec", Q::Time, U::Millisecond),
    // Seconds since 1970 (a logger's `time.time()`, a spreadsheet's Unix stamp).
    ("unix_time", Q::Time, U::Second),
    ("unixtime", Q::Time, U::Second),
    ("unix_timestamp", Q::Time, U::Second),
    ("epoch", Q::Time, U::Second),
    ("epoch_time", Q::Time, U::Second),
    ("throttle", Q::Throttle, U::ThrottleLevel),
    ("escsignal", Q::Throttle, U::Command),
    ("esc", Q::Throttle, U::Command),
    ("pwm", Q::Throttle, U::Command),
    ("cmd", Q::Throttle, U::Command),
    ("command", Q::Throttle, U::Command),
    ("dshot", Q::Throttle, U::DShot),
    ("signal", Q::Throttle, U::Command),
    ("duty", Q::Throttle, U::Command),
    ("dutycycle", Q::Throttle, U::Command),
    ("rpm", Q::Rpm, U::Rpm),
    ("erpm", Q::Rpm, U::ElectricalRpm),
    ("krpm", Q::Rpm, U::KiloRpm),
    // Hobby loggers' supply columns, named by their unit.
    ("volts", Q::Voltage, U::Volt),
    ("amps", Q::Current, U::Ampere),
    // A hobby load cell's column named by its unit (an HX711 sketch's `grams`).
    ("grams", Q::Thrust, U::GramForce),
    ("newtons", Q::Thrust, U::Newton),
];

/// Quantity words of `word(unit)` / `word_unit` names (§6, RCbenchmark / Tyto Series
/// 1580/1585 exports, hobby benches).
pub const WORDS: &[(&str, Quantity)] = &[
    ("t", Q::Time),
    ("time", Q::Time),
    ("throttle", Q::Throttle),
    ("escsignal", Q::Throttle),
    ("esc", Q::Throttle),
    ("pwm", Q::Throttle),
    ("cmd", Q::Throttle),
    ("command", Q::Throttle),
    // A generic command's names (`Signal (µs)`, `Input (%)`, `Duty cycle (%)`).
    ("signal", Q::Throttle),
    ("input", Q::Throttle),
    ("duty", Q::Throttle),
    ("dutycycle", Q::Throttle),
    ("thrust", Q::Thrust),
    ("weight", Q::Thrust),
    // Small stands' names for the load cell's reading (`Pull (kg)`, `Lift (g)`).
    ("pull", Q::Thrust),
    ("lift", Q::Thrust),
    // The load cell's force (`Force (N)`): a thrust stand measures one (a multi-axis
    // `Force X (N)` is not this word).
    ("force", Q::Thrust),
    // Its symbol, with a force unit (`F / N`, `F (gf)`; an axis's `Fz (N)` is not this word).
    ("f", Q::Thrust),
    // A load cell's reading named as such (`Load (g)`, `Load cell (kg)`, `loadcell_N`): only
    // with a force unit (a `Load (%)` is not a thrust).
    ("load", Q::Thrust),
    ("loadcell", Q::Thrust),
    ("torque", Q::Torque),
    ("rpm", Q::Rpm),
    ("speed", Q::Rpm),
    ("motorspeed", Q::Rpm),
    ("motoropticalspeed", Q::Rpm),
    // RCbenchmark's "electrical" speed in RPM is the commutation frequency already divided by
    // the pole pairs configured in its app: a mechanical rpm (it equals the optical speed in
    // the exports we have). `(eRPM)` would say otherwise.
    ("motorelectricalspeed", Q::Rpm),
    ("omega", Q::Rpm),
    ("angularvelocity", Q::Rpm),
    ("elapsed", Q::Time),
    ("timestamp", Q::Time),
    ("epoch", Q::Time),
    ("voltage", Q::Voltage),
    ("vbat", Q::Voltage),
    ("battery", Q::Voltage),
    // Betaflight blackbox CSV (`vbatLatest (V)`, `amperageLatest (A)`).
    ("vbatlatest", Q::Voltage),
    ("current", Q::Current),
    ("amperagelatest", Q::Current),
    // German benches' names (`Zeit [s]`, `Gas [%]`, `Schub [g]`, `Drehzahl [1/min]`).
    ("zeit", Q::Time),
    ("gas", Q::Throttle),
    ("schub", Q::Thrust),
    ("kraft", Q::Thrust),
    ("drehmoment", Q::Torque),
    ("drehzahl", Q::Rpm),
    ("spannung", Q::Voltage),
    ("strom", Q::Current),
];

/// The unit table: a unit suffix (normalised) of a quantity → its unit.
pub const UNITS: &[(&str, Quantity, Unit)] = &[
    ("s", Q::Time, U::Second),
    ("sec", Q::Time, U::Second),
    ("ms", Q::Time, U::Millisecond),
    ("us", Q::Time, U::Microsecond),
    ("min", Q::Time, U::Minute),
    ("secs", Q::Time, U::Second),
    ("seconds", Q::Time, U::Second),
    ("msec", Q::Time, U::Millisecond),
    ("usec", Q::Time, U::Microsecond),
    ("%", Q::Throttle, U::Percent),
    ("pct", Q::Throttle, U::Percent),
    ("us", Q::Throttle, U::PulseMicrosecond),
    ("0-1", Q::Throttle, U::Fraction),
    ("frac", Q::Throttle, U::Fraction),
    ("dshot", Q::Throttle, U::DShot),
    ("0-100", Q::Throttle, U::Percent),
    // A dimensionless command (`Throttle (1)`, `cmd [-]`: see [`lookup`], `ESC (raw)`): its
    // scale is decided from its values.
    ("1", Q::Throttle, U::Command),
    ("raw", Q::Throttle, U::Command),
    ("n", Q::Thrust, U::Newton),
    ("mn", Q::Thrust, U::Millinewton),
    ("g", Q::Thrust, U::GramForce),
    ("gf", Q::Thrust, U::GramForce),
    ("kg", Q::Thrust, U::KilogramForce),
    ("kgf", Q::Thrust, U::KilogramForce),
    ("lb", Q::Thrust, U::PoundForce),
    ("lbf", Q::Thrust, U::PoundForce),
    ("oz", Q::Thrust, U::OunceForce),
    ("ozf", Q::Thrust, U::OunceForce),
    ("newton", Q::Thrust, U::Newton),
    ("newtons", Q::Thrust, U::Newton),
    ("grams", Q::Thrust, U::GramForce),
    ("gram", Q::Thrust, U::GramForce),
    ("lbs", Q::Thrust, U::PoundForce),
    ("nm", Q::Torque, U::NewtonMetre),
    ("n-m", Q::Torque, U::NewtonMetre),
    ("nmm", Q::Torque, U::NewtonMillimetre),
    ("n-mm", Q::Torque, U::NewtonMillimetre),
    ("ncm", Q::Torque, U::NewtonCentimetre),
    ("n-cm", Q::Torque, U::NewtonCentimetre),
    ("mnm", Q::Torque, U::MillinewtonMetre),
    ("mn-m", Q::Torque, U::MillinewtonMetre),
    ("kgfcm", Q::Torque, U::KilogramForceCentimetre),
    ("kgf-cm", Q::Torque, U::KilogramForceCentimetre),
    ("kgcm", Q::Torque, U::KilogramForceCentimetre),
    ("kg-cm", Q::Torque, U::KilogramForceCentimetre),
    ("gfcm", Q::Torque, U::GramForceCentimetre),
    ("gf-cm", Q::Torque, U::GramForceCentimetre),
    ("gcm", Q::Torque, U::GramForceCentimetre),
    ("g-cm", Q::Torque, U::GramForceCentimetre),
    ("ozfin", Q::Torque, U::OunceForceInch),
    ("ozf-in", Q::Torque, U::OunceForceInch),
    ("ozin", Q::Torque, U::OunceForceInch),
    ("oz-in", Q::Torque, U::OunceForceInch),
    ("inoz", Q::Torque, U::OunceForceInch),
    ("in-oz", Q::Torque, U::OunceForceInch),
    ("in-ozf", Q::Torque, U::OunceForceInch),
    ("lbfin", Q::Torque, U::PoundForceInch),
    ("lbf-in", Q::Torque, U::PoundForceInch),
    ("lbfft", Q::Torque, U::PoundForceFoot),
    ("lbf-ft", Q::Torque, U::PoundForceFoot),
    ("rpm", Q::Rpm, U::Rpm),
    ("krpm", Q::Rpm, U::KiloRpm),
    ("erpm", Q::Rpm, U::ElectricalRpm),
    ("r/min", Q::Rpm, U::Rpm),
    ("rev/min", Q::Rpm, U::Rpm),
    ("1/min", Q::Rpm, U::Rpm),
    ("rad/s", Q::Rpm, U::RadianPerSecond),
    ("rad/sec", Q::Rpm, U::RadianPerSecond),
    ("hz", Q::Rpm, U::Hertz),
    ("rps", Q::Rpm, U::Hertz),
    ("rev/s", Q::Rpm, U::Hertz),
    ("v", Q::Voltage, U::Volt),
    ("volt", Q::Voltage, U::Volt),
    ("volts", Q::Voltage, U::Volt),
    ("mv", Q::Voltage, U::Millivolt),
    ("a", Q::Current, U::Ampere),
    ("amp", Q::Current, U::Ampere),
    ("amps", Q::Current, U::Ampere),
    ("ma", Q::Current, U::Milliampere),
];

/// Look a header name up (after [`normalise`]): a whole name ([`NAMES`]), else `word(unit)`,
/// `word"unit"` (a unit in double quotes: the RFC 4180 header `"Thrust ""gf"""` is
/// `Thrust "gf"`) or `word_unit` ([`WORDS`] and [`UNITS`]), else a whole name with a
/// qualifier ([`qualified_name`]: `Motor RPM`, `RPM (optical)`).
pub fn lookup(name: &str) -> Option<ColumnSpec> {
    let n = normalise(name);
    let whole = |n: &str| {
        NAMES
            .iter()
            .find(|(a, _, _)| *a == n)
            .map(|&(_, quantity, unit)| ColumnSpec { quantity, unit })
    };
    if let Some(spec) = whole(&n) {
        return Some(spec);
    }
    let with_unit = word_and_unit(&n).and_then(|(word, suffix)| {
        let quantity = quantity_of_word(word)?;
        // `[-]`, an engineer's "dimensionless" (not in the unit table: a `-` cell of a units
        // row is an empty one).
        let suffix = if suffix == "-" { "1" } else { suffix };
        let in_unit = |quantity| {
            UNITS
                .iter()
                .find(|(s, q, _)| *s == suffix && *q == quantity)
                .map(|&(_, _, unit)| ColumnSpec { quantity, unit })
        };
        // `T` is a thrust's symbol as well as a time's (`T (N)`, `T_g`): its unit tells them
        // apart (normalised, both are `t`).
        in_unit(quantity).or_else(|| (word == "t").then(|| in_unit(Quantity::Thrust)).flatten())
    });
    with_unit
        .or_else(|| qualified_name(&n).and_then(whole))
        .or_else(|| qualified_command(&n))
}

/// A command named with a qualifier and no unit (`Motor Command`, `motor_cmd`, `esc_pwm`): a
/// command's scale is decided from its values ([`Unit::Command`]), so no unit is guessed.
/// Other quantities without a unit are [`unitless`], never read.
fn qualified_command(n: &str) -> Option<ColumnSpec> {
    (quantity_of_word(n)? == Quantity::Throttle).then_some(ColumnSpec {
        quantity: Quantity::Throttle,
        unit: Unit::Command,
    })
}

/// The whole name ([`NAMES`]) a qualified name stands for: a unit-named speed after a
/// qualifier (`Motor RPM`, `motor_erpm`, `ESC eRPM`), or a whole name followed by a qualifier
/// that is no unit (`RPM (optical)`, `ESC signal (motor)`). A qualifier that makes it no
/// reading (`Target RPM`: [`NOT_A_READING`]) is none, and so is a name whose spaces were the
/// only clue: `Blade RPM` would read as `blad` + `eRPM`, so a qualifier ending in `e` or `k`
/// before `rpm` is not guessed.
fn qualified_name(n: &str) -> Option<&'static str> {
    if let Some((word, qualifier)) = word_and_unit(n) {
        if !is_unit(qualifier) && qualifier.chars().all(|c| c.is_alphanumeric() || c == '_') {
            return NAMES.iter().map(|e| e.0).find(|&a| a == word);
        }
    }
    const SPEED_OWNERS: [&str; 5] = ["motor", "esc", "rotor", "prop", "shaft"];
    ["erpm", "krpm", "rpm"].into_iter().find(|&w| {
        let Some(p) = n.strip_suffix(w) else {
            return false;
        };
        let q = p.trim_end_matches('_');
        // A motor's index after the owner (`Motor 1 RPM`, `esc2_erpm`).
        let owner = q
            .trim_end_matches(|c: char| c.is_ascii_digit())
            .trim_end_matches('_');
        if owner.len() < q.len() && SPEED_OWNERS.contains(&owner) {
            return true;
        }
        let told_apart = p.ends_with('_')
            || SPEED_OWNERS.contains(&q)
            || (w == "rpm" && !q.ends_with(['e', 'k']));
        is_qualifier(q) && told_apart && !no_reading(q)
    })
}

/// Quantity words that a qualifier may precede (`Motor Thrust`, `Battery Voltage`, `Rotor
/// Speed`, `Elapsed Time`, `ESC Throttle`). A load cell's generic words are not among them:
/// only a bare `Force` is the stand's load cell; a `Drag Force`, a `Side Force` or a
/// benchmark's `vir_force` (a motor's force command) is not its thrust.
const QUALIFIABLE: &[&str] = &[
    "time", "throttle", "command", "cmd", "signal", "input", "pwm", "thrust", "torque", "speed",
    "voltage", "current",
];

/// Qualifiers that make a column no reading of its quantity: a set-point (`Target Speed`), a
/// limit (`Max Current`), a figure computed from the readings (`Rise Time`, `Thrust Error`).
/// They do not apply to the command, whose set-point it is (`Target Throttle`).
const NOT_A_READING: &[&str] = &[
    "target", "setpoint", "desired", "demand", "ref", "cmd", "command", "max", "min", "limit",
    "offset", "error", "rise", "settl", "dwell", "delay", "dead", "loop",
];

/// True when qualifier `p` starts or ends with a word of [`NOT_A_READING`] (`Max Current`,
/// `Motor target speed`); a word inside another is no such word (`Terminal Voltage` holds
/// `min`).
fn no_reading(p: &str) -> bool {
    let p = p.trim_matches('_');
    NOT_A_READING
        .iter()
        .any(|m| p.starts_with(m) || p.ends_with(m))
}

/// True for a qualifier before a quantity word: letters (and `_`) only, not empty.
fn is_qualifier(p: &str) -> bool {
    !p.is_empty() && p.chars().all(|c| c.is_alphabetic() || c == '_')
}

/// A normalised name split into its word and its unit suffix: `word(unit)`, `word"unit"`,
/// `word_unit` or `word/unit` (the quantity-over-unit of a table's column, `t / s`, `F / N`,
/// `omega / rad/s`: only where what follows the first `/` is a unit of the unit table).
fn word_and_unit(n: &str) -> Option<(&str, &str)> {
    let enclosed = |open: char, close: char| n.strip_suffix(close)?.split_once(open);
    enclosed('(', ')')
        .or_else(|| enclosed('"', '"'))
        .or_else(|| n.rsplit_once('_'))
        .or_else(|| {
            n.split_once('/')
                .filter(|(_, u)| UNITS.iter().any(|(s, _, _)| s == u))
        })
}

/// The quantity of a name's word ([`WORDS`]), also with a motor's or a sensor's index around
/// it (`Motor 1 Thrust (N)`, `m2_thrust_g`, `ESC 1 (µs)`, `Thrust 2 (N)`: [`sensor_word`]) or a
/// qualifier before it (`Motor Thrust (N)`, `Battery Voltage (V)`, `Rotor Speed (rad/s)`:
/// [`QUALIFIABLE`], [`NOT_A_READING`]).
fn quantity_of_word(word: &str) -> Option<Quantity> {
    let of = |w: &str| WORDS.iter().find(|(x, _)| *x == w).map(|&(_, q)| q);
    let qualified = |w: &str| {
        QUALIFIABLE.iter().find_map(|&q| {
            let p = w.strip_suffix(q)?.trim_end_matches('_');
            let quantity = of(q)?;
            let a_reading = quantity == Quantity::Throttle || !no_reading(p);
            (is_qualifier(p) && a_reading).then_some(quantity)
        })
    };
    // A command's word followed by a set-point's (`throttle_setpoint`, `ESC command`, `pwm
    // cmd`): the command itself.
    let set_point = |w: &str| {
        SET_POINT_WORDS.iter().find_map(|&sp| {
            let q = of(w.strip_suffix(sp)?.trim_end_matches('_'))?;
            (q == Quantity::Throttle).then_some(q)
        })
    };
    of(word)
        .or_else(|| of(strip_index(word)?))
        .or_else(|| qualified(word))
        .or_else(|| qualified(strip_index(word)?))
        .or_else(|| set_point(word))
        // Words joined by `_` where a header would have a space (`load_cell_N`, `motor_speed`).
        .or_else(|| of(&word.replace('_', "")))
}

/// Words that name a set-point after a command's word (`Throttle setpoint (%)`).
const SET_POINT_WORDS: &[&str] = &["setpoint", "command", "cmd", "target", "demand", "ref"];

/// `word` without a motor's or a sensor's index (`motor1thrust`, `m1_thrust`, `esc2`,
/// `thrust_3` → `thrust`, `thrust`, `esc`, `thrust`); `None` when it has none.
fn strip_index(word: &str) -> Option<&str> {
    let digits = |s: &str| s.len() - s.trim_start_matches(|c: char| c.is_ascii_digit()).len();
    for prefix in ["motor", "m", "esc"] {
        if let Some(rest) = word.strip_prefix(prefix) {
            let d = digits(rest);
            if d > 0 {
                let rest = &rest[d..];
                let rest = rest.strip_prefix('_').unwrap_or(rest);
                if !rest.is_empty() {
                    return Some(rest);
                }
            }
        }
    }
    let base = word.trim_end_matches(|c: char| c.is_ascii_digit());
    (base.len() < word.len() && !base.is_empty()).then(|| base.strip_suffix('_').unwrap_or(base))
}

/// The sensor a column names: its normalised name without the unit (`Thrust (gf)` and
/// `Thrust (N)` name one sensor, `Motor 1 Thrust (N)` and `Motor 2 Thrust (N)` two).
pub fn sensor_word(name: &str) -> String {
    let n = normalise(name);
    match word_and_unit(&n) {
        Some((word, suffix)) if UNITS.iter().any(|(s, _, _)| *s == suffix) => word.to_string(),
        _ => n,
    }
}

/// True when two columns are one kind of sensor told apart by an index only (`Motor 1 Thrust
/// (N)` and `Motor 2 Thrust (N)`, `m1_thrust_g` and `m2_thrust_g`: a load cell per motor). A
/// reader picking a column by its quantity refuses to choose between them.
pub fn indexed_alike(a: &str, b: &str) -> bool {
    let (wa, wb) = (sensor_word(a), sensor_word(b));
    let base = |w: &str| strip_index(w).map(str::to_string);
    wa != wb && base(&wa).is_some() && base(&wa) == base(&wb)
}

/// A header name that is a quantity word without a unit (`Thrust`, `Torque`, `Current`; not a
/// whole name of [`NAMES`] such as `rpm`, whose unit is its name): the quantity whose unit the
/// file does not say. A reader must not guess it (newtons or gram-force?).
pub fn unitless(name: &str) -> Option<Quantity> {
    if lookup(name).is_some() {
        return None;
    }
    quantity_of_word(&normalise(name))
}

/// The units a quantity's column may be written in (the suffixes of [`UNITS`] as a person
/// writes them: `N, gf, kgf, lbf, ozf` for thrust), for messages.
pub fn units_of(q: Quantity) -> String {
    let mut out: Vec<&str> = Vec::new();
    for &(_, uq, u) in UNITS {
        if uq == q && !out.contains(&u.symbol()) {
            out.push(u.symbol());
        }
    }
    out.join(", ")
}

/// True when `text` is a unit of the unit table (`s`, `%`, `gf`, `N·mm`, `[rad/s]`): a cell of a
/// units row written under a header.
pub fn is_unit(text: &str) -> bool {
    let n = normalise(text);
    let n = n
        .strip_prefix('(')
        .and_then(|n| n.strip_suffix(')'))
        .unwrap_or(&n);
    UNITS.iter().any(|(u, _, _)| *u == n)
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

mod scale;
pub use scale::{CommandScales, Scale};

#[cfg(test)]
mod tests;
