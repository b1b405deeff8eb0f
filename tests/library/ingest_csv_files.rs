//! CSV file reader: §6 files, exported stand logs, benchmark files, and malformed variants (a
//! wrong checksum, a missing column, text in a number field, an empty file), each a clear error
//! or a counted, skipped row.

use propid_ingest::csv_file::{read_csv, CsvFileError, CsvFileOptions, InputChoice};
use propid_numerics::outliers::is_reading;
use propid_wire::protocol::csv::checksum;

fn with_checksum(line: &str) -> String {
    format!("{line}*{:02X}", checksum(line.as_bytes()))
}

fn opts() -> CsvFileOptions {
    CsvFileOptions::default()
}

#[test]
fn protocol_csv_with_checksums_comments_and_a_bad_row() {
    let mut text = String::from("# stand v1\nt_us,throttle,thrust_N\n");
    for k in 0..20 {
        let line = format!(
            "{},{},{}",
            k * 1000,
            3000 + (k % 2) * 100,
            1.0 + 0.01 * k as f64
        );
        text.push_str(&with_checksum(&line));
        text.push('\n');
    }
    text.push_str("20000,3000,1.2*00\n"); // wrong checksum
    text.push_str("21000,abc,1.2\n"); // text in a number field
    text.push_str("22000,3000\n"); // too few fields
    text.push_str("#ACK THR OK 5\n");
    let f = read_csv(&text, &opts()).unwrap();
    assert_eq!(f.source.rows, 20);
    assert_eq!(f.source.skipped.bad_checksum, 1);
    assert_eq!(f.source.skipped.not_a_number, 1);
    assert_eq!(f.source.skipped.short_row, 1);
    assert_eq!(f.source.comments, 2);
    assert!((f.record.dt_s - 1e-3).abs() < 1e-12);
    let thr = f.record.channel("throttle").unwrap();
    assert_eq!(thr.data[1], 0.31);
    assert_eq!(f.input.as_deref(), Some("throttle"));
    assert_eq!(f.outputs, vec!["thrust_N".to_string()]);
}

#[test]
fn exported_log_with_bom_units_and_long_header() {
    let mut text = String::from(
        "\u{feff}Time (s),ESC signal (µs),Servo 1 (µs),Torque (N·m),Thrust (gf),Voltage (V),\
         Current (A),Motor Electrical Speed (RPM),Motor Optical Speed (RPM),Electrical Power (W),\
         Mechanical Power (W),Motor Efficiency (%),Propeller Mech. Efficiency (gf/W),App message\n",
    );
    for k in 0..30 {
        text.push_str(&format!(
            "{},{},,0.01,{},16.8,1.0,{},0,16,0,0,0,{}\n",
            0.02 * k as f64,
            1150 + 10 * (k / 10),
            100.0 + k as f64,
            5000 + k,
            if k == 3 { "step done" } else { "" }
        ));
    }
    let f = read_csv(&text, &opts()).unwrap();
    assert_eq!(
        f.source.rows, 30,
        "text in an unused column is not an error"
    );
    assert_eq!(f.source.input.as_deref(), Some("ESC signal (µs)"));
    assert_eq!(f.source.outputs, vec!["Thrust (gf)".to_string()]);
    let thrust = &f.record.channel("thrust_N").unwrap().data;
    assert!((thrust[0] - 0.1 * 9.80665).abs() < 1e-12, "gf to N");
    let thr = &f.record.channel("throttle").unwrap().data;
    assert!(
        (thr[0] - 0.15).abs() < 1e-12,
        "µs to fraction with 1000..2000"
    );
    // Choose other columns by their names as written, or by canonical names.
    let o = CsvFileOptions {
        outputs: vec!["Motor Electrical Speed (RPM)".into(), "torque_Nm".into()],
        ..opts()
    };
    let f = read_csv(&text, &o).unwrap();
    assert_eq!(f.outputs, vec!["rpm".to_string(), "torque_Nm".to_string()]);
}

#[test]
fn kilogram_force_and_grams_are_converted() {
    let text = "t_s,throttle_pct,thrust_kgf\n0,10,0.5\n0.01,20,0.6\n0.02,20,0.7\n";
    let f = read_csv(text, &opts()).unwrap();
    let thrust = &f.record.channel("thrust_N").unwrap().data;
    assert!((thrust[0] - 0.5 * 9.80665).abs() < 1e-12);
    assert_eq!(f.record.channel("throttle").unwrap().data[1], 0.2);
}

