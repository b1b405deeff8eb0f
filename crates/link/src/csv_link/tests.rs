//! The CSV link against the simulated stand's CSV dialect and against a plain Arduino bench.

use super::*;
use propid_sim::csv::CsvWriter;
use propid_wire::protocol::message::{msg_type, Event, EventCode};
use propid_wire::stream::csv_stream::made_up_hello;

fn sample(k: u32, throttle: u16, thrust: f32) -> Sample {
    Sample {
        sample_index: 1000 + k,
        t_us: 40_000 + k * 1000,
        throttle,
        flags: SampleFlags(SampleFlags::THRUST_VALID.0 | SampleFlags::ARMED.0),
        thrust_n: thrust,
        ..Sample::default()
    }
}

fn frames(link: &mut CsvLink, text: &str) -> Vec<Frame> {
    let mut v = Vec::new();
    link.push(text.as_bytes(), &mut |f| v.push(f));
    link.finish(&mut |f| v.push(f));
    v
}

#[test]
fn simulated_stand_lines_become_the_frames_it_would_have_sent() {
    let w = CsvWriter::new();
    let mut hello = made_up_hello(1000);
    hello.boot_id = 0x1234_5678;
    let mut text = w.format(&Message::Hello(hello)).unwrap();
    let pulse_at = [10u32, 30];
    for k in 0..50u32 {
        let thr = if pulse_at.contains(&k) { 3500 } else { 3000 };
        text += &w.format(&Message::Sample(sample(k, thr, 0.5))).unwrap();
    }
    text += &w
        .format(&Message::Event(Event {
            code: EventCode::WatchdogTrip,
            arg: 0,
            t_us: 40_000 + 49_000,
            sample_index: 1049,
        }))
        .unwrap();
    let mut link = CsvLink::new(CsvLinkOptions::default());
    let got = frames(&mut link, &text);
    assert!(matches!(got[0].msg, Message::Hello(h) if h == hello));
    let samples: Vec<Sample> = got
        .iter()
        .filter_map(|f| match f.msg {
            Message::Sample(s) => Some(s),
            _ => None,
        })
        .collect();
    assert_eq!(samples.len(), 50);
    for (k, s) in samples.iter().enumerate() {
        let k = k as u32;
        assert_eq!(s.sample_index, k, "rows are numbered from 0");
        assert_eq!(s.t_us, 40_000 + k * 1000);
        assert_eq!(
            s.flags.contains(SampleFlags::IMPULSE_ACTIVE),
            pulse_at.contains(&k)
        );
        assert!(s.flags.contains(SampleFlags::THRUST_VALID));
        assert!((s.thrust_n - 0.5).abs() < 1e-6);
    }
    let event = got.iter().find_map(|f| match f.msg {
        Message::Event(e) => Some(e),
        _ => None,
    });
    assert_eq!(
        event.map(|e| (e.code, e.sample_index)),
        Some((EventCode::WatchdogTrip, 49))
    );
    assert_eq!(link.stats().pulses, 2);
    assert_eq!(link.stats().rows, 50);
    assert_eq!(link.lines_ok(), 52);
    assert!(link.dropped().iter().all(|d| d.1 == 0));
}

#[test]
fn acks_go_back_to_the_command_that_was_sent_and_a_silent_bench_gets_a_hello() {
    let mut link = CsvLink::new(CsvLinkOptions::default());
    let mut buf = [0u8; 64];
    let n = link
        .encode_command(41, &Message::HelloReq, &mut buf)
        .unwrap();
    assert_eq!(&buf[..n], b"PING\n");
    let n = link
        .encode_command(
            42,
            &Message::SetThrottle(propid_wire::protocol::SetThrottle {
                level: 3000,
                ramp_ms: 200,
            }),
            &mut buf,
        )
        .unwrap();
    assert_eq!(&buf[..n], b"THR 3000 200\n");
    // a plain Arduino bench: header, rows at 500 Hz, ACKs, no HELLO
    let mut text = String::from("t_us,throttle,thrust_g\n");
    for k in 0..20 {
        text += &format!("{},{},{}\n", k * 2000, 3000, 100);
    }
    text += "#ACK PING OK 40000\n#ACK THR ERR 6\n#ACK FLY OK 1\n";
    let got = frames(&mut link, &text);
    let msgs: Vec<Message> = got
        .iter()
        .map(|f| f.msg)
        .filter(|m| !matches!(m, Message::Sample(_)))
        .collect();
    assert_eq!(msgs.len(), 3, "{msgs:?}");
    match msgs[0] {
        Message::Hello(h) => assert_eq!((h.boot_id, h.sample_rate_hz), (0, 500)),
        other => panic!("{other:?}"),
    }
    match msgs[1] {
        Message::Ack(a) => assert_eq!(
            (a.cmd_seq, a.cmd_type, a.result, a.t_us),
            (41, msg_type::HELLO_REQ, AckResult::Ok, 40_000)
        ),
        other => panic!("{other:?}"),
    }
    match msgs[2] {
        Message::Ack(a) => assert_eq!(
            (a.cmd_seq, a.cmd_type, a.result),
            (42, msg_type::SET_THROTTLE, AckResult::Busy)
        ),
        other => panic!("{other:?}"),
    }
    // grams converted to newtons
    let s = got
        .iter()
        .find_map(|f| match f.msg {
            Message::Sample(s) => Some(s),
            _ => None,
        })
        .unwrap();
    assert!((s.thrust_n - 0.980_665).abs() < 1e-5, "{}", s.thrust_n);
    assert_eq!(link.stats().acks, 3);
}

