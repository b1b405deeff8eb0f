//! One placer: a CSV-stream recording replayed (the daemon's wire → CSV link → tracker, what
//! `propid replay` runs) and the same recording identified (`propid_ingest::read_record`)
//! place every row at the same index — with timestamp jitter, lost rows, a repeated row, a row
//! out of order, the bench's 32-bit `micros()` wrapping, HELLO and EVENT lines and a bench
//! restart in the recording.

use propid::daemon::config::Config;
use propid::daemon::runner::csv_options;
use propid::daemon::tracker::Tracker;
use propid::daemon::wire::Wire;
use propid_ingest::read_record;
use propid_sim::csv::CsvWriter;
use propid_wire::protocol::message::{
    EscProtocol, Event, EventCode, Frame, Hello, Message, Sample, SampleFlags,
};
use propid_wire::record::{names, RecordEventKind};

/// Rows per boot, and the rows of the first boot that never reach the host.
const ROWS: u32 = 6000;
const LOST: [u32; 9] = [3, 40, 41, 700, 1500, 2999, 3000, 3001, 4444];

/// A thrust value unique to row `k` of boot `boot` (4 decimals, as the bench prints it).
fn thrust(boot: u32, k: u32) -> f32 {
    (1.0 + f64::from(boot) + f64::from(k) * 1e-4) as f32
}

/// ±150 µs of pseudo-random jitter (15 % of the period).
fn jitter(k: u32) -> i64 {
    let x = (u64::from(k) + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    ((x >> 40) % 301) as i64 - 150
}

fn hello(boot_id: u32) -> Message {
    Message::Hello(Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::None,
        fw_version: 1,
        boot_id,
        t_us: 0,
        sample_rate_hz: 1000,
        channels: 1,
        motor_poles: 0,
        caps: 0,
        name: Hello::name_field("jittery"),
    })
}

/// The recording: what the simulated bench's CSV writer prints for a bench whose clock starts
/// 2.5 s before the 32-bit wrap and runs 0.2 % slow, with jitter, lost rows, a row sent twice,
/// one out of order, a pulse announced by an EVENT line, then a reboot (the clock starts again
/// from 0, announced by two HELLO lines).
fn recording() -> Vec<u8> {
    let w = CsvWriter::new();
    let line = |m: Message| w.format(&m).unwrap_or_default();
    let mut text = String::from("# booting\n");
    let start = i64::from(u32::MAX) - 2_500_000;
    let t = |k: u32| ((start + i64::from(k) * 998 + jitter(k)) % (1i64 << 32)) as u32;
    let sample = |boot: u32, k: u32, t_us: u32| Sample {
        sample_index: 0,
        t_us,
        throttle: if k % 500 == 250 { 3500 } else { 3000 },
        flags: SampleFlags::THRUST_VALID,
        thrust_n: thrust(boot, k),
        ..Sample::default()
    };
    for k in 0..ROWS {
        if k == 100 {
            text += &line(hello(0xA1));
        }
        if k == 250 {
            text += &line(Message::Event(Event {
                code: EventCode::ImpulseStart,
                arg: 3500,
                t_us: t(250),
                sample_index: 123_456, // the bench's own count: not the host's
            }));
        }
        if LOST.contains(&k) {
            continue;
        }
        text += &line(Message::Sample(sample(0, k, t(k))));
        if k == 2000 {
            text += &line(Message::Sample(sample(0, k, t(k)))); // sent twice
        }
        if k == 5000 {
            text += &line(Message::Sample(sample(0, 4990, t(4990)))); // out of order
        }
    }
    text += &line(hello(0xB2));
    text += &line(hello(0xB2));
    for k in 0..ROWS / 2 {
        let t = (5_000 + i64::from(k) * 1000 + jitter(k + 7)) as u32;
        text += &line(Message::Sample(sample(1, k, t)));
    }
    text.into_bytes()
}

/// What the sampler hands the worker, per sample: record position, thrust.
fn replayed(bytes: &[u8]) -> (Vec<(usize, f32)>, Tracker, usize) {
    let cfg = Config::default();
    let mut wire = Wire::new(cfg.device.protocol, csv_options(&cfg));
    let mut tracker = Tracker::default();
    let mut placed = Vec::new();
    let mut next = 0usize;
    let mut impulse_at = None;
    let mut on_frame = |f: Frame, _| match f.msg {
        Message::Hello(h) => {
            tracker.hello_csv(h.boot_id, h.sample_rate_hz);
        }
        Message::Sample(s) => {
            let p = tracker.sample(s.sample_index, s.t_us);
            if p.duplicate {
                return;
            }
            // a masked gap is filled with missing samples; a new segment is appended as it is
            if !p.new_segment {
                next += p.lost_before as usize;
            }
            placed.push((next, s.thrust_n));
            next += 1;
        }
        Message::Event(e) => {
            let at = tracker.event_index(e.sample_index);
            impulse_at = Some(at);
        }
        _ => {}
    };
    // the sampler's read size
    for chunk in bytes.chunks(4096) {
        wire.push(chunk, &mut on_frame);
    }
    wire.finish(&mut on_frame);
    (placed, tracker, impulse_at.map_or(0, |i| i as usize))
}