#[test]
fn no_time_column_needs_fs() {
    let text = "throttle,thrust_N\n1000,1\n2000,2\n3000,3\n";
    assert_eq!(read_csv(text, &opts()), Err(CsvFileError::NeedRate));
    let o = CsvFileOptions {
        fs_hz: Some(50.0),
        ..opts()
    };
    let f = read_csv(text, &o).unwrap();
    assert_eq!(f.record.dt_s, 0.02);
    assert_eq!(f.source.rate_from, "--fs");
}

#[test]
fn irregular_timestamps_are_resampled_and_jitter_reported() {
    let mut text = String::from("t_ms,throttle,thrust_N\n");
    let mut t = 0.0;
    for k in 0..60 {
        t += [12.0, 20.0, 28.0][k % 3];
        text.push_str(&format!("{t},{},{}\n", 3000 + 10 * k, 0.5 * t / 1000.0));
    }
    let f = read_csv(&text, &opts()).unwrap();
    let j = f.source.jitter.as_ref().unwrap();
    assert!(j.resampled);
    assert!((j.dt_s - 0.02).abs() < 1e-12);
    assert!((j.max_dt_s - 0.028).abs() < 1e-9);
    assert!(j.rms_jitter_s > 0.006);
    let thrust = &f.record.channel("thrust_N").unwrap().data;
    for (k, v) in thrust.iter().enumerate() {
        let tk = f.record.t0_s + k as f64 * f.record.dt_s;
        assert!((v - 0.5 * tk).abs() < 1e-9, "linear data stays linear");
    }
}

#[test]
fn missing_column_names_what_is_there() {
    let text = "t_s,throttle,torque_Nm\n0,1,2\n0.1,1,2\n0.2,1,2\n";
    match read_csv(text, &opts()) {
        Err(CsvFileError::MissingColumn {
            what, available, ..
        }) => {
            assert_eq!(what, "output");
            assert!(available.contains("torque_Nm"), "{available}");
        }
        other => panic!("{other:?}"),
    }
    let o = CsvFileOptions {
        input: InputChoice::Column("nope".into()),
        outputs: vec!["torque_Nm".into()],
        ..opts()
    };
    assert!(matches!(
        read_csv(text, &o),
        Err(CsvFileError::MissingColumn { what: "input", .. })
    ));
}

#[test]
fn empty_files_are_errors() {
    assert_eq!(read_csv("", &opts()), Err(CsvFileError::Empty));
    assert_eq!(
        read_csv("# only a comment\n\n", &opts()),
        Err(CsvFileError::Empty)
    );
    assert_eq!(
        read_csv("t_s,throttle,thrust_N\n", &opts()),
        Err(CsvFileError::Empty)
    );
    // Rows whose needed cells are no numbers: the error says which cell first.
    let e = read_csv("t_s,throttle,thrust_N\n0,1,x\n0.1,1,y\n", &opts()).unwrap_err();
    assert!(matches!(e, CsvFileError::TooFewRows { rows: 0, .. }), "{e}");
    assert!(
        e.to_string().ends_with(
            ": 2 row(s) with a cell that is no number, the first \"x\" in thrust_N (data row 1)"
        ),
        "{e}"
    );
}

#[test]
fn headerless_files_are_refused_unless_their_columns_are_named() {
    let text = "0,1000,1.0\n1000,1000,1.1\n2000,1500,1.2\n";
    let e = read_csv(text, &opts()).unwrap_err();
    assert_eq!(e, CsvFileError::NoHeader { fields: 3 });
    assert!(e.to_string().contains("--columns"), "{e}");
    let two = "0.0,0.797\n0.02,0.797\n0.04,0.796\n";
    let named = CsvFileOptions {
        columns: Some(vec!["t_s".into(), "load_kg".into()]),
        outputs: vec!["load_kg".into()],
        ..opts()
    };
    // Named, but without a command column: the caller must say there is no input.
    assert!(matches!(
        read_csv(two, &named),
        Err(CsvFileError::NoCommand { .. })
    ));
    let o = CsvFileOptions {
        input: InputChoice::None,
        ..named
    };
    let f = read_csv(two, &o).unwrap();
    assert_eq!(f.input, None, "no input column: response only");
    // `load_kg` is a load cell in kilogram-force: the thrust, in newtons.
    let thrust = f
        .record
        .channel(propid_wire::record::names::THRUST)
        .unwrap();
    assert!((thrust.data[2] - 0.796 * 9.80665).abs() < 1e-12);
    assert!(!f.source.header);
    // Tab separated, quoted names, trailing empty column.
    let tabs = "\"V1\"\t\"V2\"\t\n0.1\t0.2\t\n0.3\t0.4\t\n";
    let o = CsvFileOptions {
        input: InputChoice::Column("V1".into()),
        outputs: vec!["V2".into()],
        fs_hz: Some(610.35),
        ..opts()
    };
    let f = read_csv(tabs, &o).unwrap();
    assert_eq!(f.record.channel("V2").unwrap().data, vec![0.2, 0.4]);
}

