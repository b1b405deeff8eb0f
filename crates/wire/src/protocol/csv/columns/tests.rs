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

/// Every name of the flat alias table this one replaced still maps as it did.
#[test]
fn the_former_aliases_keep_their_meaning() {
    use Quantity as Q;
    use Unit as U;
    let former = [
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
        ("motorelectricalspeed(rpm)", Q::Rpm, U::Rpm),
        ("voltage_v", Q::Voltage, U::Volt),
        ("voltage(v)", Q::Voltage, U::Volt),
        ("vbat(v)", Q::Voltage, U::Volt),
        ("current_a", Q::Current, U::Ampere),
        ("current(a)", Q::Current, U::Ampere),
    ];
    for (name, quantity, unit) in former {
        assert_eq!(lookup(name), Some(ColumnSpec { quantity, unit }), "{name}");
    }
}

#[test]
fn new_units_and_command_names_map() {
    use Quantity as Q;
    use Unit as U;
    let cases = [
        ("ESC signal", Q::Throttle, U::Command),
        ("pwm", Q::Throttle, U::Command),
        ("cmd", Q::Throttle, U::Command),
        ("DShot", Q::Throttle, U::DShot),
        ("throttle (0-1)", Q::Throttle, U::Fraction),
        ("Torque (N·mm)", Q::Torque, U::NewtonMillimetre),
        ("torque [ozf·in]", Q::Torque, U::OunceForceInch),
        ("Torque (oz-in)", Q::Torque, U::OunceForceInch),
        ("Thrust (ozf)", Q::Thrust, U::OunceForce),
        ("thrust_lbf", Q::Thrust, U::PoundForce),
        ("Motor Speed (rad/s)", Q::Rpm, U::RadianPerSecond),
        ("speed (Hz)", Q::Rpm, U::Hertz),
        ("Motor Electrical Speed (eRPM)", Q::Rpm, U::ElectricalRpm),
        ("Voltage (mV)", Q::Voltage, U::Millivolt),
        ("current_mA", Q::Current, U::Milliampere),
    ];
    for (name, quantity, unit) in cases {
        assert_eq!(lookup(name), Some(ColumnSpec { quantity, unit }), "{name}");
    }
    // Neither a unit of another quantity nor a word the table lacks.
    for name in [
        "Thrust (N·m)",
        "Torque (gf)",
        "m1_thrust",
        "m1_erpm",
        "thrust",
        "Vbat",
        "Servo 1 (µs)",
        "Electrical Power (W)",
        "90% settling time (s)",
        "vir_force_N",
    ] {
        assert_eq!(lookup(name), None, "{name}");
    }
}

#[test]
fn new_units_convert_to_si() {
    let o = ConvOptions {
        motor_poles: Some(14),
        ..ConvOptions::default()
    };
    let conv = |name: &str, raw: f64| lookup(name).unwrap().conversion(&o).unwrap().apply(raw);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
    assert!(close(conv("Torque (N·mm)", 12.5), 0.0125));
    assert!(close(conv("Torque (ozf·in)", 1.0), 0.007_061_551_814_8));
    assert!(close(conv("Thrust (ozf)", 16.0), LBF_N));
    assert!(close(conv("Thrust (lbf)", 1.0), 4.448_221_615_260_5));
    assert!(close(conv("Thrust (kgf)", 1.0), 9.80665));
    assert!(close(conv("speed (rad/s)", std::f64::consts::TAU), 60.0));
    assert!(close(conv("speed (Hz)", 50.0), 3000.0));
    assert!(close(conv("speed (eRPM)", 7000.0), 1000.0));
    assert!(close(conv("Voltage (mV)", 16_800.0), 16.8));
    assert!(close(conv("current_mA", 250.0), 0.25));
    assert!(close(conv("dshot", 48.0), 0.0) && close(conv("dshot", 2047.0), 1.0));
    let cmd = lookup("ESC signal").unwrap();
    assert_eq!(cmd.conversion(&o), Err(ConvError::NeedsRange));
}

