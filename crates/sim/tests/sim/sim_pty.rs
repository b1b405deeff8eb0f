//! The simulated stand over a real pseudo-terminal: loopback through `serialport`, pacing, the
//! watchdog, fault counts and hang-up with re-open. Each test runs a few hundred milliseconds.

use std::io::Read;
use std::time::{Duration, Instant};

use propid_sim::config::SimConfig;
use propid_sim::pty::{RunOptions, SimHandle};
use propid_wire::protocol::message::msg_type;
use propid_wire::protocol::{
    encode_frame, AckResult, Arm, Decoder, EventCode, Frame, Message, MAX_FRAME_LEN,
};

fn open(path: &std::path::Path) -> Box<dyn serialport::SerialPort> {
    serialport::new(path.to_string_lossy(), 921_600)
        .timeout(Duration::from_millis(20))
        .open()
        .expect("open the pty slave")
}

fn send(port: &mut dyn serialport::SerialPort, seq: u16, msg: Message) {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(seq, &msg, &mut buf);
    port.write_all(&buf[..n]).unwrap();
}

/// Reads frames for `dur` (or until `until` says stop).
fn collect(
    port: &mut dyn serialport::SerialPort,
    dec: &mut Decoder,
    dur: Duration,
    mut until: impl FnMut(&[Frame]) -> bool,
) -> Vec<Frame> {
    let mut frames = Vec::new();
    let mut buf = [0u8; 4096];
    let end = Instant::now() + dur;
    while Instant::now() < end && !until(&frames) {
        match port.read(&mut buf) {
            Ok(n) => dec.push(&buf[..n], |f| frames.push(f)),
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("read: {e}"),
        }
    }
    frames
}

fn ack_of(frames: &[Frame], seq: u16) -> Option<propid_wire::protocol::Ack> {
    frames.iter().find_map(|f| match f.msg {
        Message::Ack(a) if a.cmd_seq == seq => Some(a),
        _ => None,
    })
}

/// The sample indices of the SAMPLE frames among `frames`, in order.
fn sample_indices(frames: &[Frame]) -> Vec<u32> {
    frames
        .iter()
        .filter_map(|f| match f.msg {
            Message::Sample(s) => Some(s.sample_index),
            _ => None,
        })
        .collect()
}

/// The first HELLO among `frames`.
fn hello_of(frames: &[Frame]) -> Option<propid_wire::protocol::Hello> {
    frames.iter().find_map(|f| match f.msg {
        Message::Hello(h) => Some(h),
        _ => None,
    })
}

#[test]
fn hello_req_over_the_pty_gets_hello_and_ack_and_samples_are_paced() {
    let sim = SimHandle::spawn(SimConfig::default(), RunOptions::default()).unwrap();
    let mut port = open(sim.path());
    let mut dec = Decoder::new();
    send(&mut *port, 1, Message::HelloReq);
    let frames = collect(&mut *port, &mut dec, Duration::from_secs(2), |f| {
        ack_of(f, 1).is_some()
    });
    let hello = hello_of(&frames).expect("HELLO");
    assert_eq!(hello.boot_id, sim.report().boot_id);
    let ack = ack_of(&frames, 1).expect("ACK");
    assert_eq!(
        (ack.cmd_type, ack.result),
        (msg_type::HELLO_REQ, AckResult::Ok)
    );
    // Pacing: about 1000 samples per second of wall time, in order, no gaps.
    let t0 = Instant::now();
    let frames = collect(&mut *port, &mut dec, Duration::from_millis(300), |_| false);
    let wall = t0.elapsed().as_secs_f64();
    let idx = sample_indices(&frames);
    assert!(idx.windows(2).all(|w| w[1] == w[0] + 1), "no gaps");
    let rate = idx.len() as f64 / wall;
    assert!(
        (600.0..1400.0).contains(&rate),
        "{} samples in {wall} s",
        idx.len()
    );
    assert_eq!(dec.stats().dropped.total(), 0);
    let report = sim.stop().unwrap();
    assert_eq!(report.ended, "stopped");
    assert!(report.firmware.samples as usize >= idx.len());
}

