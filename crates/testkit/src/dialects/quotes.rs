//! Dialects of quotes and names (see [`super`]): RFC 4180 escaped quotes, stray inch marks, a
//! `;` file with decimal points and thousands commas, load cells named as such.

use super::common::{every_row, gf, pct, t_s, us, Collector, PCT_RANGE, US_RANGE};
use super::{col, expect, num, Dialect, Expect, Style, G0, PLAIN};

/// The dialects of this file, seeded from `first` on.
pub(super) fn dialects(first: u64) -> Vec<Dialect> {
    let mut c = Collector::new(first);
    // 28. RFC 4180: every field quoted, `""` for a quote: the header `"Thrust ""gf"""`, a note
    //     `"10""x4.5, 2-blade"` holding the separator and a quote.
    c.add(
        "rfc4180_escaped_quotes",
        Style {
            quoted: true,
            ..PLAIN
        },
        &[
            col("Time (s)", t_s),
            col("Throttle (%)", pct),
            col("Thrust \"gf\"", gf),
            col("Note, \"prop\"", |_, _| "10\"x4.5, 2-blade".into()),
        ],
        Expect {
            source: every_row(&[]),
            ..expect(
                &[
                    ("throttle", "Throttle (%)", "%", 0.01),
                    ("thrust", "Thrust \"gf\"", "gf", G0 / 1e3),
                ],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 29. Inch marks, unquoted: a header `Torque (in-oz")` and cells `5"x4.5` before the
    //     command and thrust columns, a load cell called `Load (g)`.
    c.add(
        "inch_marks",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("Torque (in-oz\")", |_, s| {
                num(s.torque_nm / 0.007_061_552, 3)
            }),
            col("Prop", |_, _| "5\"x4.5".into()),
            col("Throttle (%)", pct),
            col("Load (g)", gf),
        ],
        Expect {
            source: every_row(&[]),
            ..expect(
                &[
                    ("throttle", "Throttle (%)", "%", 0.01),
                    ("thrust", "Load (g)", "gf", G0 / 1e3),
                ],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 30. A `;` file with decimal points and thousands commas (a European-locale export with
    //     English numbers): `0.010;1,300;307.23;6,026`.
    c.add(
        "semicolon_thousands_decimal_point",
        Style {
            sep: ';',
            thousands: true,
            ..PLAIN
        },
        &[
            col("Time (s)", t_s),
            col("ESC signal (µs)", us),
            col("Thrust (g)", gf),
            col("Motor Optical Speed (RPM)", |_, s| num(s.rpm, 0)),
        ],
        Expect {
            source: every_row(&[]),
            ..expect(
                &[
                    ("throttle", "ESC signal (µs)", "µs", 1e-3),
                    ("thrust", "Thrust (g)", "gf", G0 / 1e3),
                    ("rpm", "Motor Optical Speed (RPM)", "RPM", 1.0),
                ],
                US_RANGE.0,
                US_RANGE.1,
            )
        },
    );
    // 31. A hobby bench: `PWM (us)`, `Load cell (g)`, voltage and current.
    c.add(
        "pwm_us_load_cell",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("PWM (us)", us),
            col("Load cell (g)", gf),
            col("Voltage (V)", |_, s| num(s.voltage_v, 3)),
            col("Current (A)", |_, s| num(s.current_a, 3)),
        ],
        Expect {
            source: every_row(&[]),
            ..expect(
                &[
                    ("throttle", "PWM (us)", "µs", 1e-3),
                    ("thrust", "Load cell (g)", "gf", G0 / 1e3),
                    ("current", "Current (A)", "A", 1.0),
                ],
                US_RANGE.0,
                US_RANGE.1,
            )
        },
    );
    c.out
}