#[test]
fn small_stands_units_read_and_convert() {
    use Quantity as Q;
    use Unit as U;
    // Small motors' stands write torque in kgf·cm, gf·cm, mN·m or N·cm, thrust in mN, speed in
    // kRPM or rev/s, and a dot of any kind (`N•m`, `N∙m`, `N-m`) in the unit.
    let cases = [
        ("Thrust (mN)", Q::Thrust, U::Millinewton, 250.0, 0.25),
        (
            "Torque (kgf·cm)",
            Q::Torque,
            U::KilogramForceCentimetre,
            1.0,
            0.0980665,
        ),
        (
            "torque_kg-cm",
            Q::Torque,
            U::KilogramForceCentimetre,
            10.0,
            0.980665,
        ),
        (
            "Torque (gf.cm)",
            Q::Torque,
            U::GramForceCentimetre,
            1000.0,
            0.0980665,
        ),
        (
            "Torque [g-cm]",
            Q::Torque,
            U::GramForceCentimetre,
            100.0,
            0.00980665,
        ),
        ("Torque (mN·m)", Q::Torque, U::MillinewtonMetre, 12.0, 0.012),
        ("Torque (N·cm)", Q::Torque, U::NewtonCentimetre, 5.0, 0.05),
        ("Torque (N•m)", Q::Torque, U::NewtonMetre, 0.2, 0.2),
        ("Torque (N∙m)", Q::Torque, U::NewtonMetre, 0.2, 0.2),
        ("torque_N-m", Q::Torque, U::NewtonMetre, 0.2, 0.2),
        ("Speed (kRPM)", Q::Rpm, U::KiloRpm, 12.5, 12_500.0),
        ("speed (rps)", Q::Rpm, U::Hertz, 100.0, 6000.0),
        ("Speed (rev/s)", Q::Rpm, U::Hertz, 100.0, 6000.0),
        ("time (sec)", Q::Time, U::Second, 1.5, 1.5),
    ];
    let o = ConvOptions::default();
    for (name, quantity, unit, raw, si) in cases {
        let spec = lookup(name);
        assert_eq!(spec, Some(ColumnSpec { quantity, unit }), "{name}");
        let got = spec.unwrap().conversion(&o).unwrap().apply(raw);
        assert!(
            (got - si).abs() <= 1e-12 * si.abs(),
            "{name}: {got} against {si}"
        );
    }
    for name in ["Thrust (kgf·cm)", "Torque (mN)", "Speed (kgf)"] {
        assert_eq!(lookup(name), None, "{name}");
    }
}

#[test]
fn command_scales_are_declared_by_a_unit_or_left_to_the_values() {
    let scales = |name: &str| lookup(name).unwrap().unit.command_scales();
    assert_eq!(
        scales("ESC signal (µs)"),
        Some(CommandScales::Declared(Scale::ESC_US))
    );
    assert_eq!(
        scales("throttle (%)"),
        Some(CommandScales::Declared(Scale::PERCENT))
    );
    assert_eq!(scales("dshot"), Some(CommandScales::Declared(Scale::DSHOT)));
    let Some(CommandScales::FromValues(bare)) = scales("ESC signal") else {
        panic!("a bare command is decided from its values");
    };
    assert!(bare.contains(&Scale::RAW_ESC) && !bare.contains(&Scale::TSP1_LEVEL));
    let Some(CommandScales::FromValues(thr)) = scales("throttle") else {
        panic!("a file's `throttle` is decided from its values");
    };
    assert!(thr.contains(&Scale::TSP1_LEVEL) && thr.contains(&Scale::FRACTION));
    assert_eq!(scales("Thrust (N)"), None);
    assert_eq!(Scale::ESC_US.affine().apply(1500.0), 0.5);
}

#[test]
fn unitless_quantities_units_rows_and_clock_names() {
    assert_eq!(unitless("Thrust"), Some(Quantity::Thrust));
    assert_eq!(unitless(" torque "), Some(Quantity::Torque));
    // A name whose unit is said, or is the name itself, is not unitless.
    assert_eq!(unitless("Thrust (gf)"), None);
    assert_eq!(unitless("rpm"), None);
    assert_eq!(unitless("Motor"), None);
    assert_eq!(units_of(Quantity::Thrust), "N, mN, gf, kgf, lbf, ozf");
    for u in ["s", "%", "gf", "N·mm", "[rad/s]", "(µs)", "mA"] {
        assert!(is_unit(u), "{u}");
    }
    for u in ["", "-", "Thrust", "1.5"] {
        assert!(!is_unit(u), "{u}");
    }
    let spec = |q, u| {
        Some(ColumnSpec {
            quantity: q,
            unit: u,
        })
    };
    assert_eq!(lookup("Timestamp"), spec(Quantity::Time, Unit::Clock));
    assert_eq!(
        lookup("Torque (lbf·in)"),
        spec(Quantity::Torque, Unit::PoundForceInch)
    );
    assert_eq!(
        lookup("vbatLatest (V)"),
        spec(Quantity::Voltage, Unit::Volt)
    );
    let lbf_ft = lookup("torque_lbf-ft")
        .unwrap()
        .conversion(&ConvOptions::default());
    assert!((lbf_ft.unwrap().factor() - 1.355_817_948).abs() < 1e-8);
}

