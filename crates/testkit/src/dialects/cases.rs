//! The dialects, one stand each way (see [`super`]).

use serde_json::json;

use super::common::{every_row, gf, pct, t_s, us, Collector, PCT_RANGE};
use super::{
    col, expect, num, sparse, unit, Dialect, Expect, Sample, Style, G0, LBF_N, PLAIN, TRUTH,
};

/// The dialects (see the module documentation), each with what a reader must make of it.
pub fn dialects() -> Vec<Dialect> {
    let n: fn(usize, &Sample) -> String = |_, s| num(s.thrust_n, 4);
    let mut c = Collector::new(1);
    // 1. Tyto/RCbenchmark Series 1585: µs command, kgf, N·m, both speeds, extra columns.
    c.add(
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
    c.add(
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
        Expect {
            source: vec![
                ("/input", json!("ESC signal")),
                ("/csv/channels/thrust/values", json!(700)),
            ],
            ..expect(
                &[
                    ("throttle", "ESC signal", "raw ESC", 1.0 / 2047.0),
                    ("thrust", "Thrust (gf)", "gf", G0 / 1e3),
                    ("torque", "Torque (N·mm)", "N·mm", 1e-3),
                ],
                [0.0, 2047.0],
                "values: 0..2047 (DShot/raw ESC)",
            )
        },
    );
    // 3. A European spreadsheet: `;`, decimal commas, grams.
    c.add(
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
        Expect {
            source: vec![
                ("/csv/skipped/not_a_number", json!(0)),
                ("/samples", json!(1050)),
            ],
            ..expect(
                &[
                    ("throttle", "Throttle (%)", "%", 0.01),
                    ("thrust", "Thrust (g)", "gf", G0 / 1e3),
                ],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 4. Units on a row of their own under the names.
    c.add(
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
        Expect {
            source: vec![("/csv/units_row", json!(true))],
            ..expect(
                &[
                    ("time", "Time (s)", "s", 1.0),
                    ("thrust", "Thrust (gf)", "gf", G0 / 1e3),
                    ("torque", "Torque (N·mm)", "N·mm", 1e-3),
                ],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 5. A preamble (motor, propeller, date, a key,value line) before the header.
    c.add(
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
        Expect {
            source: vec![("/csv/preamble", json!(3)), ("/csv/comments", json!(0))],
            ..expect(
                &[("throttle", "ESC (µs)", "µs", 1e-3)],
                [1000.0, 2000.0],
                "header: µs",
            )
        },
    );
    // 6. BOM, CRLF, every field quoted.
    c.add(
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
        expect(&[("time", "Time (s)", "s", 1.0)], PCT_RANGE.0, PCT_RANGE.1),
    );
    // 7. An Arduino logger: milliseconds not starting at 0, pulse width in µs, grams, rpm.
    c.add(
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
    c.add(
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
    c.add(
        "matlab_tab_underscore",
        Style { sep: '\t', ..PLAIN },
        &[
            col("Time_s", t_s),
            col("Throttle_pct", pct),
            col("Thrust_N", n),
        ],
        expect(
            &[("throttle", "Throttle_pct", "%", 0.01)],
            PCT_RANGE.0,
            PCT_RANGE.1,
        ),
    );
    // 10. No time column, rows at a constant rate: refused naming --fs, read with it.
    c.add(
        "no_time_constant_rate",
        PLAIN,
        &[col("Throttle (%)", pct), col("Thrust (N)", n)],
        Expect {
            args: vec!["--fs", "100"],
            refused_without_args: Some(vec!["--fs"]),
            ..expect(
                &[("thrust", "Thrust (N)", "N", 1.0)],
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 11. Time stamps rounded to 20 ms on rows every 10 ms (duplicated stamps): a clock
    //     coarser than the rows, its two rows per stamp spread over the tick (none dropped).
    c.add(
        "duplicated_stamps",
        PLAIN,
        &[
            col("Time (s)", |_, s| {
                num((s.t_s * 50.0 + 1e-9).floor() / 50.0, 2)
            }),
            col("Throttle (%)", pct),
            col("Thrust (N)", n),
        ],
        Expect {
            source: every_row(&[
                ("/csv/jitter/non_increasing", json!(0)),
                ("/csv/jitter/coarse_clock/tick_s", json!(0.02)),
                ("/csv/jitter/coarse_clock/rows_per_tick", json!(2)),
            ]),
            ..expect(&[("time", "Time (s)", "s", 1.0)], PCT_RANGE.0, PCT_RANGE.1)
        },
    );
    // 12. A load cell mounted reversed: thrust negative.
    c.add(
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
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 13. Throttle 0..1, thrust in lbf, speed in eRPM of a 14-pole motor: --poles needed.
    c.add(
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
    c.add(
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
            PCT_RANGE.0,
            PCT_RANGE.1,
        ),
    );
    // 15. Date-time stamps, ms resolution, starting in the evening.
    c.add(
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
            PCT_RANGE.0,
            PCT_RANGE.1,
        ),
    );
    // 16. No header at all: refused naming --columns, read with it.
    c.add(
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
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 17. A thrust column without a unit: refused naming --columns, read with it.
    c.add(
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
                PCT_RANGE.0,
                PCT_RANGE.1,
            )
        },
    );
    // 18. A logger's clock without a unit (`time` in ms): refused naming --columns.
    c.add(
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
    c.add(
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
            PCT_RANGE.0,
            PCT_RANGE.1,
        ),
    );
    // 20. A flight controller's motor output (`motor[0]`, DShot values) beside a load cell: no
    //    command column the table knows, refused naming --input; read with the column and its
    //    range.
    c.add(
        "blackbox_motor_output",
        PLAIN,
        &[
            col("loopIteration", |k, _| (4 * k).to_string()),
            col("time (us)", |_, s| num(5e6 + (1e6 * s.t_s).round(), 0)),
            col("rcCommand[3]", us),
            col("motor[0]", |_, s| num(48.0 + 1999.0 * s.u, 0)),
            col("thrust (g)", gf),
        ],
        Expect {
            args: vec!["--input", "motor[0]", "--input-range", "48,2047"],
            refused_without_args: Some(vec!["--input NAME"]),
            ..expect(
                &[("motor[0]", "motor[0]", "raw", 1.0 / 1999.0)],
                [48.0, 2047.0],
                "--input-range",
            )
        },
    );
    // 21. A `Time` column of times of day (a logger's wall clock), seconds with a decimal comma in
    //     a `;` file.
    c.add(
        "time_of_day_semicolon",
        Style { sep: ';', ..PLAIN },
        &[
            col("Time", |_, s| {
                let ms = 43_199_500 + (1e3 * s.t_s).round() as u64;
                let (h, m, sec, milli) =
                    (ms / 3_600_000, ms / 60_000 % 60, ms / 1000 % 60, ms % 1000);
                format!("{h:02}:{m:02}:{sec:02},{milli:03}")
            }),
            col("Throttle (%)", pct),
            col("Thrust (N)", n),
        ],
        expect(
            &[("time", "Time", "date-time", 1.0)],
            PCT_RANGE.0,
            PCT_RANGE.1,
        ),
    );
    let mut out = c.out;
    let first = out.len() as u64 + 1;
    out.extend(super::numbers::dialects(first));
    let first = out.len() as u64 + 1;
    out.extend(super::quotes::dialects(first));
    let first = out.len() as u64 + 1;
    out.extend(super::clocks::dialects(first));
    let first = out.len() as u64 + 1;
    out.extend(super::names::dialects(first));
    out
}