#[test]
fn a_dropped_reading_is_missing_in_its_channel_only() {
    let mut text = String::from("t_s,throttle,thrust_N,voltage_V\n");
    for k in 0..20 {
        let thrust = if k == 1 { String::new() } else { k.to_string() };
        let volt = if k == 2 { "" } else { "12" };
        text.push_str(&format!("{},0.4,{thrust},{volt}\n", 0.01 * k as f64));
    }
    let o = CsvFileOptions {
        optional: vec!["voltage_V".into()],
        ..opts()
    };
    let f = read_csv(&text, &o).unwrap();
    assert_eq!(f.record.missing_count(), 1);
    assert!(f.record.missing[1]);
    assert!(f.record.channel("thrust_N").unwrap().data[1].is_nan());
    assert_eq!(
        f.record.channel("throttle").unwrap().data[1],
        0.4,
        "the row stays"
    );
    let v = &f.record.channel("voltage_V").unwrap().data;
    assert!(
        v[2].is_nan(),
        "a reading beside the outputs keeps its own gap"
    );
    assert_eq!(v[3], 12.0);
    assert!(!f.record.missing[2], "and does not make the sample missing");
    assert_eq!(f.optional, vec!["voltage_V".to_string()]);
    assert_eq!(f.source.channels["thrust"].missing, 1);
}

#[test]
fn missing_markers_are_empty_cells_not_unreadable_rows() {
    // A load cell that did not report is written `N/A`, `-` or `NULL` (the first data row
    // already has one): each is a missing value of its channel, the row and the command stay.
    let mut text = String::from("Time (s),ESC signal (µs),Thrust (gf),Voltage (V)\n");
    for k in 0..40 {
        let thrust = match k % 4 {
            0 => format!("{}", 100 + k),
            1 => "N/A".into(),
            2 => "-".into(),
            _ => "NULL".into(),
        };
        let volt = if k % 2 == 0 { "16.0" } else { "nan" };
        text.push_str(&format!("{},1400,{thrust},{volt}\n", 0.01 * k as f64));
    }
    let o = CsvFileOptions {
        optional: vec!["voltage_V".into()],
        ..opts()
    };
    let f = read_csv(&text, &o).unwrap();
    assert_eq!(f.record.len(), 40);
    assert_eq!(f.source.skipped.total(), 0);
    assert!(f.source.header);
    let c = &f.source.channels["thrust"];
    assert_eq!(c.values, 10, "{c:?}");
    let y = &f.record.channel("thrust_N").unwrap().data;
    assert!(
        (y[2] - 102.0 * 9.80665e-3).abs() < 1e-9,
        "interpolated: {}",
        y[2]
    );
    assert_eq!(f.source.channels["voltage"].values, 20);
}

#[test]
fn a_command_logged_on_its_changes_holds_until_the_next() {
    // The throttle written only on the rows where it changes (every 50 rows), the thrust on
    // every row: the command is a staircase held to the end, not ramps between its changes.
    let mut text = String::from("Time (s),Throttle (%),Thrust (gf)\n");
    for k in 0..200 {
        let level = [20, 40, 60, 30][k / 50];
        let cmd = if k % 50 == 0 {
            level.to_string()
        } else {
            String::new()
        };
        text.push_str(&format!("{},{cmd},{}\n", 0.01 * k as f64, 10 * level));
    }
    let f = read_csv(&text, &opts()).unwrap();
    let u = &f.record.channel("throttle").unwrap().data;
    for (k, &v) in u.iter().enumerate() {
        assert_eq!(v, [0.2, 0.4, 0.6, 0.3][k / 50], "{k}");
    }
    assert_eq!(f.record.missing_count(), 0);
    assert_eq!(f.source.channels["throttle"].command_held, 196);
    assert_eq!(f.source.channels["thrust"].command_held, 0);
}