/// The names of RCbenchmark / Tyto Series 1580/1585 exports (`Time (s),ESC signal (µs),Servo 1
/// (µs),…,Torque (N·m),Thrust (gf),Voltage (V),Current (A),Motor Electrical Speed (RPM),Motor
/// Optical Speed (RPM),Electrical Power (W),…,App message`), other benches' load cells and
/// commands, and a unit in double quotes.
#[test]
fn stand_export_names_and_load_cells_map_to_quantities() {
    let spec = |quantity, unit| Some(ColumnSpec { quantity, unit });
    let (q, u) = (Quantity::Thrust, Unit::GramForce);
    for name in [
        "Load (g)",
        "Load cell (g)",
        "Load Cell [gf]",
        "loadcell_g",
        "Thrust \"gf\"",
    ] {
        assert_eq!(lookup(name), spec(q, u), "{name}");
    }
    let cases = [
        ("Thrust (kgf)", Quantity::Thrust, Unit::KilogramForce),
        ("Load (kg)", Quantity::Thrust, Unit::KilogramForce),
        ("Load cell (N)", Quantity::Thrust, Unit::Newton),
        ("Torque (N·m)", Quantity::Torque, Unit::NewtonMetre),
        ("Torque (in-oz)", Quantity::Torque, Unit::OunceForceInch),
        ("Motor Optical Speed (RPM)", Quantity::Rpm, Unit::Rpm),
        ("Motor Electrical Speed (RPM)", Quantity::Rpm, Unit::Rpm),
        ("Voltage (V)", Quantity::Voltage, Unit::Volt),
        ("Current (A)", Quantity::Current, Unit::Ampere),
        (
            "ESC signal (µs)",
            Quantity::Throttle,
            Unit::PulseMicrosecond,
        ),
        (
            "ESC signal (μs)",
            Quantity::Throttle,
            Unit::PulseMicrosecond,
        ),
        ("Throttle (%)", Quantity::Throttle, Unit::Percent),
        ("PWM (us)", Quantity::Throttle, Unit::PulseMicrosecond),
        ("PWM (µs)", Quantity::Throttle, Unit::PulseMicrosecond),
    ];
    for (name, q, u) in cases {
        assert_eq!(lookup(name), spec(q, u), "{name}");
    }
    // A load without a force unit is no thrust; the other columns of those exports map to
    // nothing; a unit with a stray inch mark is not guessed.
    for other in [
        "Load (%)",
        "Electrical Power (W)",
        "Motor Efficiency (%)",
        "Vibration (g)",
        "App message",
        "Torque (in-oz\")",
        "Thrust \"gf",
    ] {
        assert_eq!(lookup(other), None, "{other}");
    }
    // A bare `Load` is a thrust of unknown unit (refused naming --columns, never guessed).
    assert_eq!(unitless("Load"), Some(Quantity::Thrust));
    assert_eq!(unitless("Load cell"), Some(Quantity::Thrust));
}