#[test]
fn watchdog_trips_over_the_pty_when_heartbeats_stop() {
    let sim = SimHandle::spawn(SimConfig::default(), RunOptions::default()).unwrap();
    let mut port = open(sim.path());
    let mut dec = Decoder::new();
    send(&mut *port, 1, Message::Arm(Arm::new(100)));
    let frames = collect(&mut *port, &mut dec, Duration::from_secs(2), |f| {
        f.iter()
            .any(|f| matches!(f.msg, Message::Event(e) if e.code == EventCode::WatchdogTrip))
    });
    assert_eq!(ack_of(&frames, 1).map(|a| a.result), Some(AckResult::Ok));
    let trip = frames
        .iter()
        .any(|f| matches!(f.msg, Message::Event(e) if e.code == EventCode::WatchdogTrip));
    assert!(trip, "WATCHDOG_TRIP within 2 s of a 100 ms watchdog");
    assert_eq!(sim.stop().unwrap().firmware.watchdog_trips, 1);
}

#[test]
fn injected_faults_match_what_the_host_counts() {
    let mut cfg = SimConfig::default();
    cfg.stand.sample_rate_hz = 2000;
    cfg.faults.bit_flip_per_byte = 0.002;
    cfg.faults.garbage_bursts_per_s = 20.0;
    cfg.faults.drop_sample_prob = 0.01;
    let sim = SimHandle::spawn(cfg, RunOptions::default()).unwrap();
    let mut port = open(sim.path());
    let mut dec = Decoder::new();
    // Let output flow (the stand discards output until a host has the slave open).
    let _ = collect(&mut *port, &mut dec, Duration::from_millis(50), |_| false);
    // Bracket: what was injected between two snapshots must be what the host counted, give or
    // take the frames in flight at each end (the test reads concurrently with the stand).
    let injected = |r: &propid_sim::pty::SimReport| {
        let f = r.faults;
        (
            f.corrupted_frames + f.garbage_bursts,
            f.dropped_samples + f.corrupted_samples,
        )
    };
    let s0 = injected(&sim.report());
    let d0 = dec.stats().dropped.total();
    let mut frames = collect(&mut *port, &mut dec, Duration::from_millis(400), |_| false);
    let s1 = injected(&sim.report());
    frames.extend(collect(
        &mut *port,
        &mut dec,
        Duration::from_millis(50),
        |_| false,
    ));
    let s2 = injected(&sim.report());
    let drops = dec.stats().dropped.total() - d0;
    assert!(s1.0 - s0.0 > 5, "too few faults to test: {s0:?} {s1:?}");
    assert!(
        drops + 2 >= s1.0 - s0.0 && drops <= s2.0 - s0.0 + 2,
        "host dropped {drops} frames, injected {} ..= {}",
        s1.0 - s0.0,
        s2.0 - s0.0
    );
    let idx = sample_indices(&frames);
    let gaps: u64 = idx.windows(2).map(|w| (w[1] - w[0] - 1) as u64).sum();
    assert!(
        gaps + 2 >= s1.1 - s0.1 && gaps <= s2.1 - s0.1 + 2,
        "sample gaps {gaps}, injected losses {} ..= {}",
        s1.1 - s0.1,
        s2.1 - s0.1
    );
    drop(sim);
}

#[test]
fn faults_stop_after_faults_for_and_the_tail_is_clean() {
    let mut cfg = SimConfig::default();
    cfg.faults.drop_sample_prob = 0.3;
    cfg.faults.bit_flip_per_byte = 0.01;
    let opts = RunOptions {
        faults_for: Some(0.3),
        ..RunOptions::default()
    };
    let sim = SimHandle::spawn(cfg, opts).unwrap();
    let t0 = Instant::now();
    let mut port = open(sim.path());
    let mut dec = Decoder::new();
    let _ = collect(&mut *port, &mut dec, Duration::from_millis(450), |_| false);
    let during = sim.report();
    assert!(t0.elapsed() >= Duration::from_millis(300));
    let drops = dec.stats().dropped.total();
    let tail = collect(&mut *port, &mut dec, Duration::from_millis(200), |_| false);
    let after = sim.report();
    assert!(during.faults.dropped_samples > 0, "{during:?}");
    assert_eq!(after.faults, during.faults, "no fault after faults_for");
    assert_eq!(dec.stats().dropped.total(), drops, "the tail decodes whole");
    let idx = sample_indices(&tail);
    assert!(idx.len() > 100, "the stand goes on: {} samples", idx.len());
    assert!(
        idx.windows(2).all(|w| w[1] == w[0] + 1),
        "no sample lost in the tail"
    );
    drop(sim);
}