#[test]
fn replay_and_identify_place_every_csv_row_at_the_same_index() {
    let bytes = recording();
    let (record, ingest) = read_record(&bytes).expect("the recording reads");
    let (placed, tracker, impulse_at) = replayed(&bytes);

    // every sample the daemon placed is at the same record position, with the same value
    let recorded = &record.channel(names::THRUST).expect("thrust").data;
    let mut covered = vec![false; record.len()];
    for &(k, y) in &placed {
        assert!(
            k < record.len(),
            "position {k} past the record ({})",
            record.len()
        );
        assert!(!record.missing[k], "position {k} is missing in the record");
        assert_eq!(recorded[k] as f32, y, "position {k}");
        covered[k] = true;
    }
    // … and every other record position is a gap the daemon also saw
    assert_eq!(record.len(), placed.last().map_or(0, |p| p.0 + 1));
    for (k, c) in covered.iter().enumerate() {
        assert_eq!(!c, record.missing[k], "position {k}");
    }
    let a = &ingest.assemble;
    assert_eq!(a.samples, placed.len() as u64);
    assert_eq!(
        (
            a.samples_lost,
            a.gaps + a.large_gaps,
            a.duplicates,
            a.segments
        ),
        (
            tracker.samples_lost,
            tracker.gaps,
            tracker.duplicates,
            tracker.assemble_stats().segments
        )
    );

    // and the placement is the right one: row k of the first boot at position k, each lost row
    // a one-sample gap, the duplicate and the row out of order dropped, the second boot a
    // segment of its own after the first
    let first = ROWS as usize;
    for (pos, &(k, y)) in placed.iter().enumerate() {
        let want = if k < first {
            thrust(0, k as u32)
        } else {
            thrust(1, (k - first) as u32)
        };
        assert_eq!(y, want, "sample {pos} at position {k}");
    }
    assert_eq!(a.samples_lost, LOST.len() as u64);
    assert_eq!(a.duplicates, 1);
    assert_eq!(a.segments, 2);
    assert_eq!(record.len(), first + ROWS as usize / 2);
    assert_eq!(
        record
            .events
            .iter()
            .filter(|e| e.kind == RecordEventKind::SegmentStart)
            .map(|e| e.sample)
            .collect::<Vec<_>>(),
        [first]
    );
    // the EVENT line lands on the row of its time, in both
    assert_eq!(impulse_at, 250);
    assert_eq!(record.impulse_starts().collect::<Vec<_>>(), [250]);
}

/// `propid identify` and `propid diagnose` read files through the one loader: a CSV-stream
/// recording goes to the same stream placer as above (not to the exported-log reader, which
/// resamples by its time column), so the record they identify is the record `replay` places.
#[test]
fn the_file_loader_reads_a_csv_stream_recording_through_the_stream_placer() {
    use propid::cli::load::{load, Origin, Request};
    let bytes = recording();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bench.csv");
    std::fs::write(&path, &bytes).unwrap();
    let loaded = load(&path, &Request::default()).expect("the loader reads it");
    assert!(matches!(loaded.origin, Origin::Tsp1(_)), "read as a stream");
    let (record, _) = read_record(&bytes).unwrap();
    assert_eq!(loaded.record.len(), record.len());
    assert_eq!(loaded.record.missing, record.missing);
    let a = &loaded.record.channel(names::THRUST).unwrap().data;
    let b = &record.channel(names::THRUST).unwrap().data;
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            x == y || (x.is_nan() && y.is_nan()),
            "position {k}: {x} vs {y}"
        );
    }
    // An exported log (a header, no checksums, no bench comments) stays with its time column.
    let log = dir.path().join("export.csv");
    let rows: String = (0..200)
        .map(|k| {
            format!(
                "{},{},{}\n",
                k as f64 * 0.01,
                0.3,
                1.0 + (k % 7) as f64 * 0.01
            )
        })
        .collect();
    std::fs::write(&log, format!("Time (s),throttle,thrust_N\n{rows}")).unwrap();
    let loaded = load(&log, &Request::default()).expect("the log reads");
    assert!(
        matches!(loaded.origin, Origin::Csv(_)),
        "read as an exported log"
    );
}
