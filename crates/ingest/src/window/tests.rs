use super::*;
use crate::tsp::read_record;
use propid_wire::protocol::message::{Event, EventCode, Hello, Sample, SampleFlags};
use propid_wire::protocol::{encode_frame, EscProtocol, Message, MAX_FRAME_LEN};

fn wire(seq: u16, m: &Message, out: &mut Vec<u8>) {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(seq, m, &mut buf);
    out.extend_from_slice(&buf[..n]);
}

/// `n` samples at 1 kHz, throttle `cmd(i)` (0..10000), a thrust following it; samples in
/// `lost` not sent; an IMPULSE_START event at every sample of `pulses`.
fn recording(n: u32, cmd: impl Fn(u32) -> u16, lost: &[u32], pulses: &[u32]) -> Vec<u8> {
    let mut out = Vec::new();
    let hello = Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::DShot600,
        fw_version: 1,
        boot_id: 9,
        t_us: 0,
        sample_rate_hz: 1000,
        channels: 0x01,
        motor_poles: 0,
        caps: 0,
        name: Hello::name_field("t"),
    };
    let mut seq = 0u16;
    wire(seq, &Message::Hello(hello), &mut out);
    for i in 0..n {
        seq = seq.wrapping_add(1);
        if pulses.contains(&i) {
            let e = Event {
                code: EventCode::ImpulseStart,
                arg: 0,
                t_us: 1000 * i,
                sample_index: i,
            };
            wire(seq, &Message::Event(e), &mut out);
            seq = seq.wrapping_add(1);
        }
        if lost.contains(&i) {
            continue;
        }
        let s = Sample {
            sample_index: i,
            t_us: 1000 * i,
            throttle: cmd(i),
            flags: SampleFlags::THRUST_VALID | SampleFlags::THRUST_FRESH,
            thrust_n: 0.001 * cmd(i) as f32 + 0.01 * (i % 7) as f32,
            ..Sample::default()
        };
        wire(seq, &Message::Sample(s), &mut out);
    }
    out
}

/// Both passes of [`Scan`] over `bytes` in pieces of `piece` bytes.
fn scan(bytes: &[u8], window: usize, piece: usize) -> (Record, IngestStats) {
    let mut s = Scan::new(&IngestOptions::default(), Some("throttle"), window);
    loop {
        for c in bytes.chunks(piece) {
            s.push(c);
        }
        match s.finish().unwrap() {
            Scanned::Whole(r, st) => return (r, st),
            Scanned::Rescan(again) => s = again,
            Scanned::Window(mut reader) => {
                for c in bytes.chunks(piece) {
                    reader.push(c);
                }
                return reader.finish().unwrap();
            }
        }
    }
}

fn show(r: &Record) -> String {
    format!("{r:?}") // NaN (a missing sample) is no equal of itself: compared as printed
}

#[test]
fn a_recording_within_the_window_reads_as_before() {
    let bytes = recording(
        1500,
        |i| 2000 + 1000 * ((i / 300) % 2) as u16,
        &[40],
        &[600],
    );
    let whole = read_record(&bytes).unwrap();
    for piece in [64, 4096] {
        let (r, st) = scan(&bytes, 1600, piece);
        assert_eq!(show(&r), show(&whole.0));
        assert_eq!(st, whole.1);
        assert_eq!(st.window, None);
    }
}