#[test]
fn hang_up_closes_the_port_and_reopens_as_a_new_boot_behind_the_link() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let mut cfg = SimConfig::default();
    cfg.faults.hangup_after_s = 0.3;
    cfg.faults.reopen_after_ms = 100;
    let opts = RunOptions {
        link: Some(link.clone()),
        seconds: None,
        faults_for: None,
    };
    let sim = SimHandle::spawn(cfg, opts).unwrap();
    assert_eq!(sim.path(), link.as_path());
    let mut port = open(&link);
    let mut buf = [0u8; 1024];
    let t0 = Instant::now();
    let err = loop {
        match port.read(&mut buf) {
            Ok(0) => break std::io::ErrorKind::UnexpectedEof,
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => break e.kind(),
        }
        assert!(t0.elapsed() < Duration::from_secs(3), "no hang-up seen");
    };
    assert!(
        matches!(
            err,
            std::io::ErrorKind::BrokenPipe | std::io::ErrorKind::UnexpectedEof
        ) || err == std::io::ErrorKind::Other,
        "{err:?}"
    );
    let first_boot = sim.report().boot_id;
    drop(port);
    // Reconnect by the same path: a new boot.
    let t0 = Instant::now();
    while sim.report().boots < 2 {
        assert!(t0.elapsed() < Duration::from_secs(3), "no re-open");
        std::thread::sleep(Duration::from_millis(10));
    }
    let mut port = open(&link);
    let mut dec = Decoder::new();
    send(&mut *port, 9, Message::HelloReq);
    let frames = collect(&mut *port, &mut dec, Duration::from_secs(2), |f| {
        ack_of(f, 9).is_some()
    });
    assert_ne!(
        hello_of(&frames).expect("HELLO after re-open").boot_id,
        first_boot
    );
    let r = sim.stop().unwrap();
    assert_eq!((r.faults.hangups, r.faults.reopens), (1, 1));
}

#[test]
fn a_freeze_keeps_the_port_open_and_silent_until_the_host_closes_it_which_resets_the_board() {
    let mut cfg = SimConfig::default();
    cfg.faults.freeze_after_s = 0.3;
    let sim = SimHandle::spawn(cfg, RunOptions::default()).unwrap();
    let mut port = open(sim.path());
    let mut dec = Decoder::new();
    let first_boot = sim.report().boot_id;
    // samples flow, then stop: the port stays open (reads time out, never EOF or EIO)
    let t0 = Instant::now();
    while sim.report().faults.freezes == 0 {
        assert!(t0.elapsed() < Duration::from_secs(3), "no freeze");
        let _ = collect(&mut *port, &mut dec, Duration::from_millis(20), |_| false);
    }
    let _ = collect(&mut *port, &mut dec, Duration::from_millis(50), |_| false);
    send(&mut *port, 3, Message::HelloReq);
    let frames = collect(&mut *port, &mut dec, Duration::from_millis(300), |_| false);
    assert!(frames.is_empty(), "frozen: {frames:?}");
    assert_eq!(sim.report().boots, 1);
    // the host closes and reopens the port: a new boot on the same pty answers
    drop(port);
    std::thread::sleep(Duration::from_millis(50));
    let mut port = open(sim.path());
    send(&mut *port, 4, Message::HelloReq);
    let frames = collect(&mut *port, &mut dec, Duration::from_secs(2), |f| {
        ack_of(f, 4).is_some()
    });
    let hello = hello_of(&frames).expect("HELLO after the reset");
    assert_ne!(hello.boot_id, first_boot);
    let r = sim.stop().unwrap();
    assert_eq!((r.boots, r.faults.freezes, r.faults.hangups), (2, 1, 0));
}

#[test]
fn csv_dialect_over_the_pty() {
    let mut cfg = SimConfig::default();
    cfg.stand.protocol = propid_sim::config::WireProtocol::Csv;
    let sim = SimHandle::spawn(cfg, RunOptions::default()).unwrap();
    let mut port = open(sim.path());
    std::io::Write::write_all(&mut port, b"PING\nARM 500\n").unwrap();
    let mut text = String::new();
    let mut buf = [0u8; 4096];
    let t0 = Instant::now();
    let row = |t: &str| {
        t.lines()
            .any(|l| l.split(',').count() == 7 && l.contains('*'))
    };
    while !(text.contains("#ACK ARM OK") && row(&text)) && t0.elapsed() < Duration::from_secs(2) {
        if let Ok(n) = port.read(&mut buf) {
            text.push_str(&String::from_utf8_lossy(&buf[..n]));
        }
    }
    assert!(text.contains("#ACK PING OK"), "{text}");
    assert!(text.contains("# HELLO propid-sim"), "{text}");
    assert!(text.contains("#ACK ARM OK"), "{text}");
    assert!(row(&text), "{text}");
    drop(sim);
}

