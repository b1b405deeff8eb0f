//! Dialects of clocks and sensors (see [`super`]): Unix time stamps in ms and µs, an
//! Arduino's `millis` column, time in minutes, a load cell reading `Force`, a motor's index in
//! its columns' names, a stand with a load cell per motor, and US software's dates and 12-hour
//! clock; a spreadsheet's stamps in whole seconds (100 rows each).

use serde_json::json;

use super::common::{every_row, gf, pct, t_s, us, Collector, PCT_RANGE, US_RANGE};
use super::{col, expect, num, Dialect, Expect, Style, G0, PLAIN};

/// 2024-11-24 12:00:00 UTC, s since 1970.
const UNIX_NOON_S: f64 = 1_732_449_600.0;

/// The dialects of this file, seeded from `first` on.
pub(super) fn dialects(first: u64) -> Vec<Dialect> {
    let n = |_: usize, s: &super::Sample| num(s.thrust_n, 4);
    let mut c = Collector::new(first);
    // A logger's `timestamp`: Unix time in milliseconds, no unit in the header.
    c.add(
        "unix_ms_timestamp",
        PLAIN,
        &[
            col("timestamp", |_, s| {
                num(1e3 * UNIX_NOON_S + (1e3 * s.t_s).round(), 0)
            }),
            col("throttle (%)", pct),
            col("thrust (N)", n),
        ],
        Expect {
            source: every_row(&[]),
            ..expect(
                &[("time", "timestamp", "ms (Unix time)", 1e-3)],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // A `time` column of Unix time in microseconds, `;` separated.
    c.add(
        "unix_us_time",
        Style { sep: ';', ..PLAIN },
        &[
            col("time", |_, s| {
                num(1e6 * UNIX_NOON_S + (1e6 * s.t_s).round(), 0)
            }),
            col("ESC (µs)", us),
            col("Thrust (gf)", gf),
        ],
        expect(
            &[
                ("time", "time", "µs (Unix time)", 1e-6),
                ("thrust", "Thrust (gf)", "gf", G0 / 1e3),
            ],
            US_RANGE.0,
            US_RANGE.1,
        ),
    );
    // An Arduino logger: `millis`, a PWM percentage, a load cell in grams.
    c.add(
        "arduino_millis",
        PLAIN,
        &[
            col("millis", |_, s| num(8_000.0 + (1e3 * s.t_s).round(), 0)),
            col("pwm_pct", pct),
            col("load_g", gf),
        ],
        expect(&[("time", "millis", "ms", 1e-3)], PCT_RANGE.0, PCT_RANGE.1),
    );
    // Time in minutes, a motor's index in every name, the load cell's `Force`.
    c.add(
        "minutes_motor_index_force",
        PLAIN,
        &[
            col("Time (min)", |_, s| num(s.t_s / 60.0, 7)),
            col("Motor 1 ESC (µs)", us),
            col("Motor 1 Force (N)", n),
        ],
        expect(
            &[
                ("time", "Time (min)", "min", 60.0),
                ("throttle", "Motor 1 ESC (µs)", "µs", 1e-3),
                ("thrust", "Motor 1 Force (N)", "N", 1.0),
            ],
            US_RANGE.0,
            US_RANGE.1,
        ),
    );
    // A load cell per motor: which is the output is not guessed; named, it is read.
    c.add(
        "load_cell_per_motor",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("m1_throttle_pct", pct),
            col("m1_thrust_g", gf),
            col("m2_thrust_g", |_, s| num(0.5 * s.thrust_n / G0 * 1e3, 2)),
        ],
        Expect {
            args: vec!["--output", "m1_thrust_g"],
            refused_without_args: Some(vec!["--output NAME", "m1_thrust_g, m2_thrust_g"]),
            ..expect(
                &[("thrust", "m1_thrust_g", "gf", G0 / 1e3)],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // US software's wall clock: `M/D/YYYY h:mm:ss.fff AM|PM`, across midnight (11:59:57 PM on
    // November 24 to 12:00:07 AM on November 25: the date carries the day).
    c.add(
        "us_date_twelve_hour_clock",
        PLAIN,
        &[
            col("Date/Time", |_, s| {
                let ms = 86_397_000 + (1e3 * s.t_s).round() as u64;
                let (day, ms) = (24 + ms / 86_400_000, ms % 86_400_000);
                let (h, m, sec, milli) =
                    (ms / 3_600_000, ms / 60_000 % 60, ms / 1000 % 60, ms % 1000);
                let (h12, half) = (
                    if h % 12 == 0 { 12 } else { h % 12 },
                    if h < 12 { "AM" } else { "PM" },
                );
                format!("11/{day}/2024 {h12}:{m:02}:{sec:02}.{milli:03} {half}")
            }),
            col("ESC signal (µs)", us),
            col("Thrust (gf)", gf),
        ],
        Expect {
            source: every_row(&[]),
            ..expect(
                &[
                    ("time", "Date/Time", "date-time", 1.0),
                    ("thrust", "Thrust (gf)", "gf", G0 / 1e3),
                ],
                US_RANGE.0,
                US_RANGE.1,
            )
        },
    );
    // A spreadsheet that saved its time column in whole seconds (`14:03:27`): 100 rows share
    // each stamp, the first second cut at the record's start (60 rows).
    c.add(
        "spreadsheet_whole_seconds",
        PLAIN,
        &[
            col("Time", |_, s| {
                let sec = (50_607.4 + s.t_s + 1e-9).floor() as u64;
                format!("{}:{:02}:{:02}", sec / 3600, sec / 60 % 60, sec % 60)
            }),
            col("Throttle (%)", pct),
            col("Thrust (gf)", gf),
        ],
        Expect {
            source: every_row(&[
                ("/csv/jitter/coarse_clock/tick_s", json!(1.0)),
                ("/csv/jitter/coarse_clock/rows_per_tick", json!(100)),
                ("/csv/jitter/non_increasing", json!(0)),
            ]),
            ..expect(
                &[
                    ("time", "Time", "date-time", 1.0),
                    ("thrust", "Thrust (gf)", "gf", G0 / 1e3),
                ],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    c.out
}
