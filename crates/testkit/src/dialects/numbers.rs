//! Dialects of numbers and clocks (see [`super`]): thousands separators with either decimal
//! mark, decimal commas in quoted fields of a `,` file, times of day across midnight, and a
//! command column the unit table does not know.

use serde_json::json;

use super::common::{every_row, gf, pct, t_s, us, Collector, PCT_RANGE, US_RANGE};
use super::{col, expect, num, Dialect, Expect, Sample, Style, G0, PLAIN};

/// The dialects of this file, seeded from `first` on.
pub(super) fn dialects(first: u64) -> Vec<Dialect> {
    // Electrical rpm of a 14-pole motor: up to 98 000, thousands grouped.
    let erpm: fn(usize, &Sample) -> String = |_, s| num(7.0 * s.rpm, 0);
    let mut c = Collector::new(first);
    // 22. A European spreadsheet with thousands: `;`, `1.300` µs, `98.000` eRPM, `0,010` s
    //     (the `0,010` tells that `1.300` is 1300 and `1,500` s is 1.5 s).
    c.add(
        "semicolon_thousands_decimal_comma",
        Style {
            sep: ';',
            decimal_comma: true,
            thousands: true,
            ..PLAIN
        },
        &[
            col("Time (s)", t_s),
            col("ESC signal (µs)", us),
            col("Thrust (g)", gf),
            col("eRPM", erpm),
        ],
        Expect {
            args: vec!["--poles", "14"],
            source: every_row(&[("/csv/decimal_mark", json!(","))]),
            ..expect(
                &[
                    ("throttle", "ESC signal (µs)", "µs", 1e-3),
                    ("thrust", "Thrust (g)", "gf", G0 / 1e3),
                    ("rpm", "eRPM", "eRPM", 2.0 / 14.0),
                ],
                US_RANGE.0,
                US_RANGE.1,
            )
        },
    );
    // 23. A Tyto-style export with every field quoted and thousands grouped: `"1,300.0"` µs,
    //     `"98,000"` eRPM in a `,` file.
    c.add(
        "quoted_thousands",
        Style {
            quoted: true,
            thousands: true,
            ..PLAIN
        },
        &[
            col("Time (s)", |_, s| num(s.t_s, 4)),
            col("ESC signal (µs)", |_, s| num(1000.0 + 1000.0 * s.u, 1)),
            col("Thrust (gf)", gf),
            col("eRPM", erpm),
        ],
        Expect {
            args: vec!["--poles", "14"],
            source: every_row(&[]),
            ..expect(
                &[
                    ("throttle", "ESC signal (µs)", "µs", 1e-3),
                    ("rpm", "eRPM", "eRPM", 2.0 / 14.0),
                ],
                US_RANGE.0,
                US_RANGE.1,
            )
        },
    );
    // 24. Tab-separated with thousands and decimal points: `1,300` µs beside `0.010` s.
    c.add(
        "tab_thousands",
        Style {
            sep: '\t',
            thousands: true,
            ..PLAIN
        },
        &[
            col("Time_s", t_s),
            col("pwm_us", us),
            col("thrust_g", gf),
            col("Speed (eRPM)", erpm),
        ],
        Expect {
            args: vec!["--poles", "14"],
            source: every_row(&[]),
            ..expect(
                &[
                    ("throttle", "pwm_us", "µs", 1e-3),
                    ("rpm", "Speed (eRPM)", "eRPM", 2.0 / 14.0),
                ],
                US_RANGE.0,
                US_RANGE.1,
            )
        },
    );
    // 25. Decimal commas inside the quoted fields of a `,` file (`"0,45","12,3"`).
    c.add(
        "comma_quoted_decimal_comma",
        Style {
            quoted: true,
            decimal_comma: true,
            ..PLAIN
        },
        &[
            col("Time (s)", t_s),
            col("Throttle (%)", pct),
            col("Thrust (N)", |_, s| num(s.thrust_n, 4)),
        ],
        Expect {
            source: every_row(&[("/csv/decimal_mark", json!(","))]),
            ..expect(
                &[("throttle", "Throttle (%)", "%", 0.01)],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 26. A logger's wall clock (times of day) across midnight: 23:59:57.000 ... 00:00:07.490.
    c.add(
        "time_of_day_midnight",
        PLAIN,
        &[
            col("Time", |_, s| {
                let ms = (86_397_000 + (1e3 * s.t_s).round() as u64) % 86_400_000;
                let (h, m, sec, milli) =
                    (ms / 3_600_000, ms / 60_000 % 60, ms / 1000 % 60, ms % 1000);
                format!("{h:02}:{m:02}:{sec:02}.{milli:03}")
            }),
            col("Throttle (%)", pct),
            col("Thrust (N)", |_, s| num(s.thrust_n, 4)),
        ],
        Expect {
            source: every_row(&[("/csv/midnights", json!(1))]),
            ..expect(
                &[("time", "Time", "date-time", 1.0)],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 27. A command column the unit table does not know (`setpoint`, 30..70): refused naming
    //     --input; with it, its range is inferred from the values and said.
    c.add(
        "unknown_unit_input",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("setpoint", pct),
            col("Thrust (N)", |_, s| num(s.thrust_n, 4)),
        ],
        Expect {
            args: vec!["--input", "setpoint"],
            refused_without_args: Some(vec!["--input NAME"]),
            ..expect(
                &[("setpoint", "setpoint", "%", 0.01)],
                [0.0, 100.0],
                "values: 0..100 (%)",
            )
        },
    );
    c.out
}
