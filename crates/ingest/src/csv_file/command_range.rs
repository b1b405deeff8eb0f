//! The full scale of a file's command column: which raw value is throttle 0 and which is
//! throttle 1, decided from the options, the header's unit and the values, and always stated
//! ([`CommandRange::from`]), never guessed in silence.
//!
//! The rule, first that applies:
//! 1. `--input-range MIN,MAX` is the scale (`"--input-range"`), also of an input column the
//!    unit table does not know as a command (`--input u`).
//! 2. `--esc-us MIN,MAX` is the scale of a column in µs or without a unit (`"--esc-us"`).
//! 3. A header that declares the unit (`ESC signal (µs)`, `throttle (%)`, `throttle (0-1)`,
//!    `dshot`: [`CommandScales::Declared`]) gives the scale (`"header: µs"`); the values must
//!    lie in it (within [`TOLERANCE`] of its span), else the file is refused with the option to
//!    give (`--esc-us` for µs: an ESC calibrated to 1100..1900 µs is common). Values that are
//!    all fractions within 0..1 under a wider declared scale (`Throttle (%)` holding 0.40,
//!    0.45) are refused naming `--input-range 0,1`: under a hundredth of full throttle spins
//!    no propeller, but the file cannot say which the exporter meant.
//! 4. Otherwise (`throttle`, `ESC signal`, `pwm`, `cmd` without a unit:
//!    [`CommandScales::FromValues`]) the values decide among the candidate scales of the unit
//!    table: a candidate **fits** when every value lies in it (within [`TOLERANCE`]) and the
//!    largest value reaches at least [`MIN_REACH`] of its span above its zero. An identification
//!    experiment sweeps a good part of the command's range; a scale the values use less than a
//!    fifth of is not what they were written in (0.40/0.45 are not 0.4 % of 0..100, 2047 is
//!    not 20 % of a 0..10000 level when 0..2047 holds it whole). Exactly one candidate fitting
//!    is the scale (`"values: 0..2047 (DShot/raw ESC)"`); none or several is a refusal that
//!    names the candidates and the options (`1000..2000` fits both µs and 0..2047: refused).
//!
//! 5. An `--input` column whose unit the table does not know (`motor[0]`, `setpoint`: unit
//!    `?`) is read like a bare command ([`unknown_input_range`]): `--input-range`, `--esc-us`,
//!    else its values decide among the same candidates (`"values: 0..100 (%)"`). Values that fit
//!    none and are signed or fractional are no command a stand sends (a throttle is never
//!    negative, and a raw command is a whole number: these are a signal in its own units, a
//!    benchmark's voltage, torque or force) and are taken as they are, factor 1
//!    ([`RAW_SIGNAL`], `input_range` `[0, 1]`); whole numbers ≥ 0 that fit none (an 8-bit
//!    10..250: a command in a range of its own), and values that fit several (1000..2000: µs
//!    or raw ESC), are refused naming `--input-range`: a command's scale is not guessed.
//!
//! The map is affine, `throttle = (raw − raw_min) / (raw_max − raw_min)`.

use propid_wire::protocol::csv::columns::{Affine, CommandScales, Scale, Unit};

/// How far outside a scale a value may lie, as a fraction of the scale's span (rounding in
/// exports: 999.5 µs on a 1000..2000 µs ESC).
pub const TOLERANCE: f64 = 0.005;

/// The least share of a candidate scale's span the largest value must reach for the scale to
/// fit (see the module documentation).
pub const MIN_REACH: f64 = 0.2;

/// Ranges the user gave.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GivenRanges {
    /// `--input-range MIN,MAX`: the command's raw values at throttle 0 and 1.
    pub input_range: Option<(f64, f64)>,
    /// `--esc-us MIN,MAX`: the ESC's pulse widths at throttle 0 and 1.
    pub esc_us: Option<(f64, f64)>,
}

/// The scale a command column was read with.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandRange {
    /// Raw value at throttle 0.
    pub raw_min: f64,
    /// Raw value at throttle 1.
    pub raw_max: f64,
    /// The unit as stated (`µs`, `%`, `0..1`, `raw ESC`, ...).
    pub unit: &'static str,
    /// Where the scale came from: `"--input-range"`, `"--esc-us"`, `"header: µs"`,
    /// `"values: 0..1"`, ...
    pub from: String,
}