#[test]
fn a_load_cell_repeating_its_last_reading_is_marked_read_at_its_runs_starts() {
    // The thrust written on every row as its last reading, a new one every 10 rows: the record
    // marks every repeat as interpolated, every run's first row as a reading.
    let mut text = String::from("Time (s),Throttle (%),Thrust (N)\n");
    for k in 0..400 {
        let reading = 1.0 + 0.1 * ((k / 10) % 7) as f64;
        text.push_str(&format!("{},50,{reading}\n", 0.01 * k as f64));
    }
    let f = read_csv(&text, &opts()).unwrap();
    assert_eq!(f.source.channels["thrust"].held_rows, Some(10));
    let ch = f.record.channel("thrust_N").unwrap();
    for k in 0..391 {
        assert_eq!(is_reading(&ch.interpolated, k), k % 10 == 0, "{k}");
    }
}

#[test]
fn sensors_at_their_own_rates_are_carried_not_dropped() {
    // A row for every command update (100 Hz); the load cell fills one row in five, the
    // current one in ten: the record keeps every row, each channel at its own rate.
    let mut text = String::from("Time (s),ESC signal (µs),Thrust (gf),Current (A)\n");
    for k in 0..200 {
        let t = 0.01 * k as f64;
        let thrust = if k % 5 == 2 {
            format!("{}", 100.0 + 50.0 * t)
        } else {
            String::new()
        };
        let amps = if k % 10 == 4 {
            format!("{}", 2.0 + t)
        } else {
            String::new()
        };
        text.push_str(&format!("{t},1400,{thrust},{amps}\n"));
    }
    let o = CsvFileOptions {
        optional: vec!["current_A".into()],
        ..opts()
    };
    let f = read_csv(&text, &o).unwrap();
    assert_eq!(f.record.len(), 200);
    let y = &f.record.channel("thrust_N").unwrap().data;
    for (k, v) in y.iter().enumerate().take(198).skip(2) {
        let t = 0.01 * k as f64;
        assert!(
            (v - (100.0 + 50.0 * t) * 9.80665e-3).abs() < 1e-9,
            "{k}: {v}"
        );
    }
    assert!(y[..2].iter().chain(&y[198..]).all(|v| v.is_nan()));
    assert_eq!(
        f.record.missing_count(),
        4,
        "only before the first and after the last reading"
    );
    let c = &f.source.channels["thrust"];
    assert_eq!(c.values, 40);
    assert!((c.own_dt_s.unwrap() - 0.05).abs() < 1e-9);
    assert_eq!(c.bridged, 196 - 40);
    let ch = f.record.channel("thrust_N").unwrap();
    for k in 2..198 {
        assert_eq!(
            is_reading(&ch.interpolated, k),
            k % 5 == 2,
            "{k}: the record says what was read"
        );
    }
    assert!(f
        .record
        .channel("throttle")
        .unwrap()
        .interpolated
        .is_empty());
    let a = &f.record.channel("current_A").unwrap().data;
    assert!((a[50] - 2.5).abs() < 1e-9, "{}", a[50]);
    let u = &f.source.units;
    assert_eq!(u["thrust"].unit, "gf");
    assert!((u["thrust"].factor - 0.00980665).abs() < 1e-15);
    assert_eq!(u["throttle"].zero, 1000.0);
}

#[test]
fn a_throttle_of_fractions_is_read_as_fractions() {
    let mut text = String::from("t_s,throttle,thrust_N\n");
    for k in 0..40 {
        let u = if k < 20 { 0.40 } else { 0.45 };
        text.push_str(&format!("{},{u},{}\n", 0.02 * k as f64, 3.0 * u));
    }
    let f = read_csv(&text, &opts()).unwrap();
    assert_eq!(f.record.channel("throttle").unwrap().data[30], 0.45);
    let r = f.source.input_range.as_ref().unwrap();
    assert_eq!(
        (r.raw_min, r.raw_max, r.from.as_str()),
        (0.0, 1.0, "values: 0..1")
    );
    // The same file with a §6 level in 0..10000 is read as one.
    let text = text.replace(",0.4,", ",4000,").replace(",0.45,", ",4500,");
    let f = read_csv(&text, &opts()).unwrap();
    assert_eq!(f.record.channel("throttle").unwrap().data[30], 0.45);
    // A command whose scale its values cannot decide is refused, naming the options.
    let text = text.replace(",4000,", ",1000,").replace(",4500,", ",2000,");
    let e = read_csv(&text, &opts()).unwrap_err();
    assert!(matches!(e, CsvFileError::CommandRange { .. }), "{e}");
    assert!(e.to_string().contains("--input-range MIN,MAX"), "{e}");
    let given = CsvFileOptions {
        input_range: Some((1000.0, 2000.0)),
        ..opts()
    };
    let f = read_csv(&text, &given).unwrap();
    assert_eq!(f.record.channel("throttle").unwrap().data[30], 1.0);
}