#[test]
fn a_long_recording_keeps_the_window_with_the_most_moves() {
    // 10 000 rows: held at 2000 but for a burst of steps over rows 5 200..6 000; a gap and
    // pulses inside and outside the window
    let cmd = |i: u32| {
        if (5200..6000).contains(&i) && (i / 50) % 2 == 1 {
            3000
        } else {
            2000
        }
    };
    let bytes = recording(10_000, cmd, &[100, 5500, 5501], &[300, 5300, 9000]);
    let whole = read_record(&bytes).unwrap();
    let (r, st) = scan(&bytes, 1600, 4096);
    // blocks of 100 rows: the earliest window on a block boundary covering the burst's blocks
    let w = st.window.unwrap();
    assert_eq!((w.start, w.samples, w.file_samples), (4500, 1600, 10_000));
    assert_eq!((w.moves, w.file_moves), (16, 16));
    assert_eq!(w.start_s, 4.5);
    assert_eq!(r.len(), 1600);
    for (c, full) in r.channels.iter().zip(&whole.0.channels) {
        let want = &full.data[4500..6100];
        assert_eq!(format!("{:?}", c.data), format!("{want:?}"), "{}", c.name);
    }
    assert_eq!(r.missing, whole.0.missing[4500..6100]);
    assert_eq!(r.missing_count(), 2);
    assert_eq!(r.impulse_starts().collect::<Vec<_>>(), [800]);
    assert_eq!(r.t0_s, whole.0.t0_s + 4.5);
    // the counters are the whole file's
    let mut no_window = st.clone();
    no_window.window = None;
    assert_eq!(no_window, whole.1);
}

#[test]
fn an_early_small_change_is_no_move_once_the_range_widens() {
    // a dither of 10 (0.1 %) early, steps of 1000 later: the first pass keeps the dither's
    // changes (over 2 % of the range seen then) and drops them at the end
    let cmd = |i: u32| match i {
        0..=2999 => 2000 + 10 * ((i / 10) % 2) as u16,
        _ => 2000 + 1000 * ((i / 100) % 2) as u16,
    };
    let u: Vec<f64> = (0..6000).map(|i| cmd(i) as f64 * 1e-4).collect();
    let mut first = MoveCounter::new(None, 100);
    let mut counting = MoveCounter::new(Some(0.1), 100);
    for c in u.chunks(77) {
        first.push(c);
        counting.push(c);
    }
    let moves = first.moves().unwrap();
    assert_eq!(moves, counting.moves().unwrap());
    assert_eq!(moves[..30].iter().sum::<usize>(), 0);
    assert_eq!(moves[30..].iter().sum::<usize>(), 29);
    assert_eq!(choose_window(&moves, 6000, 1600, 100), (3100, 16));
}

#[test]
fn a_chattering_command_takes_a_counting_pass_with_the_same_window() {
    // held, then a change on every row from row 4 000 on
    let cmd = |i: u32| match i {
        0..=3999 => 2000,
        _ => 2000 + ((i * 7919) % 13) as u16 * 100 + if i > 7000 { 1000 } else { 0 },
    };
    let bytes = recording(9000, cmd, &[], &[]);
    let mut s = Scan::new(&IngestOptions::default(), Some("throttle"), 1600);
    s.counter.cap = 500;
    s.push(&bytes);
    let Ok(Scanned::Rescan(again)) = s.finish() else {
        panic!("no counting pass");
    };
    let (r, st) = scan(&bytes, 1600, 4096); // kept every change
    let mut again = again;
    again.push(&bytes);
    let Ok(Scanned::Window(mut reader)) = again.finish() else {
        panic!("no window");
    };
    reader.push(&bytes);
    let (r2, st2) = reader.finish().unwrap();
    assert_eq!(st2, st);
    assert_eq!(show(&r2), show(&r));
    assert_eq!(st.window.unwrap().start, 4000);
}

#[test]
fn choose_window_takes_the_earliest_of_the_busiest() {
    assert_eq!(choose_window(&[1, 2, 0, 2, 1], 500, 200, 100), (0, 3));
    assert_eq!(choose_window(&[0, 2, 0, 1, 2], 500, 200, 100), (300, 3));
    // the window ends within the rows: a last block too short for a window is not a start
    assert_eq!(choose_window(&[0, 0, 0, 0, 9], 450, 200, 100), (0, 0));
    assert_eq!(choose_window(&[3], 80, 200, 100), (0, 3));
}
