//! Dialects of names and cells (see [`super`]): a qualifier before a quantity's word (`Motor
//! RPM`, `Battery Voltage`, `Rotor speed`), the small stands' words for a load cell (`Pull`,
//! `Lift`) and for a command (`Signal`, `cmd [-]`, `Duty cycle`), a stopwatch's `M:SS.fff`
//! time, percent signs in the cells, a drag `Force` left of the `Thrust`, fractions under a
//! `%` header (refused: which the exporter meant is not in the file), a German bench's words,
//! a snake_case script log (`motor_cmd`, `load_cell_N`) and `quantity / unit` headers.

use super::common::{gf, pct, t_s, us, Collector, PCT_RANGE, US_RANGE};
use super::{col, expect, num, Dialect, Expect, Sample, G0, PLAIN};

/// The dialects of this file, seeded from `first` on.
pub(super) fn dialects(first: u64) -> Vec<Dialect> {
    let n = |_: usize, s: &Sample| num(s.thrust_n, 4);
    let mut c = Collector::new(first);
    // A hobby bench: a stopwatch's minutes and seconds, percentages with their sign, the load
    // cell's `Pull` in kg, qualified speed, voltage and current.
    c.add(
        "stopwatch_percent_cells_pull",
        PLAIN,
        &[
            col("Time", |_, s| {
                let ms = (1e3 * s.t_s).round() as u64;
                format!("{}:{:02}.{:03}", ms / 60_000, ms / 1000 % 60, ms % 1000)
            }),
            col("Throttle", |_, s| format!("{:.0}%", 100.0 * s.u)),
            col("Pull (kg)", |_, s| num(s.thrust_n / G0, 5)),
            col("Motor RPM", |_, s| num(s.rpm, 0)),
            col("Battery Voltage (V)", |_, s| num(s.voltage_v, 2)),
            col("Motor Current (A)", |_, s| num(s.current_a, 2)),
        ],
        expect(
            &[
                ("time", "Time", "date-time", 1.0),
                ("throttle", "Throttle", "%", 0.01),
                ("thrust", "Pull (kg)", "kgf", G0),
                ("rpm", "Motor RPM", "RPM", 1.0),
                ("current", "Motor Current (A)", "A", 1.0),
            ],
            [0.0, 100.0],
            "values: 0..100 (%)",
        ),
    );
    // A lab rig: units in brackets, a bare `Signal` in µs, a drag force logged left of the
    // thrust, the rotor's speed in rad/s.
    c.add(
        "signal_drag_force_rotor_speed",
        PLAIN,
        &[
            col("Time [s]", t_s),
            col("Signal [us]", us),
            col("Force [N]", |_, s| num(0.1 * s.thrust_n, 4)),
            col("Thrust [N]", n),
            col("Rotor speed [rad/s]", |_, s| {
                num(s.rpm * std::f64::consts::TAU / 60.0, 3)
            }),
        ],
        expect(
            &[
                ("throttle", "Signal [us]", "µs", 1e-3),
                ("thrust", "Thrust [N]", "N", 1.0),
                (
                    "rpm",
                    "Rotor speed [rad/s]",
                    "rad/s",
                    60.0 / std::f64::consts::TAU,
                ),
            ],
            US_RANGE.0,
            US_RANGE.1,
        ),
    );
    // A script's log: a dimensionless `cmd [-]` in 0..1, `Lift` in grams.
    c.add(
        "dimensionless_cmd_lift",
        PLAIN,
        &[
            col("t [s]", t_s),
            col("cmd [-]", |_, s| num(s.u, 3)),
            col("Lift (g)", |_, s| num(s.thrust_n / G0 * 1e3, 2)),
        ],
        expect(
            &[
                ("throttle", "cmd [-]", "0..1", 1.0),
                ("thrust", "Lift (g)", "gf", G0 / 1e3),
            ],
            [0.0, 1.0],
            "values: 0..1",
        ),
    );
    // Fractions under a `%` header: refused naming the fraction's range, read with it.
    c.add(
        "fractions_under_percent_header",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("Throttle (%)", |_, s| num(s.u, 2)),
            col("Thrust (N)", n),
        ],
        Expect {
            args: vec!["--input-range", "0,1"],
            refused_without_args: Some(vec!["--input-range 0,1", "fractions"]),
            ..expect(
                &[("thrust", "Thrust (N)", "N", 1.0)],
                [0.0, 1.0],
                "--input-range",
            )
        },
    );
    // Duty cycle in percent, thrust in millinewtons.
    c.add(
        "duty_cycle_millinewtons",
        PLAIN,
        &[
            col("Time (s)", t_s),
            col("Duty cycle (%)", pct),
            col("Thrust (mN)", |_, s| num(1e3 * s.thrust_n, 1)),
        ],
        expect(
            &[
                ("throttle", "Duty cycle (%)", "%", 0.01),
                ("thrust", "Thrust (mN)", "mN", 1e-3),
            ],
            PCT_RANGE.0,
            PCT_RANGE.1,
        ),
    );
    // A German lab bench: its words, units in brackets, speed in 1/min.
    c.add(
        "german_bench_words",
        PLAIN,
        &[
            col("Zeit [s]", t_s),
            col("Gas [%]", pct),
            col("Schub [g]", gf),
            col("Drehzahl [1/min]", |_, s| num(s.rpm, 0)),
            col("Spannung [V]", |_, s| num(s.voltage_v, 3)),
            col("Strom [A]", |_, s| num(s.current_a, 3)),
        ],
        expect(
            &[
                ("time", "Zeit [s]", "s", 1.0),
                ("throttle", "Gas [%]", "%", 0.01),
                ("thrust", "Schub [g]", "gf", G0 / 1e3),
                ("rpm", "Drehzahl [1/min]", "RPM", 1.0),
                ("current", "Strom [A]", "A", 1.0),
            ],
            PCT_RANGE.0,
            PCT_RANGE.1,
        ),
    );
    // A script's snake_case log: a qualified command with no unit (its values decide), a
    // `load_cell` in newtons, an elapsed time; and a table's `quantity / unit` force `F / N`
    // beside an ESC's `esc_pwm_us`.
    c.add(
        "snake_case_motor_cmd_load_cell",
        PLAIN,
        &[
            col("elapsed_s", t_s),
            col("motor_cmd", |_, s| num(s.u, 3)),
            col("load_cell_N", n),
        ],
        expect(
            &[
                ("time", "elapsed_s", "s", 1.0),
                ("throttle", "motor_cmd", "0..1", 1.0),
                ("thrust", "load_cell_N", "N", 1.0),
            ],
            [0.0, 1.0],
            "values: 0..1",
        ),
    );
    c.add(
        "quantity_over_unit_force_esc_pwm",
        PLAIN,
        &[col("t / s", t_s), col("esc_pwm_us", us), col("F / N", n)],
        expect(
            &[
                ("throttle", "esc_pwm_us", "µs", 1e-3),
                ("thrust", "F / N", "N", 1.0),
            ],
            US_RANGE.0,
            US_RANGE.1,
        ),
    );
    c.out
}
