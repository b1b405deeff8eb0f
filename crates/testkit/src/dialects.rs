//! Stand exports in the dialects of benches propid has not seen (issue 11, item 1): one
//! simulated stand with known parameters ([`TRUTH`]) written as each bench writes its logs —
//! units in brackets, parentheses, after an underscore or on a row of their own, `;`/tab
//! separators with decimal commas, a preamble before the header, a BOM, CRLF and quoted
//! fields (RFC 4180 `""` escapes, stray inch marks: `dialects/quotes.rs`), time in s, ms, µs,
//! minutes, Unix time stamps or date-time stamps not starting at 0, duplicated stamps, no time
//! column, empty trailing columns, sensor cells left empty between sensor updates, a reversed
//! load cell, eRPM, percentages, 0..1, DShot and raw ESC values, a motor's index in the
//! names and a load cell per motor (`dialects/clocks.rs`), qualified and small stands' names,
//! a stopwatch's time, percent signs in cells and fractions under a `%` header
//! (`dialects/names.rs`). Each [`Dialect`] says what a
//! reader must make of it (the units, the command's range) or how it must be refused and what
//! fixes it. Written from the dialects' features, not copied from any bench's file.
//!
//! The stand: a command staircase up and down ([`LEVELS`], each held [`HOLD_S`]); thrust
//! `T = K·u` N reached through a dead time and a first-order lag ([`Truth`]); rotor speed,
//! torque and current follow the thrust; the supply sags with the current. Thrust noise is
//! Gaussian (σ = [`NOISE_N`]), seeded: every call gives the same bytes.

use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// The simulated stand's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Thrust per unit throttle, N.
    pub gain_n: f64,
    /// Time constant of the thrust, s.
    pub tau_s: f64,
    /// Dead time from command to thrust, s.
    pub dead_s: f64,
}

/// The stand every dialect is written from.
pub const TRUTH: Truth = Truth {
    gain_n: 10.0,
    tau_s: 0.08,
    dead_s: 0.02,
};

/// The command staircase (throttle 0..1), up and down.
pub const LEVELS: [f64; 7] = [0.3, 0.5, 0.4, 0.7, 0.5, 0.6, 0.3];
/// How long each level is held, s.
pub const HOLD_S: f64 = 1.5;
/// Thrust noise, N (σ).
pub const NOISE_N: f64 = 0.01;
/// Rotor speed per newton of thrust, rev/min (linear, like the thrust: the dialect is the
/// point, not the propeller).
const RPM_PER_N: f64 = 2000.0;
/// Standard gravity (gram-force, kilogram-force).
pub(crate) const G0: f64 = 9.80665;
/// One pound-force, N.
pub(crate) const LBF_N: f64 = 4.448_221_615_260_5;

/// One sample of the stand, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time since the start, s.
    pub t_s: f64,
    /// Throttle 0..1.
    pub u: f64,
    /// Thrust, N (with noise).
    pub thrust_n: f64,
    /// Rotor speed, rev/min.
    pub rpm: f64,
    /// Torque, N·m.
    pub torque_nm: f64,
    /// Current, A.
    pub current_a: f64,
    /// Supply voltage, V.
    pub voltage_v: f64,
}

/// The stand sampled every `dt_s` over the whole staircase (exact discretisation of the lag,
/// the command delayed by the dead time), thrust noise from `seed`.
pub fn stand(dt_s: f64, seed: u64) -> Vec<Sample> {
    let n = (LEVELS.len() as f64 * HOLD_S / dt_s).round() as usize;
    let level = |t: f64| LEVELS[((t.max(0.0) / HOLD_S) as usize).min(LEVELS.len() - 1)];
    let a = (-dt_s / TRUTH.tau_s).exp();
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, NOISE_N).expect("σ > 0");
    let mut y = TRUTH.gain_n * LEVELS[0];
    (0..n)
        .map(|k| {
            let t = k as f64 * dt_s;
            let thrust = y;
            y = a * y + (1.0 - a) * TRUTH.gain_n * level(t - TRUTH.dead_s);
            let current = 0.5 + 2.0 * thrust;
            Sample {
                t_s: t,
                u: level(t),
                thrust_n: thrust + noise.sample(&mut rng),
                rpm: RPM_PER_N * thrust,
                torque_nm: 0.02 * thrust,
                current_a: current,
                voltage_v: 16.8 - 0.05 * current,
            }
        })
        .collect()
}

