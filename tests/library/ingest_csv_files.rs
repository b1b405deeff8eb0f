//! CSV file reader: §6 files, exported stand logs, benchmark files, and malformed variants (a
//! wrong checksum, a missing column, text in a number field, an empty file), each a clear error
//! or a counted, skipped row.

use propid::ingest::csv_file::{read_csv, CsvFileError, CsvFileOptions};
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
        input: Some("nope".into()),
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
    assert_eq!(
        read_csv("t_s,throttle,thrust_N\n0,1,x\n0.1,1,y\n", &opts()),
        Err(CsvFileError::TooFewRows(0))
    );
}

#[test]
fn headerless_files_follow_section_6_or_given_names() {
    let text = "0,1000,1.0\n1000,1000,1.1\n2000,1500,1.2\n";
    let f = read_csv(text, &opts()).unwrap();
    assert_eq!(f.record.dt_s, 1e-3);
    assert!(!f.source.header);
    let two = "0.0,0.797\n0.02,0.797\n0.04,0.796\n";
    let o = CsvFileOptions {
        columns: Some(vec!["t_s".into(), "load_kg".into()]),
        outputs: vec!["load_kg".into()],
        ..opts()
    };
    let f = read_csv(two, &o).unwrap();
    assert_eq!(f.input, None, "no input column: response only");
    assert_eq!(f.record.channel("load_kg").unwrap().data[2], 0.796);
    // Tab separated, quoted names, trailing empty column.
    let tabs = "\"V1\"\t\"V2\"\t\n0.1\t0.2\t\n0.3\t0.4\t\n";
    let o = CsvFileOptions {
        input: Some("V1".into()),
        outputs: vec!["V2".into()],
        fs_hz: Some(610.35),
        ..opts()
    };
    let f = read_csv(tabs, &o).unwrap();
    assert_eq!(f.record.channel("V2").unwrap().data, vec![0.2, 0.4]);
}

#[test]
fn empty_fields_are_missing_samples() {
    let text = "t_s,throttle,thrust_N\n0,1000,1\n0.01,1000,\n0.02,1000,3\n";
    let f = read_csv(text, &opts()).unwrap();
    assert_eq!(f.record.missing, vec![false, true, false]);
    assert!(f.record.channel("thrust_N").unwrap().data[1].is_nan());
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