#[test]
fn a_motors_index_clocks_and_forces_are_read() {
    let spec = |quantity, unit| Some(ColumnSpec { quantity, unit });
    let cases = [
        ("Motor 1 Thrust (N)", Quantity::Thrust, Unit::Newton),
        ("m2_thrust_g", Quantity::Thrust, Unit::GramForce),
        ("Thrust 2 (N)", Quantity::Thrust, Unit::Newton),
        ("thrust_3 (kgf)", Quantity::Thrust, Unit::KilogramForce),
        (
            "Motor 1 ESC (µs)",
            Quantity::Throttle,
            Unit::PulseMicrosecond,
        ),
        ("ESC 1 (µs)", Quantity::Throttle, Unit::PulseMicrosecond),
        ("Force (N)", Quantity::Thrust, Unit::Newton),
        ("millis", Quantity::Time, Unit::Millisecond),
        ("micros", Quantity::Time, Unit::Microsecond),
        ("Time (min)", Quantity::Time, Unit::Minute),
    ];
    for (name, q, u) in cases {
        assert_eq!(lookup(name), spec(q, u), "{name}");
    }
    // An axis is no index; a word with digits inside is not a motor's.
    for other in ["Force X (N)", "Fz (N)", "motor (%)", "m_thrust_x (N)"] {
        assert_eq!(lookup(other), None, "{other}");
    }
    assert_eq!(
        lookup("Motor Optical Speed (RPM)"),
        spec(Quantity::Rpm, Unit::Rpm)
    );
    // One sensor in two units; one sensor for each of two motors; two words.
    assert_eq!(sensor_word("Thrust (kgf)"), sensor_word("Thrust (N)"));
    assert!(!indexed_alike("Thrust (kgf)", "Thrust (N)"));
    assert!(indexed_alike("Motor 1 Thrust (N)", "Motor 2 Thrust (N)"));
    assert!(indexed_alike("m1_thrust_g", "m2_thrust_g"));
    assert!(indexed_alike("Thrust 1 (N)", "Thrust 2 (N)"));
    assert!(!indexed_alike("Thrust (N)", "Force (N)"));
    assert!(!indexed_alike("Motor 1 Thrust (N)", "Motor 1 Thrust (gf)"));
    assert_eq!(unitless("Motor 1 Thrust"), Some(Quantity::Thrust));
}