impl CommandRange {
    /// The map of raw values onto throttle 0..1.
    pub fn affine(&self) -> Affine {
        Affine {
            zero: self.raw_min,
            mul: 1.0,
            div: self.raw_max - self.raw_min,
        }
    }

    /// `--input-range` for an input column the unit table does not know as a command.
    pub fn given_input(range: (f64, f64)) -> Self {
        Self::given(range, "raw", "--input-range")
    }

    fn given(range: (f64, f64), unit: &'static str, from: &str) -> Self {
        Self {
            raw_min: range.0,
            raw_max: range.1,
            unit,
            from: from.to_string(),
        }
    }
}

/// Why the scale of a command column cannot be decided.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RangeError {
    /// No finite value to decide from.
    #[error("no value to decide its range from: give --input-range MIN,MAX")]
    NoValues,
    /// The values leave the scale the header declares.
    #[error("values {lo}..{hi} lie outside {scale}, the range its header declares: give {option}")]
    OutsideDeclared {
        /// Smallest value.
        lo: f64,
        /// Largest value.
        hi: f64,
        /// The declared scale.
        scale: &'static str,
        /// The option to give.
        option: &'static str,
    },
    /// Every value lies within 0..1 and one has a fraction, under a header that declares a
    /// wider scale (`Throttle (%)` holding 0.40, 0.45): fractions or a fraction of a percent
    /// are not told apart from the file.
    #[error(
        "values {lo}..{hi} are fractions of 0..1 under a header that declares {scale}: give \
         --input-range 0,1 if they are fractions of full throttle (--input-range {raw_min},{raw_max} \
         if they are {unit})"
    )]
    FractionsUnderDeclared {
        /// Smallest value.
        lo: f64,
        /// Largest value.
        hi: f64,
        /// The declared scale.
        scale: &'static str,
        /// Its unit.
        unit: &'static str,
        /// Its raw value at throttle 0.
        raw_min: f64,
        /// Its raw value at throttle 1.
        raw_max: f64,
    },
    /// No candidate scale fits the values, or several do.
    #[error(
        "the range cannot be decided from values {lo}..{hi}: {}; give --input-range MIN,MAX \
         (--esc-us MIN,MAX for pulse widths in µs)",
        fits_text(.fits, .candidates)
    )]
    Undecided {
        /// Smallest value.
        lo: f64,
        /// Largest value.
        hi: f64,
        /// The candidates that fit (none, or more than one).
        fits: Vec<&'static str>,
        /// Every candidate.
        candidates: Vec<&'static str>,
    },
}

fn fits_text(fits: &[&str], candidates: &[&str]) -> String {
    if fits.is_empty() {
        format!(
            "they fit none of {} (within its span, reaching a fifth of it)",
            candidates.join(", ")
        )
    } else {
        format!("they fit {} alike", fits.join(" and "))
    }
}

/// The scale of a command column of unit `unit` whose raw values are `values` (NaN = empty
/// cell), by the rule of the module documentation. `None` when `unit` is not a command's.
pub fn command_range(
    unit: Unit,
    values: &[f64],
    given: &GivenRanges,
) -> Option<Result<CommandRange, RangeError>> {
    let scales = unit.command_scales()?;
    if let Some(r) = given.input_range {
        let unit = match scales {
            CommandScales::Declared(s) => s.unit,
            CommandScales::FromValues(_) => "raw",
        };
        return Some(Ok(CommandRange::given(r, unit, "--input-range")));
    }
    let in_us = matches!(
        scales,
        CommandScales::FromValues(_) | CommandScales::Declared(Scale::ESC_US)
    );
    if let (Some(r), true) = (given.esc_us, in_us) {
        return Some(Ok(CommandRange::given(r, "µs", "--esc-us")));
    }
    Some(from_values(scales, values))
}

/// What an input column of unknown unit was taken as when its values fit no command scale
/// and are signed or fractional (rule 5 of the module documentation).
pub const RAW_SIGNAL: &str = "raw: signed or fractional values, no command range";

/// Whether an input column read with `range` is a stand's command: read on a command's scale,
/// any but [`RAW_SIGNAL`] (a signal taken in its own units). A column without one (a force in
/// N named with `--input`: a shaker's) is a measured signal, no command.
pub fn is_a_command(range: Option<&CommandRange>) -> bool {
    range.is_some_and(|r| r.from != RAW_SIGNAL)
}