/// One column of an export: its header name and its cell, written every `every`-th row (empty
/// between: a sensor slower than the rows).
#[derive(Clone, Copy)]
pub struct Col {
    /// The header's name.
    pub name: &'static str,
    /// The unit on a units row (when the dialect has one).
    pub unit: &'static str,
    /// Written on rows `k` with `k % every == phase`.
    pub every: usize,
    /// See `every`.
    pub phase: usize,
    /// The cell of row `k` at sample `s`.
    pub cell: fn(usize, &Sample) -> String,
}

pub(crate) const fn col(name: &'static str, cell: fn(usize, &Sample) -> String) -> Col {
    Col {
        name,
        unit: "",
        every: 1,
        phase: 0,
        cell,
    }
}

pub(crate) const fn sparse(
    name: &'static str,
    every: usize,
    phase: usize,
    c: fn(usize, &Sample) -> String,
) -> Col {
    Col {
        name,
        unit: "",
        every,
        phase,
        cell: c,
    }
}

pub(crate) const fn unit(
    name: &'static str,
    unit: &'static str,
    cell: fn(usize, &Sample) -> String,
) -> Col {
    Col {
        name,
        unit,
        every: 1,
        phase: 0,
        cell,
    }
}

/// How the rows are written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    /// Field separator.
    pub sep: char,
    /// Decimal comma in numbers.
    pub decimal_comma: bool,
    /// `\r\n` line ends.
    pub crlf: bool,
    /// A UTF-8 byte-order mark first.
    pub bom: bool,
    /// Every field in double quotes.
    pub quoted: bool,
    /// Thousands grouped (`1,300`; `1.300` with a decimal comma).
    pub thousands: bool,
    /// A units row under the header (from [`Col::unit`]).
    pub units_row: bool,
    /// A header line at all.
    pub header: bool,
    /// Lines before the header.
    pub preamble: &'static [&'static str],
    /// Row period, s.
    pub dt_s: f64,
}

/// `,`-separated, `\n`, a header, rows every 10 ms.
pub const PLAIN: Style = Style {
    sep: ',',
    decimal_comma: false,
    crlf: false,
    bom: false,
    quoted: false,
    thousands: false,
    units_row: false,
    header: true,
    preamble: &[],
    dt_s: 0.01,
};