/// Names other benches give: a qualifier before a quantity's word, small stands' words for
/// the load cell and the command, unit spellings; and the qualifiers that make a column no
/// reading, or whose word cannot be told from the spaces a normalised name has lost.
#[test]
fn qualified_and_small_stands_names_map_and_set_points_do_not() {
    let spec = |quantity, unit| Some(ColumnSpec { quantity, unit });
    let cases = [
        ("Motor Thrust (N)", Quantity::Thrust, Unit::Newton),
        ("Pull (kg)", Quantity::Thrust, Unit::KilogramForce),
        ("lift_g", Quantity::Thrust, Unit::GramForce),
        ("Thrust (grams)", Quantity::Thrust, Unit::GramForce),
        ("Motor RPM", Quantity::Rpm, Unit::Rpm),
        ("motor_rpm", Quantity::Rpm, Unit::Rpm),
        ("ESC eRPM", Quantity::Rpm, Unit::ElectricalRpm),
        ("motor_erpm", Quantity::Rpm, Unit::ElectricalRpm),
        ("RPM (optical)", Quantity::Rpm, Unit::Rpm),
        ("Rotor speed [rad/s]", Quantity::Rpm, Unit::RadianPerSecond),
        ("omega (rad/sec)", Quantity::Rpm, Unit::RadianPerSecond),
        ("Speed (r/min)", Quantity::Rpm, Unit::Rpm),
        ("Battery Voltage (V)", Quantity::Voltage, Unit::Volt),
        ("Battery (V)", Quantity::Voltage, Unit::Volt),
        ("Volts", Quantity::Voltage, Unit::Volt),
        ("Motor Current (A)", Quantity::Current, Unit::Ampere),
        ("Amps", Quantity::Current, Unit::Ampere),
        ("Elapsed Time (s)", Quantity::Time, Unit::Second),
        ("Timestamp (ms)", Quantity::Time, Unit::Millisecond),
        ("time (seconds)", Quantity::Time, Unit::Second),
        ("Signal [us]", Quantity::Throttle, Unit::PulseMicrosecond),
        ("Input (%)", Quantity::Throttle, Unit::Percent),
        ("Duty cycle", Quantity::Throttle, Unit::Command),
        ("Duty cycle (%)", Quantity::Throttle, Unit::Percent),
        ("cmd [-]", Quantity::Throttle, Unit::Command),
        ("Throttle (0-100)", Quantity::Throttle, Unit::Percent),
        ("ESC Throttle (%)", Quantity::Throttle, Unit::Percent),
        ("Target Throttle (%)", Quantity::Throttle, Unit::Percent),
        ("t / s", Quantity::Time, Unit::Second),
        ("Thrust / N", Quantity::Thrust, Unit::Newton),
        ("omega / rad/s", Quantity::Rpm, Unit::RadianPerSecond),
        ("Throttle/%", Quantity::Throttle, Unit::Percent),
        ("throttle_setpoint_pct", Quantity::Throttle, Unit::Percent),
        ("Terminal Voltage (V)", Quantity::Voltage, Unit::Volt),
        (
            "ESC command (µs)",
            Quantity::Throttle,
            Unit::PulseMicrosecond,
        ),
        ("Throttle command (%)", Quantity::Throttle, Unit::Percent),
        // A qualified command without a unit: its scale from its values.
        ("motor_cmd", Quantity::Throttle, Unit::Command),
        ("Motor Command", Quantity::Throttle, Unit::Command),
        ("esc_pwm", Quantity::Throttle, Unit::Command),
        ("esc_pwm_us", Quantity::Throttle, Unit::PulseMicrosecond),
        // Words joined by `_`, a time named by its unit, a German bench's names.
        ("load_cell_N", Quantity::Thrust, Unit::Newton),
        ("motor_speed_rpm", Quantity::Rpm, Unit::Rpm),
        ("sec", Quantity::Time, Unit::Second),
        ("ms", Quantity::Time, Unit::Millisecond),
        ("Zeit [s]", Quantity::Time, Unit::Second),
        ("Gas [%]", Quantity::Throttle, Unit::Percent),
        ("Schub [g]", Quantity::Thrust, Unit::GramForce),
        ("Kraft (N)", Quantity::Thrust, Unit::Newton),
        ("Drehmoment [Nm]", Quantity::Torque, Unit::NewtonMetre),
        ("Drehzahl [1/min]", Quantity::Rpm, Unit::Rpm),
        ("Spannung [V]", Quantity::Voltage, Unit::Volt),
        ("Strom [A]", Quantity::Current, Unit::Ampere),
        ("F / N", Quantity::Thrust, Unit::Newton),
        ("Motor 1 RPM", Quantity::Rpm, Unit::Rpm),
        ("esc2_erpm", Quantity::Rpm, Unit::ElectricalRpm),
        ("F (gf)", Quantity::Thrust, Unit::GramForce),
        // A command qualified as a motor's input, thrust by its symbol `T` with a force unit,
        // a Unix time stamp, a hobby load cell's column named by its unit.
        ("Motor input (%)", Quantity::Throttle, Unit::Percent),
        ("T (N)", Quantity::Thrust, Unit::Newton),
        ("T_g", Quantity::Thrust, Unit::GramForce),
        ("T [kgf]", Quantity::Thrust, Unit::KilogramForce),
        ("t_ms", Quantity::Time, Unit::Millisecond),
        ("unix_time", Quantity::Time, Unit::Second),
        ("epoch_ms", Quantity::Time, Unit::Millisecond),
        ("unix_time_ms", Quantity::Time, Unit::Millisecond),
        ("grams", Quantity::Thrust, Unit::GramForce),
    ];
    for (name, q, u) in cases {
        assert_eq!(lookup(name), spec(q, u), "{name}");
    }
    for other in [
        // Set-points, limits and figures computed from the readings.
        "Target RPM",
        "Target Speed (RPM)",
        "Max Current (A)",
        "Rise Time (s)",
        "Thrust Setpoint (N)",
        // `blad` + `eRPM` or `blade` + `RPM`: not guessed.
        "Blade RPM",
        "Average RPM",
        // A quantity's word with a unit of another.
        "Input (V)",
        "Pull (%)",
        "Wind speed (m/s)",
        // An axis, a word after the quantity's, a force that is no load cell's.
        "Thrust X (N)",
        "Drag Force (N)",
        "Thrust error (N)",
        "Thrust/Weight",
        "Thrust setpoint (N)",
        "Motor max current (A)",
        "motor_target_rpm",
        "Settling Time (s)",
        "speed_target_rpm",
        "Thrust/Power (g/W)",
        // No command's word at the end; a letter other than `t` and `F`, `F` with no force unit.
        "motor_temp",
        "u / %",
        "f (Hz)",
        "T (V)",
        "Analog input (V)",
    ] {
        assert_eq!(lookup(other), None, "{other}");
    }
    assert_eq!(unitless("Motor Thrust"), Some(Quantity::Thrust));
    assert_eq!(unitless("Pull"), Some(Quantity::Thrust));
    assert_eq!(unitless("Schub"), Some(Quantity::Thrust));
    assert_eq!(unitless("load_cell"), Some(Quantity::Thrust));
}
