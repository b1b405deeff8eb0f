use super::columns::{ConvOptions, Quantity};
use super::*;

fn run(opts: CsvOptions, input: &[u8]) -> (Vec<String>, Vec<CsvRow>, CsvDecoder) {
    let mut dec = CsvDecoder::new(opts);
    let mut items = Vec::new();
    let mut rows = Vec::new();
    let mut on = |it: CsvItem<'_>| {
        match &it {
            CsvItem::Row(r) => rows.push(*r),
            CsvItem::Header(h) => items.push(format!("header {}", h.columns.len())),
            CsvItem::Ack(a) => items.push(format!("ack {a:?}")),
            CsvItem::Comment(c) => items.push(format!("comment {c}")),
        };
    };
    dec.push(input, &mut on);
    dec.finish(&mut on);
    (items, rows, dec)
}

#[test]
fn headerless_stream_uses_default_order() {
    let (_, rows, dec) = run(
        CsvOptions::default(),
        b"1000,3500,1.25\r\n2000,3600,1.5,0.01,9000,16.8,3.2\n",
    );
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0].t_s, Some(1e-3));
    assert_eq!(rows[0].throttle, Some(0.35));
    assert_eq!(rows[0].thrust_n, Some(1.25));
    assert_eq!(rows[0].rpm, None);
    assert_eq!(rows[1].rpm, Some(9000.0));
    assert_eq!(rows[1].current_a, Some(3.2));
    assert_eq!(dec.stats().rows, 2);
    assert_eq!(dec.stats().headers, 0);
}

#[test]
fn header_units_comments_and_acks() {
    let input = b"# propid bench v1\n\
t_ms,idx,throttle_pct,thrust_g,erpm,temp_C\n\
10,0,35,100,14000,25\n\
#ACK THR OK 123456\n\
#ACK ARM ERR 1\n\
20,1,36,,14700,25\n";
    let opts = CsvOptions {
        conv: ConvOptions {
            motor_poles: Some(14),
            ..Default::default()
        },
        ..Default::default()
    };
    let (items, rows, dec) = run(opts, input);
    assert_eq!(
        items,
        [
            "comment  propid bench v1",
            "header 5",
            "ack CsvAck { command: Thr, result: Ok(Some(123456)) }",
            "ack CsvAck { command: Arm, result: Err(1) }",
        ]
    );
    assert_eq!(rows.len(), 2);
    assert!((rows[0].t_s.unwrap() - 0.010).abs() < 1e-15);
    assert_eq!(rows[0].index, Some(0.0));
    assert!((rows[0].throttle.unwrap() - 0.35).abs() < 1e-15);
    assert!((rows[0].thrust_n.unwrap() - 0.980665).abs() < 1e-12);
    assert!((rows[0].rpm.unwrap() - 2000.0).abs() < 1e-9);
    assert_eq!(rows[1].thrust_n, None);
    assert_eq!(dec.stats().acks, 2);
}

#[test]
fn unresolved_columns_are_reported_not_guessed() {
    let (_, rows, dec) = run(
        CsvOptions::default(),
        b"t_s,throttle_us,thrust_N\n0,1500,1\n",
    );
    let h = dec.header().unwrap();
    assert_eq!(h.unresolved.len(), 1);
    assert_eq!(h.unresolved[0].source_name, "throttle_us");
    assert_eq!(rows[0].throttle, None);
    assert_eq!(rows[0].thrust_n, Some(1.0));
}

#[test]
fn checksums_are_checked() {
    let good = b"1000,3500,1.25";
    let cs = checksum(good);
    let input = format!("1000,3500,1.25*{cs:02X}\n1000,3500,1.25*{:02x}\n", cs ^ 1);
    let (_, rows, dec) = run(CsvOptions::default(), input.as_bytes());
    assert_eq!(rows.len(), 1);
    assert_eq!(dec.stats().bad_checksum, 1);
}

#[test]
fn long_lines_and_bad_rows_are_dropped_and_counted() {
    let mut input = Vec::new();
    input.extend_from_slice(b"t_us,throttle,thrust_N\n");
    input.extend(std::iter::repeat_n(b'1', 300));
    input.extend_from_slice(b"\n1,2,x\n1,2,3\n\n");
    let (_, rows, dec) = run(CsvOptions::default(), &input);
    assert_eq!(rows.len(), 1);
    let s = dec.stats();
    assert_eq!((s.too_long, s.bad_row, s.empty_lines), (1, 1, 1));
    assert_eq!(s.dropped(), 2);
    // The limit counts characters without the newline; exactly 255 passes.
    let mut ok = vec![b'7'; 255];
    ok.push(b'\n');
    let (_, rows, dec) = run(CsvOptions::default(), &ok);
    assert_eq!((rows.len(), dec.stats().too_long), (1, 0));
}

#[test]
fn exported_stand_log_with_bom_and_empty_fields() {
    let opts = CsvOptions {
        conv: ConvOptions {
            esc_min_us: Some(1000.0),
            esc_max_us: Some(2000.0),
            motor_poles: None,
        },
        max_line: 4096,
    };
    let input = "\u{feff}Time (s),ESC signal (µs),Servo 1 (µs),AccX (g),Torque (N·m),Thrust (N),\
Voltage (V),Current (A),Motor Electrical Speed (RPM),Motor Optical Speed (RPM),App message,\n\
0.5,1150,,-0.06,0.001,0.087,16.7,0.61,3323,3323,,\n\
0.52,1200,,-0.06,0.002,0.25,16.7,0.91,5646,0,note,\n";
    let (items, rows, dec) = run(opts, input.as_bytes());
    assert_eq!(items, ["header 7"]);
    let h = dec.header().unwrap();
    assert_eq!(h.column(Quantity::Rpm).unwrap().index, 8);
    assert_eq!(rows.len(), 2);
    assert!((rows[0].throttle.unwrap() - 0.15).abs() < 1e-12);
    assert_eq!(rows[1].rpm, Some(5646.0));
    assert_eq!(rows[1].torque_nm, Some(0.002));
    assert_eq!(dec.stats().bad_row, 0);
}

#[test]
fn tab_separated_and_reheadered_streams() {
    let input = b"1\t2\t3\nt_s,thrust_N\n0.1,5\nhello world\nt_ms,thrust_N\n5,6\n";
    let (_, rows, dec) = run(CsvOptions::default(), input);
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[1].t_s, Some(0.1));
    assert_eq!(rows[2].t_s, Some(0.005));
    assert_eq!(dec.stats().headers, 2);
    assert_eq!(dec.stats().bad_row, 1);
}

#[test]
fn chunking_does_not_matter() {
    let input = b"# hi\nt_us,throttle,thrust_N\n1,2,3\n4,5,6*00\n7,8,9\n";
    let (_, whole, _) = run(CsvOptions::default(), input);
    let mut dec = CsvDecoder::default();
    let mut rows = Vec::new();
    for b in input.iter() {
        dec.push(std::slice::from_ref(b), |it| {
            if let CsvItem::Row(r) = it {
                rows.push(r)
            }
        });
    }
    assert_eq!(rows, whole);
    assert_eq!(whole.len(), 2);
}