/// The real exported log (RCbenchmark/Tyto, no licence: read from ../shared/data only).
#[test]
fn real_tyto_export_from_shared_data() {
    let root = std::env::var_os("PROPID_SHARED_DATA")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let path = root.join("vanderploeg-rcbenchmark-steps/90PERCENT_2024-08-13_185523.csv");
    let Ok(text) = std::fs::read_to_string(&path) else {
        eprintln!(
            "skipped: {} is absent (vanderploeg-rcbenchmark-steps)",
            path.display()
        );
        return;
    };
    let f = read_csv(&text, &opts()).unwrap();
    assert_eq!(f.source.rows, 623);
    assert_eq!(f.source.skipped.total(), 0);
    let j = f.source.jitter.as_ref().unwrap();
    assert!((j.median_dt_s - 0.0223).abs() < 5e-4, "{j:?}");
    assert!(
        j.non_increasing >= 1,
        "the export starts with two rows at t = 0"
    );
}

#[test]
fn an_input_range_scales_an_input_the_table_does_not_know() {
    let text = "t_s,u8,thrust_N\n0,51,1\n0.01,102,2\n0.02,204,3\n";
    let o = CsvFileOptions {
        input: InputChoice::Column("u8".into()),
        ..opts()
    };
    // Whole numbers in no usual command range: a command's scale is not guessed.
    let e = read_csv(text, &o).unwrap_err();
    assert!(
        matches!(&e, CsvFileError::CommandRange { column, .. } if column == "u8"),
        "{e}"
    );
    assert!(e.to_string().contains("--input-range MIN,MAX"), "{e}");
    let o = CsvFileOptions {
        input_range: Some((0.0, 255.0)),
        ..o
    };
    let f = read_csv(text, &o).unwrap();
    assert_eq!(f.record.channel("u8").unwrap().data, vec![0.2, 0.4, 0.8]);
    let r = f.source.input_range.as_ref().unwrap();
    assert_eq!((r.raw_max, r.from.as_str()), (255.0, "--input-range"));
    assert_eq!(f.source.units["u8"].unit, "raw");
}

#[test]
fn an_input_of_unknown_unit_is_read_from_its_values_or_raw_when_a_signal() {
    let rows = |cell: fn(usize) -> String| -> String {
        let body: String = (0..40)
            .map(|k| format!("{},{},{}\n", 0.01 * k as f64, cell(k), k % 7))
            .collect();
        format!("t_s,setpoint,thrust_N\n{body}")
    };
    let o = CsvFileOptions {
        input: InputChoice::Column("setpoint".into()),
        ..opts()
    };
    // 30..70: percent, inferred and said.
    let f = read_csv(&rows(|k| (30 + k).to_string()), &o).unwrap();
    let r = f.source.input_range.as_ref().unwrap();
    assert_eq!((r.raw_max, r.from.as_str()), (100.0, "values: 0..100 (%)"));
    assert_eq!(f.record.channel("setpoint").unwrap().data[0], 0.3);
    assert_eq!(f.source.units["setpoint"].unit, "%");
    // A signed signal: as it is, factor 1, said.
    let f = read_csv(&rows(|k| format!("{}", k as f64 * 0.1 - 2.0)), &o).unwrap();
    let r = f.source.input_range.as_ref().unwrap();
    assert!(r.from.starts_with("raw"), "{}", r.from);
    assert_eq!(f.record.channel("setpoint").unwrap().data[0], -2.0);
    assert_eq!(
        (
            f.source.units["setpoint"].unit.as_str(),
            f.source.units["setpoint"].factor
        ),
        ("?", 1.0)
    );
}

