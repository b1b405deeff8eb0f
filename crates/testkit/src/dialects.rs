//! Stand exports in the dialects of benches propid has not seen (issue 11, item 1): one
//! simulated stand with known parameters ([`TRUTH`]) written as each bench writes its logs —
//! units in brackets, parentheses, after an underscore or on a row of their own, `;`/tab
//! separators with decimal commas, a preamble before the header, a BOM, CRLF and quoted
//! fields, time in s, ms, µs or date-time stamps not starting at 0, duplicated stamps, no time
//! column, empty trailing columns, sensor cells left empty between sensor updates, a reversed
//! load cell, eRPM, percentages, 0..1, DShot and raw ESC values. Each [`Dialect`] says what a
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
const G0: f64 = 9.80665;
/// One pound-force, N.
const LBF_N: f64 = 4.448_221_615_260_5;

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

const fn col(name: &'static str, cell: fn(usize, &Sample) -> String) -> Col {
    Col {
        name,
        unit: "",
        every: 1,
        phase: 0,
        cell,
    }
}

const fn sparse(
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

const fn unit(name: &'static str, unit: &'static str, cell: fn(usize, &Sample) -> String) -> Col {
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

fn num(v: f64, decimals: usize) -> String {
    format!("{v:.decimals$}")
}

/// Writes the stand in `style` with `cols`.
pub fn write(style: &Style, cols: &[Col], seed: u64) -> String {
    let nl = if style.crlf { "\r\n" } else { "\n" };
    let quote = |f: String| {
        let f = if style.decimal_comma {
            f.replace('.', ",")
        } else {
            f
        };
        if style.quoted {
            format!("\"{f}\"")
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

fn expect(
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
    }
}

/// The dialects (see the module documentation), each with what a reader must make of it.
pub fn dialects() -> Vec<Dialect> {
    let t_s: fn(usize, &Sample) -> String = |_, s| num(s.t_s, 3);
    let pct: fn(usize, &Sample) -> String = |_, s| num(100.0 * s.u, 1);
    let us: fn(usize, &Sample) -> String = |_, s| num(1000.0 + 1000.0 * s.u, 0);
    let n: fn(usize, &Sample) -> String = |_, s| num(s.thrust_n, 4);
    let gf: fn(usize, &Sample) -> String = |_, s| num(s.thrust_n / G0 * 1e3, 2);
    let mut out = Vec::new();
    let mut add = |name, style: Style, cols: &[Col], expect: Expect| {
        out.push(Dialect {
            name,
            text: write(&style, cols, out.len() as u64 + 1),
            expect,
        });
    };
    let pct_range = ([0.0, 100.0], "header: %");
    // 1. Tyto/RCbenchmark Series 1585: µs command, kgf, N·m, both speeds, extra columns.
    add(
        "tyto_1585_kgf",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("ESC signal (µs)", us),
            col("Servo 1 (µs)", |_, _| "1500".into()),
            col("Thrust (kgf)", |_, s| num(s.thrust_n / G0, 5)),
            col("Torque (N·m)", |_, s| num(s.torque_nm, 5)),
            col("Voltage (V)", |_, s| num(s.voltage_v, 3)),
            col("Current (A)", |_, s| num(s.current_a, 3)),
            col("Motor Electrical Speed (RPM)", |_, s| num(s.rpm, 0)),
            col("Motor Optical Speed (RPM)", |_, s| num(s.rpm, 0)),
            col("Electrical Power (W)", |_, s| {
                num(s.voltage_v * s.current_a, 2)
            }),
        ],
        expect(
            &[
                ("time", "Time (s)", "s", 1.0),
                ("throttle", "ESC signal (µs)", "µs", 1e-3),
                ("thrust", "Thrust (kgf)", "kgf", G0),
                ("torque", "Torque (N·m)", "N·m", 1.0),
                ("rpm", "Motor Electrical Speed (RPM)", "RPM", 1.0),
                ("current", "Current (A)", "A", 1.0),
            ],
            [1000.0, 2000.0],
            "header: µs",
        ),
    );
    // 2. Tyto sparse rows: a bare `ESC signal` 0..2047, each sensor on its own rows, an app
    //    message on the first row, 200 rows a second.
    add(
        "tyto_sparse_bare_esc",
        Style {
            dt_s: 0.005,
            ..PLAIN
        },
        &[
            col("Time (s)", |_, s| num(s.t_s, 4)),
            col("ESC signal", |_, s| num(2047.0 * s.u, 0)),
            sparse("Thrust (gf)", 3, 0, gf),
            sparse("Torque (N·mm)", 3, 1, |_, s| num(1e3 * s.torque_nm, 2)),
            sparse("Motor Optical Speed (RPM)", 2, 0, |_, s| num(s.rpm, 0)),
            sparse("Voltage (V)", 10, 5, |_, s| num(s.voltage_v, 3)),
            sparse("Current (A)", 5, 2, |_, s| num(s.current_a, 3)),
            col("App message", |k, _| {
                if k == 0 {
                    "Tare done".into()
                } else {
                    String::new()
                }
            }),
        ],
        expect(
            &[
                ("throttle", "ESC signal", "raw ESC", 1.0 / 2047.0),
                ("thrust", "Thrust (gf)", "gf", G0 / 1e3),
                ("torque", "Torque (N·mm)", "N·mm", 1e-3),
            ],
            [0.0, 2047.0],
            "values: 0..2047 (DShot/raw ESC)",
        ),
    );
    // 3. A European spreadsheet: `;`, decimal commas, grams.
    add(
        "semicolon_decimal_comma",
        Style {
            sep: ';',
            decimal_comma: true,
            ..PLAIN
        },
        &[
            col("Time (s)", t_s),
            col("Throttle (%)", pct),
            col("Thrust (g)", gf),
        ],
        expect(
            &[
                ("throttle", "Throttle (%)", "%", 0.01),
                ("thrust", "Thrust (g)", "gf", G0 / 1e3),
            ],
            pct_range.0,
            pct_range.1,
        ),
    );
    // 4. Units on a row of their own under the names.
    add(
        "units_row",
        Style {
            units_row: true,
            ..PLAIN
        },
        &[
            unit("Time", "s", t_s),
            unit("Throttle", "%", pct),
            unit("Thrust", "gf", gf),
            unit("Torque", "N·mm", |_, s| num(1e3 * s.torque_nm, 2)),
        ],
        expect(
            &[
                ("time", "Time (s)", "s", 1.0),
                ("thrust", "Thrust (gf)", "gf", G0 / 1e3),
                ("torque", "Torque (N·mm)", "N·mm", 1e-3),
            ],
            pct_range.0,
            pct_range.1,
        ),
    );
    // 5. A preamble (motor, propeller, date, a key,value line) before the header.
    add(
        "preamble",
        Style {
            preamble: &[
                "Motor: X2212 920KV",
                "Propeller,10x4.5",
                "Date: 2024-03-01",
                "",
            ],
            ..PLAIN
        },
        &[
            col("Time (s)", t_s),
            col("ESC (µs)", us),
            col("Thrust (N)", n),
        ],
        expect(
            &[("throttle", "ESC (µs)", "µs", 1e-3)],
            [1000.0, 2000.0],
            "header: µs",
        ),
    );
    // 6. BOM, CRLF, every field quoted.
    add(
        "bom_crlf_quoted",
        Style {
            bom: true,
            crlf: true,
            quoted: true,
            ..PLAIN
        },
        &[
            col("Time (s)", t_s),
            col("Throttle (%)", pct),
            col("Thrust (N)", n),
        ],
        expect(&[("time", "Time (s)", "s", 1.0)], pct_range.0, pct_range.1),
    );
    // 7. An Arduino logger: milliseconds not starting at 0, pulse width in µs, grams, rpm.
    add(
        "arduino_ms_offset",
        PLAIN,
        &[
            col("time_ms", |_, s| num(73_421.0 + (1e3 * s.t_s).round(), 0)),
            col("pwm_us", us),
            col("thrust_g", gf),
            col("rpm", |_, s| num(s.rpm, 0)),
        ],
        expect(
            &[
                ("time", "time_ms", "ms", 1e-3),
                ("throttle", "pwm_us", "µs", 1e-3),
                ("thrust", "thrust_g", "gf", G0 / 1e3),
                ("rpm", "rpm", "RPM", 1.0),
            ],
            [1000.0, 2000.0],
            "header: µs",
        ),
    );
    // 8. A flight controller's clock in µs (Betaflight-style `, ` separators), DShot values.
    add(
        "blackbox_dshot_us",
        Style { sep: ',', ..PLAIN },
        &[
            col("loopIteration", |k, _| (4 * k).to_string()),
            col("time (us)", |_, s| {
                num(912_345_678.0 + (1e6 * s.t_s).round(), 0)
            }),
            col(" dshot", |_, s| num(48.0 + 1999.0 * s.u, 0)),
            col(" vbatLatest (V)", |_, s| num(s.voltage_v, 2)),
            col(" amperageLatest (A)", |_, s| num(s.current_a, 2)),
            col(" thrust (g)", gf),
        ],
        expect(
            &[
                ("time", "time (us)", "µs", 1e-6),
                ("throttle", "dshot", "DShot", 1.0 / 1999.0),
                ("current", "amperageLatest (A)", "A", 1.0),
            ],
            [48.0, 2047.0],
            "header: DShot",
        ),
    );
    // 9. A MATLAB `writetable` with tabs and units after an underscore.
    add(
        "matlab_tab_underscore",
        Style { sep: '\t', ..PLAIN },
        &[
            col("Time_s", t_s),
            col("Throttle_pct", pct),
            col("Thrust_N", n),
        ],
        expect(
            &[("throttle", "Throttle_pct", "%", 0.01)],
            pct_range.0,
            pct_range.1,
        ),
    );
    // 10. No time column, rows at a constant rate: refused naming --fs, read with it.
    add(
        "no_time_constant_rate",
        PLAIN,
        &[col("Throttle (%)", pct), col("Thrust (N)", n)],
        Expect {
            args: vec!["--fs", "100"],
            refused_without_args: Some(vec!["--fs"]),
            ..expect(
                &[("thrust", "Thrust (N)", "N", 1.0)],
                pct_range.0,
                pct_range.1,
            )
        },
    );
    // 11. Time stamps rounded to 20 ms on rows every 10 ms (duplicated stamps).
    add(
        "duplicated_stamps",
        PLAIN,
        &[
            col("Time (s)", |_, s| {
                num((s.t_s * 50.0 + 1e-9).floor() / 50.0, 2)
            }),
            col("Throttle (%)", pct),
            col("Thrust (N)", n),
        ],
        expect(&[("time", "Time (s)", "s", 1.0)], pct_range.0, pct_range.1),
    );
    // 12. A load cell mounted reversed: thrust negative.
    add(
        "reversed_load_cell",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("Throttle (%)", pct),
            col("Thrust (N)", |_, s| num(-s.thrust_n, 4)),
        ],
        Expect {
            gain_n: -TRUTH.gain_n,
            ..expect(
                &[("thrust", "Thrust (N)", "N", 1.0)],
                pct_range.0,
                pct_range.1,
            )
        },
    );
    // 13. Throttle 0..1, thrust in lbf, speed in eRPM of a 14-pole motor: --poles needed.
    add(
        "erpm_lbf_fraction",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("Throttle (0-1)", |_, s| num(s.u, 3)),
            col("Thrust (lbf)", |_, s| num(s.thrust_n / LBF_N, 5)),
            col("eRPM", |_, s| num(7.0 * s.rpm, 0)),
        ],
        Expect {
            args: vec!["--poles", "14"],
            ..expect(
                &[
                    ("throttle", "Throttle (0-1)", "0..1", 1.0),
                    ("thrust", "Thrust (lbf)", "lbf", LBF_N),
                    ("rpm", "eRPM", "eRPM", 2.0 / 14.0),
                ],
                [0.0, 1.0],
                "header: 0..1",
            )
        },
    );
    // 14. Empty trailing columns, thrust in ozf, torque in lbf·in.
    add(
        "trailing_empty_ozf",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("Throttle (%)", pct),
            col("Thrust (ozf)", |_, s| num(s.thrust_n / LBF_N * 16.0, 3)),
            col("Torque (lbf·in)", |_, s| {
                num(s.torque_nm / (LBF_N * 0.0254), 4)
            }),
            col("", |_, _| String::new()),
            col("", |_, _| String::new()),
        ],
        expect(
            &[
                ("thrust", "Thrust (ozf)", "ozf", LBF_N / 16.0),
                ("torque", "Torque (lbf·in)", "lbf·in", LBF_N * 0.0254),
            ],
            pct_range.0,
            pct_range.1,
        ),
    );
    // 15. Date-time stamps, ms resolution, starting in the evening.
    add(
        "datetime_stamps",
        PLAIN,
        &[
            col("Timestamp", |_, s| {
                let ms = 68_123_000 + (1e3 * s.t_s).round() as u64;
                let (h, m, sec, milli) =
                    (ms / 3_600_000, ms / 60_000 % 60, ms / 1000 % 60, ms % 1000);
                format!("2024-08-13 {h:02}:{m:02}:{sec:02}.{milli:03}")
            }),
            col("Throttle (%)", pct),
            col("Thrust (N)", n),
        ],
        expect(
            &[("time", "Timestamp", "date-time", 1.0)],
            pct_range.0,
            pct_range.1,
        ),
    );
    // 16. No header at all: refused naming --columns, read with it.
    add(
        "no_header",
        Style {
            header: false,
            ..PLAIN
        },
        &[col("", t_s), col("", pct), col("", gf)],
        Expect {
            args: vec!["--columns", "t_s,throttle_pct,thrust_g"],
            refused_without_args: Some(vec!["--columns", "no header"]),
            ..expect(
                &[("thrust", "thrust_g", "gf", G0 / 1e3)],
                pct_range.0,
                pct_range.1,
            )
        },
    );
    // 17. A thrust column without a unit: refused naming --columns, read with it.
    add(
        "thrust_without_unit",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("Throttle (%)", pct),
            col("Thrust", n),
        ],
        Expect {
            args: vec!["--columns", "Time (s),Throttle (%),Thrust (N)"],
            refused_without_args: Some(vec!["--columns", "Thrust", "without a unit"]),
            ..expect(
                &[("thrust", "Thrust (N)", "N", 1.0)],
                pct_range.0,
                pct_range.1,
            )
        },
    );
    // 18. A logger's clock without a unit (`time` in ms): refused naming --columns.
    add(
        "unitless_millis",
        PLAIN,
        &[
            col("time", |_, s| num(1234.0 + (1e3 * s.t_s).round(), 0)),
            col("pwm_us", us),
            col("thrust_g", gf),
        ],
        Expect {
            args: vec!["--columns", "time_ms,pwm_us,thrust_g"],
            refused_without_args: Some(vec!["--columns", "time_ms", "no unit"]),
            ..expect(
                &[("time", "time_ms", "ms", 1e-3)],
                [1000.0, 2000.0],
                "header: µs",
            )
        },
    );
    // 19. Units in square brackets, SI multiples: rad/s, mV, mA.
    add(
        "brackets_rad_s_mv_ma",
        PLAIN,
        &[
            col("t [s]", t_s),
            col("Command [%]", pct),
            col("Thrust [N]", n),
            col("Speed [rad/s]", |_, s| {
                num(s.rpm * std::f64::consts::TAU / 60.0, 3)
            }),
            col("Voltage [mV]", |_, s| num(1e3 * s.voltage_v, 0)),
            col("Current [mA]", |_, s| num(1e3 * s.current_a, 0)),
        ],
        expect(
            &[
                (
                    "rpm",
                    "Speed [rad/s]",
                    "rad/s",
                    60.0 / std::f64::consts::TAU,
                ),
                ("current", "Current [mA]", "mA", 1e-3),
            ],
            pct_range.0,
            pct_range.1,
        ),
    );
    out
}

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
        // Same seed, same bytes.
        assert_eq!(dialects()[3].text, d[3].text);
    }
}