#[test]
fn bad_lines_are_counted_by_kind_and_lose_nothing_else() {
    let w = CsvWriter::new();
    let mut text = String::new();
    for k in 0..30u32 {
        let mut line = w.format(&Message::Sample(sample(k, 3000, 1.0))).unwrap();
        if k == 5 {
            line = line.replacen(",3000,", ",3001,", 1); // wrong checksum
        }
        if k == 12 {
            line = "x".repeat(300) + "\n"; // too long
        }
        text += &line;
        if k == 20 {
            text += "12,abc,3\n"; // text in a number field
            text += ",3000,1.0\n"; // no time
        }
    }
    let mut link = CsvLink::new(CsvLinkOptions::default());
    let got = frames(&mut link, &text);
    let idx: Vec<u32> = got
        .iter()
        .filter_map(|f| match f.msg {
            Message::Sample(s) => Some(s.sample_index),
            _ => None,
        })
        .collect();
    // rows 5 and 12 lost: their indices are gaps, not renumbered
    let want: Vec<u32> = (0..30).filter(|k| *k != 5 && *k != 12).collect();
    assert_eq!(idx, want);
    let d: std::collections::BTreeMap<_, _> = link.dropped().into_iter().collect();
    assert_eq!(d["bad_checksum"], 1);
    assert_eq!(d["line_too_long"], 1);
    assert_eq!(d["bad_row"], 1);
    assert_eq!(d["row_without_time"], 1);
}

#[test]
fn a_new_boot_releases_the_old_rows_first_and_numbers_again() {
    let w = CsvWriter::new();
    let mut h = made_up_hello(1000);
    h.boot_id = 1;
    let mut text = w.format(&Message::Hello(h)).unwrap();
    for k in 0..10u32 {
        text += &w.format(&Message::Sample(sample(k, 3000, 1.0))).unwrap();
    }
    text += &w.format(&Message::Sample(sample(10, 3600, 1.0))).unwrap(); // open excursion
    h.boot_id = 2;
    text += &w.format(&Message::Hello(h)).unwrap();
    text += &w.format(&Message::Hello(h)).unwrap(); // a reset is believed when confirmed
    for k in 0..5u32 {
        text += &w.format(&Message::Sample(sample(k, 0, 0.0))).unwrap();
    }
    let mut link = CsvLink::new(CsvLinkOptions::default());
    let got = frames(&mut link, &text);
    let seq: Vec<String> = got
        .iter()
        .map(|f| match f.msg {
            Message::Hello(h) => format!("H{}", h.boot_id),
            Message::Sample(s) => format!("{}", s.sample_index),
            other => panic!("{other:?}"),
        })
        .collect();
    let want: Vec<String> = ["H1"]
        .into_iter()
        .map(String::from)
        .chain((0..11).map(|k| k.to_string()))
        .chain(["H2".to_string()])
        .chain((0..5).map(|k| k.to_string()))
        .collect();
    assert_eq!(seq, want);
    // frames are numbered like a device's
    assert!(got.windows(2).all(|w| w[1].seq == w[0].seq.wrapping_add(1)));
}