/// What a reader must make of a dialect.
#[derive(Debug, Clone, PartialEq)]
pub struct Expect {
    /// Extra arguments to `identify`/`diagnose` the dialect needs (`--poles 14`, `--fs 100`).
    pub args: Vec<&'static str>,
    /// Without `args`, the file is refused (exit 3) with a message naming each of these.
    pub refused_without_args: Option<Vec<&'static str>>,
    /// Per channel key (`time`, `throttle`, `thrust`, `torque`, `rpm`, `current`: what identify
    /// reads; the voltage is diagnose's): column, unit, factor.
    pub units: Vec<(&'static str, &'static str, &'static str, f64)>,
    /// The command's raw values at throttle 0 and 1.
    pub input_range: [f64; 2],
    /// Where that range came from (`header: %`, `values: 0..2047 (DShot/raw ESC)`, ...).
    pub input_range_from: &'static str,
    /// Thrust per unit throttle in the file's sign (−K for a load cell mounted reversed).
    pub gain_n: f64,
    /// Other facts of identify's `source`: a JSON pointer into it and the value there
    /// (`/csv/preamble` = 3).
    pub source: Vec<(&'static str, serde_json::Value)>,
}

/// One dialect: its name, the file's text and what a reader must make of it.
pub struct Dialect {
    /// Short name (the file name without `.csv`).
    pub name: &'static str,
    /// The file's text.
    pub text: String,
    /// What a reader must make of it.
    pub expect: Expect,
}

pub(crate) fn num(v: f64, decimals: usize) -> String {
    format!("{v:.decimals$}")
}

/// Writes the stand in `style` with `cols`.
pub fn write(style: &Style, cols: &[Col], seed: u64) -> String {
    let nl = if style.crlf { "\r\n" } else { "\n" };
    let quote = |f: String| {
        let f = if style.thousands {
            group_thousands(&f)
        } else {
            f
        };
        let f = if style.decimal_comma {
            // The marks trade places: `1,300.5` becomes `1.300,5`.
            f.chars()
                .map(|c| match c {
                    '.' => ',',
                    ',' => '.',
                    c => c,
                })
                .collect()
        } else {
            f
        };
        if style.quoted {
            // RFC 4180: a quote inside a quoted field is doubled.
            format!("\"{}\"", f.replace('"', "\"\""))
        } else {
            f
        }
    };
    let sep = style.sep.to_string();
    let mut text = String::new();
    if style.bom {
        text.push('\u{feff}');
    }
    for l in style.preamble {
        text.push_str(l);
        text.push_str(nl);
    }
    let line = |cells: Vec<String>| cells.join(&sep);
    if style.header {
        text.push_str(&line(
            cols.iter().map(|c| quote(c.name.to_string())).collect(),
        ));
        text.push_str(nl);
    }
    if style.units_row {
        text.push_str(&line(
            cols.iter().map(|c| quote(c.unit.to_string())).collect(),
        ));
        text.push_str(nl);
    }
    for (k, s) in stand(style.dt_s, seed).iter().enumerate() {
        let cells = cols
            .iter()
            .map(|c| match k % c.every == c.phase {
                true => quote((c.cell)(k, s)),
                false => String::new(),
            })
            .collect();
        text.push_str(&line(cells));
        text.push_str(nl);
    }
    text
}

/// A number's integer digits grouped by three with `,` (`-12345.6` → `-12,345.6`); other text
/// as it is.
fn group_thousands(f: &str) -> String {
    let (sign, body) = match f.strip_prefix('-') {
        Some(b) => ("-", b),
        None => ("", f),
    };
    let (int, frac) = body.split_once('.').unwrap_or((body, ""));
    let numeric = !int.is_empty()
        && int.bytes().all(|c| c.is_ascii_digit())
        && frac.bytes().all(|c| c.is_ascii_digit());
    if !numeric {
        return f.to_string();
    }
    let mut grouped = String::new();
    for (i, c) in int.chars().enumerate() {
        if i > 0 && (int.len() - i) % 3 == 0 {
            grouped.push(',');
        }
        grouped.push(c);
    }
    match body.contains('.') {
        true => format!("{sign}{grouped}.{frac}"),
        false => format!("{sign}{grouped}"),
    }
}

pub(crate) fn expect(
    units: &[(&'static str, &'static str, &'static str, f64)],
    range: [f64; 2],
    from: &'static str,
) -> Expect {
    Expect {
        args: Vec::new(),
        refused_without_args: None,
        units: units.to_vec(),
        input_range: range,
        input_range_from: from,
        gain_n: TRUTH.gain_n,
        source: Vec::new(),
    }
}

/// What the dialect files share: the column writers most of them use, the command ranges a
/// header's unit gives, the expectations of a file with every row complete, and the
/// collector that numbers each dialect's noise seed.
mod common {
    use serde_json::{json, Value};

    use super::{num, write, Col, Dialect, Expect, Sample, Style, G0};

    /// Time, seconds.
    pub(super) fn t_s(_: usize, s: &Sample) -> String {
        num(s.t_s, 3)
    }

    /// Throttle, percent.
    pub(super) fn pct(_: usize, s: &Sample) -> String {
        num(100.0 * s.u, 1)
    }

    /// ESC pulse, µs (1000..2000).
    pub(super) fn us(_: usize, s: &Sample) -> String {
        num(1000.0 + 1000.0 * s.u, 0)
    }

    /// Thrust, gram-force.
    pub(super) fn gf(_: usize, s: &Sample) -> String {
        num(s.thrust_n / G0 * 1e3, 2)
    }

    /// The command range and its statement from a `µs` header.
    pub(super) const US_RANGE: ([f64; 2], &str) = ([1000.0, 2000.0], "header: µs");
    /// The command range and its statement from a `%` header.
    pub(super) const PCT_RANGE: ([f64; 2], &str) = ([0.0, 100.0], "header: %");

    /// The `source` expectations of a file whose rows are all complete (nothing skipped, 1050
    /// samples), and `extra`.
    pub(super) fn every_row(extra: &[(&'static str, Value)]) -> Vec<(&'static str, Value)> {
        let mut v = vec![
            ("/csv/skipped/not_a_number", json!(0)),
            ("/samples", json!(1050)),
        ];
        v.extend(extra.iter().cloned());
        v
    }

    /// Dialects in order, the `k`-th seeded `first + k`.
    pub(super) struct Collector {
        first: u64,
        pub(super) out: Vec<Dialect>,
    }

    impl Collector {
        /// An empty collection whose first dialect is seeded `first`.
        pub(super) fn new(first: u64) -> Collector {
            Collector {
                first,
                out: Vec::new(),
            }
        }

        /// Writes dialect `name` in `style` with columns `cols`.
        pub(super) fn add(
            &mut self,
            name: &'static str,
            style: Style,
            cols: &[Col],
            expect: Expect,
        ) {
            let text = write(&style, cols, self.first + self.out.len() as u64);
            self.out.push(Dialect { name, text, expect });
        }
    }
}

mod cases;
mod clocks;
mod names;
mod numbers;
mod quotes;
pub use cases::dialects;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stand_settles_on_k_u_after_the_dead_time() {
        let s = stand(0.01, 1);
        // Just before the first step's dead time ends the thrust is still on level 0; a hold
        // later it is K·u of level 1 within the noise.
        let at = |t: f64| s[(t / 0.01).round() as usize];
        assert!((at(HOLD_S + 0.01).thrust_n - TRUTH.gain_n * LEVELS[0]).abs() < 0.05);
        assert!((at(2.0 * HOLD_S - 0.01).thrust_n - TRUTH.gain_n * LEVELS[1]).abs() < 0.05);
        assert_eq!(at(HOLD_S).u, LEVELS[1]);
    }

    #[test]
    fn dialects_write_their_features() {
        let d = dialects();
        assert!(d.len() >= 12);
        let text = |name: &str| &d.iter().find(|x| x.name == name).unwrap().text;
        assert!(text("semicolon_decimal_comma")
            .lines()
            .nth(1)
            .unwrap()
            .contains(';'));
        assert!(text("semicolon_decimal_comma")
            .lines()
            .nth(1)
            .unwrap()
            .contains(','));
        assert!(text("bom_crlf_quoted").starts_with("\u{feff}\"Time (s)\""));
        assert!(text("bom_crlf_quoted").contains("\r\n"));
        assert_eq!(text("units_row").lines().nth(1), Some("s,%,gf,N·mm"));
        assert!(text("tyto_sparse_bare_esc")
            .lines()
            .nth(2)
            .unwrap()
            .contains(",,"));
        assert_eq!(group_thousands("-12345.6"), "-12,345.6");
        assert_eq!(group_thousands("1300"), "1,300");
        assert_eq!(group_thousands("999.25"), "999.25");
        assert_eq!(group_thousands("Time (s)"), "Time (s)");
        let eu = text("semicolon_thousands_decimal_comma");
        assert!(eu.lines().nth(1).unwrap().contains(";1.300;"), "{eu:.200}");
        assert!(text("quoted_thousands").contains("\"1,300.0\""));
        assert!(text("comma_quoted_decimal_comma")
            .lines()
            .nth(1)
            .unwrap()
            .starts_with("\"0,000\",\"30,0\","));
        assert!(text("time_of_day_midnight").contains("\n00:00:00.000,"));
        let us = text("us_date_twelve_hour_clock");
        assert!(us.contains("\n11/24/2024 11:59:57.000 PM,"), "{us:.200}");
        assert!(us.contains("\n11/25/2024 12:00:00.000 AM,"));
        let rfc = text("rfc4180_escaped_quotes");
        assert!(rfc.starts_with("\"Time (s)\",\"Throttle (%)\",\"Thrust \"\"gf\"\"\","));
        assert!(rfc
            .lines()
            .nth(1)
            .unwrap()
            .ends_with(",\"10\"\"x4.5, 2-blade\""));
        let inch = text("inch_marks");
        assert!(inch.starts_with("Time (s),Torque (in-oz\"),Prop,"));
        assert!(inch.lines().nth(1).unwrap().contains(",5\"x4.5,"));
        let semi = text("semicolon_thousands_decimal_point");
        assert!(semi.lines().nth(1).unwrap().starts_with("0.000;1,300;"));
        // Same seed, same bytes.
        assert_eq!(dialects()[3].text, d[3].text);
    }
}