/// What a host that follows the stand through its hang-ups saw: per connection a new decoder,
/// a new boot at every connection, at a HELLO with a new boot id and where the index goes back.
#[derive(Debug, Default)]
struct HostView {
    samples: u64,
    gaps: u64,
    frames_dropped: u64,
    connections: u64,
    boots: u64,
}

fn follow(link: &std::path::Path, done: &std::sync::atomic::AtomicBool) -> HostView {
    use std::sync::atomic::Ordering;
    let mut v = HostView::default();
    let mut buf = [0u8; 4096];
    while !done.load(Ordering::Relaxed) {
        let Ok(mut port) = serialport::new(link.to_string_lossy(), 921_600)
            .timeout(Duration::from_millis(20))
            .open()
        else {
            std::thread::sleep(Duration::from_millis(10));
            continue;
        };
        v.connections += 1;
        v.boots += 1;
        let mut dec = Decoder::new();
        let (mut boot, mut last) = (None::<u32>, None::<u32>);
        loop {
            let n = match port.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => continue,
                Err(_) => break,
            };
            dec.push(&buf[..n], |f| match f.msg {
                Message::Hello(h) => {
                    if boot.is_some_and(|b| b != h.boot_id) && last.is_some() {
                        v.boots += 1;
                        last = None;
                    }
                    boot = Some(h.boot_id);
                }
                Message::Sample(s) => {
                    v.samples += 1;
                    match last {
                        Some(l) if s.sample_index > l => v.gaps += (s.sample_index - l - 1) as u64,
                        Some(_) => v.boots += 1, // back: a reset whose HELLO was not seen
                        None => {}
                    }
                    last = Some(s.sample_index);
                }
                _ => {}
            });
        }
        v.frames_dropped += dec.stats().dropped.total();
    }
    v
}

#[test]
fn scheduled_hang_ups_and_resets_leave_every_sample_and_fault_accounted_for() {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let mut cfg = SimConfig::default();
    cfg.faults.bit_flip_per_byte = 0.002;
    cfg.faults.garbage_bursts_per_s = 20.0;
    cfg.faults.drop_sample_prob = 0.02;
    cfg.faults.stalls_per_s = 5.0;
    cfg.faults.stall_ms = 20;
    cfg.faults.hangup_every_s = 0.5;
    cfg.faults.reset_every_s = 0.7;
    cfg.faults.reopen_after_ms = 50;
    let opts = RunOptions {
        link: Some(link.clone()),
        seconds: None,
        faults_for: Some(1.8),
    };
    let sim = SimHandle::spawn(cfg, opts).unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let host = {
        let (link, done) = (link.clone(), Arc::clone(&done));
        std::thread::spawn(move || follow(&link, &done))
    };
    std::thread::sleep(Duration::from_millis(2200));
    // the stop cuts the link as a hang-up does: what is on the wire reaches the host first
    let r = sim.stop().unwrap();
    done.store(true, Ordering::Relaxed);
    let v = host.join().unwrap();
    let f = r.faults;
    // hang-ups at 0.5, 1.0, 1.5 s, resets at 0.7, 1.4 s (each skipped if no host was there)
    assert!(f.hangups >= 2 && f.resets >= 1, "{r:?}");
    assert_eq!(f.reopens, f.hangups);
    assert_eq!(r.boots, 1 + f.hangups + f.resets, "{r:?}");
    assert_eq!(v.connections, 1 + f.hangups, "{v:?}");
    assert_eq!(v.boots, r.boots, "{v:?} {r:?}");
    assert_eq!(r.bytes_unread_at_hangups, 0);
    assert_eq!(
        v.gaps,
        f.dropped_samples + f.corrupted_samples,
        "{v:?} {f:?}"
    );
    assert_eq!(
        v.frames_dropped,
        f.corrupted_frames + f.garbage_bursts,
        "{v:?} {f:?}"
    );
    // every sample the stand took: received, lost to a fault, cut or taken with the link down
    assert_eq!(
        v.samples + v.gaps + f.samples_cut + f.samples_unsent,
        r.samples_total,
        "{v:?} {r:?}"
    );
}