#[test]
fn every_chunking_gives_the_same_frames() {
    let w = CsvWriter::new();
    let mut h = made_up_hello(1000);
    h.boot_id = 9;
    let mut text = w.format(&Message::Hello(h)).unwrap();
    for k in 0..120u32 {
        let thr = if k % 40 == 20 { 3600 } else { 3000 };
        text += &w.format(&Message::Sample(sample(k, thr, 1.0))).unwrap();
        if k == 60 {
            text += "#ACK THR OK 99\n# a banner line\n";
        }
    }
    let bytes = text.as_bytes();
    let whole = frames(&mut CsvLink::new(CsvLinkOptions::default()), &text);
    assert_eq!(whole.len(), 1 + 120 + 1);
    // every fixed chunk size, and pseudo-random cuts
    let mut cuts: Vec<Vec<usize>> = (1..=64)
        .map(|c| (c..bytes.len()).step_by(c).collect())
        .collect();
    let mut x = 0x2545_F491_u64;
    for _ in 0..50 {
        let mut v = Vec::new();
        let mut at = 0;
        loop {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            at += 1 + (x % 97) as usize;
            if at >= bytes.len() {
                break;
            }
            v.push(at);
        }
        cuts.push(v);
    }
    for c in cuts {
        let mut link = CsvLink::new(CsvLinkOptions::default());
        let mut got = Vec::new();
        let mut from = 0;
        for &to in c.iter().chain([bytes.len()].iter()) {
            link.push(&bytes[from..to], &mut |f| got.push(f));
            from = to;
        }
        link.finish(&mut |f| got.push(f));
        assert_eq!(got, whole);
    }
}

#[test]
fn random_bytes_and_absurd_numbers_never_panic() {
    let mut x = 0x9E37_79B9_7F4A_7C15_u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let fields = [
        "0",
        "-1",
        "1e300",
        "-1e300",
        "nan",
        "inf",
        "4294967295",
        "18446744073709551616",
        "",
        "3000",
        "1000",
        "x",
        "1.5",
    ];
    for round in 0..200 {
        let mut text = String::new();
        if round % 2 == 0 {
            text += "idx,t_us,throttle,thrust_N\n";
        }
        for _ in 0..200 {
            match next() % 5 {
                0 => {
                    let bytes: Vec<u8> = (0..next() % 40).map(|_| next() as u8).collect();
                    text += &String::from_utf8_lossy(&bytes);
                    text.push('\n');
                }
                1 => text += "# HELLO x boot_id ffffffff rate_hz 1\n#ACK PING OK 1\n",
                _ => {
                    let row: Vec<&str> = (0..4)
                        .map(|_| fields[(next() % fields.len() as u64) as usize])
                        .collect();
                    text += &row.join(",");
                    text.push('\n');
                }
            }
        }
        let mut link = CsvLink::new(CsvLinkOptions::default());
        let mut n = 0usize;
        link.push(text.as_bytes(), &mut |_| n += 1);
        link.finish(&mut |_| n += 1);
        let s = link.stats();
        assert!(s.rows + s.out_of_order + s.untimed <= link.lines_ok());
    }
}

#[test]
fn a_thrust_limit_in_newtons_holds_whatever_unit_the_bench_writes() {
    use propid_wire::experiment::Limits;
    let limits = Limits {
        max_thrust_n: Some(5.0),
        ..Limits::default()
    };
    // 5 N is 509.9 gf, 1.124 lbf, 0.5099 kgf: the first row of each bench is under it,
    // the second over
    for (header, under, over) in [
        ("t_us,throttle,thrust_g", 500.0, 520.0),
        ("t_us,throttle,Thrust (kgf)", 0.5, 0.52),
        ("t_us,throttle,thrust_lbf", 1.1, 1.15),
        ("t_us,throttle,Thrust (N)", 4.9, 5.1),
    ] {
        let mut link = CsvLink::new(CsvLinkOptions::default());
        let mut text = format!("{header}\n");
        for k in 0..10 {
            let v = if k < 5 { under } else { over };
            text += &format!("{},{},{v}\n", k * 2000, 3000);
        }
        let trips: Vec<Option<f64>> = frames(&mut link, &text)
            .iter()
            .filter_map(|f| match f.msg {
                Message::Sample(s) => Some(limits.breach(&s).map(|t| t.value)),
                _ => None,
            })
            .collect();
        assert_eq!(trips.len(), 10, "{header}");
        assert!(
            trips[..5].iter().all(Option::is_none),
            "{header}: {trips:?}"
        );
        for t in &trips[5..] {
            let n = t.unwrap_or_else(|| panic!("{header}: {trips:?}"));
            assert!(n > 5.0 && n < 5.2, "{header}: {n} N");
        }
    }
}
