//! The CSV fallback decoder: random input never panics, chunking never matters, and the header
//! alias table maps the exported logs of real commercial stands in `../shared/data` (skipped with
//! a message when that folder is absent, as in a user's clone).

use std::path::PathBuf;

use propid_wire::protocol::csv::{CsvDecoder, CsvItem, CsvOptions, CsvRow};
use propid_wire::protocol::csv_columns::{ConvOptions, Quantity};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn rows(dec: &mut CsvDecoder, parts: &[&[u8]]) -> Vec<CsvRow> {
    let mut out = Vec::new();
    for p in parts {
        dec.push(p, |it| {
            if let CsvItem::Row(r) = it {
                out.push(r)
            }
        });
    }
    dec.finish(|it| {
        if let CsvItem::Row(r) = it {
            out.push(r)
        }
    });
    out
}

fn text_line() -> impl Strategy<Value = String> {
    prop_oneof![
        "[0-9]{1,6}(,[0-9.]{1,6}){2,6}",
        "t_us,idx,throttle,thrust_N",
        "#ACK (THR|ARM|STOP) (OK [0-9]{1,9}|ERR [0-9])",
        "# [ -~]{0,40}",
        "[ -~]{0,300}",
    ]
}

proptest! {
    #![proptest_config(Config {
        cases: 256,
        rng_seed: RngSeed::Fixed(0xC5F0_2026),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..3000)) {
        let mut dec = CsvDecoder::default();
        let r = rows(&mut dec, &[&bytes]);
        let s = dec.stats();
        prop_assert_eq!(s.rows, r.len() as u64);
        prop_assert!(s.lines >= s.rows + s.dropped());
    }

    #[test]
    fn chunking_never_matters(
        lines in prop::collection::vec(text_line(), 0..30),
        chunk in 1usize..64,
    ) {
        let text = lines.join("\r\n");
        let whole = rows(&mut CsvDecoder::default(), &[text.as_bytes()]);
        let parts: Vec<&[u8]> = text.as_bytes().chunks(chunk).collect();
        let mut dec = CsvDecoder::default();
        let chunked = rows(&mut dec, &parts);
        prop_assert_eq!(format!("{whole:?}"), format!("{chunked:?}"));
    }
}

fn shared_data(folder: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(folder);
    if p.is_dir() {
        Some(p)
    } else {
        eprintln!("skipped: ../shared/data/{folder} is absent");
        None
    }
}

/// Options for an exported stand log: ESC range 1000–2000 µs, lines up to 4096 bytes (their
/// headers are long).
fn export_options() -> CsvOptions {
    CsvOptions {
        conv: ConvOptions {
            esc_min_us: Some(1000.0),
            esc_max_us: Some(2000.0),
            motor_poles: None,
        },
        max_line: 4096,
    }
}

/// vanderploeg-rcbenchmark-steps (no licence: read in place, never copied): the Tyto /
/// RCbenchmark export with a BOM, µs and N·m in its names, and empty servo columns.
#[test]
fn rcbenchmark_export_maps_every_channel() {
    let Some(dir) = shared_data("vanderploeg-rcbenchmark-steps") else {
        return;
    };
    let bytes = std::fs::read(dir.join("90PERCENT_2024-08-13_185523.csv")).unwrap();
    let mut dec = CsvDecoder::new(export_options());
    let r = rows(&mut dec, &[&bytes]);
    let h = dec.header().expect("header recognised");
    for q in [
        Quantity::Time,
        Quantity::Throttle,
        Quantity::Thrust,
        Quantity::Torque,
        Quantity::Rpm,
        Quantity::Voltage,
        Quantity::Current,
    ] {
        assert!(h.column(q).is_some(), "{q:?} not mapped");
    }
    assert_eq!(
        h.column(Quantity::Rpm).unwrap().source_name,
        "Motor Electrical Speed (RPM)"
    );
    // PROVENANCE.md: 623 rows; ESC staircase 1150 → 1710 µs; supply about 16.8 V.
    assert_eq!(r.len(), 623);
    assert_eq!(dec.stats().dropped(), 0);
    let thr: Vec<f64> = r.iter().filter_map(|r| r.throttle).collect();
    let max = thr.iter().cloned().fold(f64::MIN, f64::max);
    assert!((max - 0.71).abs() < 1e-9, "max throttle {max}");
    assert!((r[0].voltage_v.unwrap() - 16.8).abs() < 0.1);
}

/// dantonio-rcbenchmark-ramp (GPL-3.0: read in place): thrust in gram-force.
#[test]
fn rcbenchmark_gram_force_export_converts_to_newtons() {
    let Some(dir) = shared_data("dantonio-rcbenchmark-ramp") else {
        return;
    };
    let bytes = std::fs::read(dir.join("StepsTest20230615_2023-06-15_174003.csv")).unwrap();
    let mut dec = CsvDecoder::new(export_options());
    let r = rows(&mut dec, &[&bytes]);
    assert!(!r.is_empty());
    // First row: 0.18824050492747205 gf.
    let want = 0.18824050492747205 * 9.80665e-3;
    assert!((r[0].thrust_n.unwrap() - want).abs() < 1e-15);
}

/// With the protocol's 255-character limit, the long export header is dropped and counted,
/// not half-parsed.
#[test]
fn wire_line_limit_drops_a_long_export_header() {
    let Some(dir) = shared_data("vanderploeg-rcbenchmark-steps") else {
        return;
    };
    let bytes = std::fs::read(dir.join("90PERCENT_2024-08-13_185523.csv")).unwrap();
    let mut dec = CsvDecoder::default();
    let _ = rows(&mut dec, &[&bytes]);
    assert!(dec.stats().too_long >= 1);
    assert!(dec.header().is_none());
}