/// The scale of an `--input` column the unit table does not know (rule 5 of the module
/// documentation): as a bare command's, except that signed or fractional values fitting no
/// command scale are taken raw (factor 1, said in [`CommandRange::from`]).
pub fn unknown_input_range(
    values: &[f64],
    given: &GivenRanges,
) -> Result<CommandRange, RangeError> {
    let decided = command_range(Unit::Command, values, given).unwrap_or(Err(RangeError::NoValues));
    let signal = || {
        values
            .iter()
            .any(|v| v.is_finite() && (*v < 0.0 || v.fract() != 0.0))
    };
    match decided {
        Err(RangeError::Undecided { ref fits, .. }) if fits.is_empty() && signal() => {
            Ok(CommandRange {
                raw_min: 0.0,
                raw_max: 1.0,
                unit: "?",
                from: RAW_SIGNAL.to_string(),
            })
        }
        other => other,
    }
}

fn from_values(scales: CommandScales, values: &[f64]) -> Result<CommandRange, RangeError> {
    let (lo, hi) = values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return Err(RangeError::NoValues);
    }
    let holds = |s: &Scale| {
        let tol = TOLERANCE * (s.raw_max - s.raw_min);
        lo >= s.raw_min - tol && hi <= s.raw_max + tol
    };
    let fractions =
        || hi <= 1.0 && lo >= 0.0 && values.iter().any(|v| v.is_finite() && v.fract() != 0.0);
    match scales {
        CommandScales::Declared(s) if s.raw_max - s.raw_min > 1.0 && fractions() => {
            Err(RangeError::FractionsUnderDeclared {
                lo,
                hi,
                scale: s.label,
                unit: s.unit,
                raw_min: s.raw_min,
                raw_max: s.raw_max,
            })
        }
        CommandScales::Declared(s) if holds(&s) => Ok(CommandRange {
            raw_min: s.raw_min,
            raw_max: s.raw_max,
            unit: s.unit,
            from: format!("header: {}", s.unit),
        }),
        CommandScales::Declared(s) => Err(RangeError::OutsideDeclared {
            lo,
            hi,
            scale: s.label,
            option: if s == Scale::ESC_US {
                "--esc-us MIN,MAX"
            } else {
                "--input-range MIN,MAX"
            },
        }),
        CommandScales::FromValues(candidates) => {
            let reach = |s: &Scale| (hi - s.raw_min) / (s.raw_max - s.raw_min) >= MIN_REACH;
            let fits: Vec<&Scale> = candidates.iter().filter(|s| holds(s) && reach(s)).collect();
            match fits.as_slice() {
                [s] => Ok(CommandRange {
                    raw_min: s.raw_min,
                    raw_max: s.raw_max,
                    unit: s.unit,
                    from: format!("values: {}", s.label),
                }),
                _ => Err(RangeError::Undecided {
                    lo,
                    hi,
                    fits: fits.iter().map(|s| s.label).collect(),
                    candidates: candidates.iter().map(|s| s.label).collect(),
                }),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decide(unit: Unit, values: &[f64]) -> Result<CommandRange, RangeError> {
        command_range(unit, values, &GivenRanges::default()).expect("a command unit")
    }

    fn range(unit: Unit, values: &[f64]) -> (f64, f64, String) {
        let r = decide(unit, values).unwrap_or_else(|e| panic!("{values:?}: {e}"));
        (r.raw_min, r.raw_max, r.from)
    }

    fn stairs(lo: f64, hi: f64) -> Vec<f64> {
        (0..=8).map(|i| lo + (hi - lo) * i as f64 / 8.0).collect()
    }

    #[test]
    fn header_units_declare_the_range() {
        let us = range(Unit::PulseMicrosecond, &stairs(1150.0, 1710.0));
        assert_eq!(us, (1000.0, 2000.0, "header: µs".into()));
        let pct = range(Unit::Percent, &[10.0, 20.0, 20.0]);
        assert_eq!(pct, (0.0, 100.0, "header: %".into()));
        let frac = range(Unit::Fraction, &[0.1, 0.15]);
        assert_eq!(frac, (0.0, 1.0, "header: 0..1".into()));
        let dshot = range(Unit::DShot, &stairs(48.0, 1500.0));
        assert_eq!(dshot, (48.0, 2047.0, "header: DShot".into()));
        // Rounding within half a percent of the span is the scale's own.
        assert_eq!(range(Unit::PulseMicrosecond, &[999.0, 2004.0]).0, 1000.0);
    }

    #[test]
    fn values_outside_the_declared_range_are_refused_with_the_option() {
        let e = decide(Unit::PulseMicrosecond, &[900.0, 2100.0]).unwrap_err();
        assert!(matches!(e, RangeError::OutsideDeclared { .. }), "{e}");
        assert!(e.to_string().contains("--esc-us MIN,MAX"), "{e}");
        let e = decide(Unit::Percent, &[0.0, 250.0]).unwrap_err();
        assert!(e.to_string().contains("--input-range MIN,MAX"), "{e}");
        let e = decide(Unit::Fraction, &[0.0, 40.0]).unwrap_err();
        assert!(e.to_string().contains("0..1"), "{e}");
    }

    #[test]
    fn fractions_under_a_percent_header_are_refused_naming_the_fraction_range() {
        let e = decide(Unit::Percent, &stairs(0.1, 0.9)).unwrap_err();
        assert!(
            matches!(e, RangeError::FractionsUnderDeclared { .. }),
            "{e}"
        );
        let text = e.to_string();
        assert!(text.contains("--input-range 0,1"), "{text}");
        assert!(text.contains("--input-range 0,100"), "{text}");
        // Whole percents, and percents past 1, keep the header's scale.
        assert_eq!(range(Unit::Percent, &[0.0, 1.0, 1.0]).1, 100.0);
        assert_eq!(range(Unit::Percent, &[0.5, 1.5, 2.5]).1, 100.0);
        // Given the fraction range, the column is read with it.
        let given = GivenRanges {
            input_range: Some((0.0, 1.0)),
            esc_us: None,
        };
        let r = command_range(Unit::Percent, &stairs(0.1, 0.9), &given);
        assert_eq!(r.map(|r| r.map(|r| r.raw_max)), Some(Ok(1.0)));
    }

    #[test]
    fn bare_values_decide_each_usual_range() {
        type Case = (Unit, Vec<f64>, (f64, f64), &'static str);
        let cases: [Case; 7] = [
            (
                Unit::ThrottleLevel,
                vec![0.40, 0.45],
                (0.0, 1.0),
                "values: 0..1",
            ),
            (Unit::Command, stairs(0.0, 0.8), (0.0, 1.0), "values: 0..1"),
            (
                Unit::Command,
                stairs(0.0, 60.0),
                (0.0, 100.0),
                "values: 0..100 (%)",
            ),
            (
                Unit::Command,
                stairs(0.0, 2047.0),
                (0.0, 2047.0),
                "values: 0..2047 (DShot/raw ESC)",
            ),
            (
                Unit::Command,
                stairs(48.0, 1200.0),
                (0.0, 2047.0),
                "values: 0..2047 (DShot/raw ESC)",
            ),
            (
                Unit::ThrottleLevel,
                stairs(3000.0, 6000.0),
                (0.0, 10000.0),
                "values: 0..10000 (TSP/1 level)",
            ),
            (
                Unit::Command,
                stairs(0.0, 45000.0),
                (0.0, 65535.0),
                "values: 0..65535 (16-bit PWM)",
            ),
        ];
        for (unit, values, want, from) in cases {
            let got = range(unit, &values);
            assert_eq!((got.0, got.1), want, "{unit:?} {values:?}");
            assert_eq!(got.2, from, "{unit:?} {values:?}");
        }
    }

    #[test]
    fn ambiguous_or_unusual_values_are_refused() {
        // 1000..2000 without a unit: µs or a raw ESC value? Both fit.
        let e = decide(Unit::Command, &stairs(1000.0, 2000.0)).unwrap_err();
        let RangeError::Undecided { fits, .. } = &e else {
            panic!("{e}")
        };
        assert_eq!(fits.len(), 2, "{e}");
        let m = e.to_string();
        assert!(
            m.contains("--input-range MIN,MAX") && m.contains("--esc-us"),
            "{m}"
        );
        assert!(m.contains("1000..2000 µs") && m.contains("0..2047"), "{m}");
        // `throttle` up to 2047: a raw ESC value or a fifth of TSP/1's level.
        assert!(decide(Unit::ThrottleLevel, &stairs(0.0, 2047.0)).is_err());
        // An 8-bit staircase 10..250 fits no usual range (a tenth of 0..2047).
        let e = decide(Unit::Command, &stairs(10.0, 250.0)).unwrap_err();
        assert!(
            matches!(&e, RangeError::Undecided { fits, .. } if fits.is_empty()),
            "{e}"
        );
        // Negative commands, a command never above 15 % of any scale, no value at all.
        assert!(decide(Unit::Command, &[-1.0, 0.5]).is_err());
        assert!(decide(Unit::Command, &[0.0, 0.1]).is_err());
        assert_eq!(
            decide(Unit::Command, &[f64::NAN; 3]),
            Err(RangeError::NoValues)
        );
    }

    #[test]
    fn an_input_of_unknown_unit_is_read_as_a_bare_command_or_raw_when_signed() {
        let none = GivenRanges::default();
        let r = unknown_input_range(&stairs(30.0, 70.0), &none).unwrap();
        assert_eq!(
            (r.raw_min, r.raw_max, r.from.as_str()),
            (0.0, 100.0, "values: 0..100 (%)")
        );
        let r = unknown_input_range(&stairs(0.15, 1.0), &none).unwrap();
        assert_eq!((r.raw_max, r.from.as_str()), (1.0, "values: 0..1"));
        // A signed excitation (Silverbox's V1, a robot arm's torque) or a fractional signal
        // outside every command range (the tanks' pump voltage 0.41..6.47): raw, factor 1, said.
        for values in [vec![-0.08, 0.0, 0.081], vec![-3.0, 2.0], stairs(0.41, 6.47)] {
            let r = unknown_input_range(&values, &none).unwrap();
            assert_eq!(
                (r.raw_min, r.raw_max, r.unit),
                (0.0, 1.0, "?"),
                "{values:?}"
            );
            assert_eq!(r.from, RAW_SIGNAL);
            assert_eq!(r.affine().apply(values[0]), values[0]);
        }
        // Whole numbers >= 0 in no usual range (an 8-bit command), or in two: refused naming
        // --input-range.
        let eight_bit: Vec<f64> = stairs(10.0, 250.0).iter().map(|v| v.round()).collect();
        for values in [eight_bit, vec![51.0, 102.0, 204.0], stairs(1000.0, 2000.0)] {
            let e = unknown_input_range(&values, &none).unwrap_err();
            assert!(e.to_string().contains("--input-range MIN,MAX"), "{e}");
        }
        assert_eq!(
            unknown_input_range(&[f64::NAN], &none),
            Err(RangeError::NoValues)
        );
        // Given ranges win, signed or not.
        let given = GivenRanges {
            input_range: Some((-1.0, 1.0)),
            esc_us: None,
        };
        let r = unknown_input_range(&[-0.5, 0.5], &given).unwrap();
        assert_eq!((r.raw_min, r.from.as_str()), (-1.0, "--input-range"));
        let esc = GivenRanges {
            esc_us: Some((1100.0, 1900.0)),
            input_range: None,
        };
        let r = unknown_input_range(&stairs(1100.0, 1900.0), &esc).unwrap();
        assert_eq!((r.raw_min, r.unit), (1100.0, "µs"));
    }

    #[test]
    fn given_ranges_win_and_are_stated() {
        let given = GivenRanges {
            input_range: Some((0.0, 255.0)),
            esc_us: Some((1100.0, 1900.0)),
        };
        let r = command_range(Unit::Command, &stairs(10.0, 250.0), &given)
            .unwrap()
            .unwrap();
        assert_eq!(
            (r.raw_min, r.raw_max, r.from.as_str()),
            (0.0, 255.0, "--input-range")
        );
        let esc = GivenRanges {
            esc_us: Some((1100.0, 1900.0)),
            ..GivenRanges::default()
        };
        let r = command_range(Unit::PulseMicrosecond, &[1100.0, 1900.0], &esc)
            .unwrap()
            .unwrap();
        assert_eq!(
            (r.raw_min, r.raw_max, r.from.as_str()),
            (1100.0, 1900.0, "--esc-us")
        );
        assert!((r.affine().apply(1500.0) - 0.5).abs() < 1e-12);
        // A declared percent is not a pulse width: --esc-us does not apply to it.
        let r = command_range(Unit::Percent, &[10.0, 50.0], &esc)
            .unwrap()
            .unwrap();
        assert_eq!(r.from, "header: %");
        assert!(command_range(Unit::Newton, &[1.0], &esc).is_none());
    }
}