#[test]
fn unix_time_stamps_are_read_by_their_size_and_a_counter_is_not_guessed() {
    let file = |stamp: &dyn Fn(usize) -> String| {
        let mut text = String::from("time,throttle (%),thrust (N)\n");
        for k in 0..400 {
            let level = if k < 200 { 30 } else { 60 };
            text.push_str(&format!("{},{level},{}\n", stamp(k), 0.1 * level as f64));
        }
        text
    };
    // Unix seconds with a fraction: s (Unix time), counted from the first stamp.
    let f = read_csv(
        &file(&|k| format!("{:.3}", 1_732_449_600.5 + 0.005 * k as f64)),
        &opts(),
    )
    .unwrap();
    let t = &f.source.units["time"];
    assert_eq!((t.unit.as_str(), t.factor), ("s (Unix time)", 1.0));
    assert_eq!(t.zero, 1_732_449_600.5);
    assert_eq!(f.record.t0_s, 0.0);
    assert!((f.record.dt_s - 0.005).abs() < 1e-6, "{}", f.record.dt_s);
    // Unix milliseconds, whole: exact to the millisecond once counted from the first.
    let f = read_csv(&file(&|k| (1_732_449_600_123 + 5 * k).to_string()), &opts()).unwrap();
    assert_eq!(f.source.units["time"].unit, "ms (Unix time)");
    assert!((f.record.dt_s - 0.005).abs() < 1e-15, "{}", f.record.dt_s);
    // Whole numbers near 10⁹ stepping by 5000: a µs counter 17 minutes after boot, or Unix
    // seconds logged every 83 minutes? Not guessed.
    let e = read_csv(&file(&|k| (1_000_000_000 + 5000 * k).to_string()), &opts()).unwrap_err();
    assert!(matches!(e, CsvFileError::UnitlessTime { .. }), "{e}");
}

#[test]
fn a_speed_column_without_a_sensor_gives_way_to_the_one_that_reads() {
    // An RCbenchmark export writes an electrical and an optical speed; a stand with only the
    // optical probe writes 0 in the electrical one on every row.
    let header = "Time (s),ESC signal (µs),Thrust (N),Motor Electrical Speed (RPM),\
                  Motor Optical Speed (RPM),Voltage (V)\n";
    let table = |electrical: bool, optical: bool, volts: &str| {
        let mut text = String::from(header);
        for k in 0..100 {
            let rpm = 5000 + 10 * k;
            let e = if electrical { rpm } else { 0 };
            let o = if optical { rpm } else { 0 };
            text.push_str(&format!("{},1400,1.5,{e},{o},{volts}\n", 0.01 * k as f64));
        }
        text
    };
    let o = CsvFileOptions {
        optional: vec!["rpm".into(), "voltage_V".into()],
        ..opts()
    };
    let f = read_csv(&table(false, true, "16.1"), &o).unwrap();
    assert_eq!(f.source.units["rpm"].column, "Motor Optical Speed (RPM)");
    assert_eq!(f.record.channel("rpm").unwrap().data[10], 5100.0);
    assert!(f.source.unread.is_empty(), "{:?}", f.source.unread);
    // Both read: the first, as before.
    let f = read_csv(&table(true, true, "16.1"), &o).unwrap();
    assert_eq!(f.source.units["rpm"].column, "Motor Electrical Speed (RPM)");
    // Neither reads, nor the voltage (an empty column): left out, and said.
    let f = read_csv(&table(false, false, ""), &o).unwrap();
    assert!(f.record.channel("rpm").is_none());
    assert!(f.record.channel("voltage_V").is_none());
    assert!(f.optional.is_empty(), "{:?}", f.optional);
    let left: Vec<&str> = f.source.unread.iter().map(|u| u.column.as_str()).collect();
    assert_eq!(left, ["Motor Electrical Speed (RPM)", "Voltage (V)"]);
    assert!(f.source.unread[0].reason.contains("no reading"));
}

#[test]
fn a_speed_per_motor_beside_one_thrust_is_left_out_and_said() {
    // A quad's rig: one load cell under the frame, a speed per motor. Motor 1's speed beside
    // the total thrust would give a thrust coefficient four times too large.
    let mut text = String::from("Time (s),Throttle (%),Thrust (N),Motor 1 RPM,Motor 2 RPM\n");
    for k in 0..100 {
        text.push_str(&format!("{},40,6.0,9000,9100\n", 0.01 * k as f64));
    }
    let o = CsvFileOptions {
        optional: vec!["rpm".into()],
        ..opts()
    };
    let f = read_csv(&text, &o).unwrap();
    assert!(f.record.channel("rpm").is_none());
    assert_eq!(f.source.unread.len(), 1, "{:?}", f.source.unread);
    assert_eq!(f.source.unread[0].column, "Motor 1 RPM");
    assert!(f.source.unread[0].reason.contains("one column per motor"));
    // One motor's speed alone is read.
    let one = text.replace(",Motor 2 RPM", ",Note");
    let f = read_csv(&one, &o).unwrap();
    assert_eq!(f.source.units["rpm"].column, "Motor 1 RPM");
}
