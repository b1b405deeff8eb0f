//! The sampler against scripted sources and simulated-stand recordings: detection, reconnects,
//! overflows, large gaps, silence and shutdown.

use super::*;
use crate::daemon::item::SampleItem;
use crate::daemon::source::{ScriptedSource, Step};
use propid_sim::record::{record, RecordSummary};
use propid_sim::SimConfig;
use propid_wire::protocol::message::{Hello, Sample, SampleFlags};
use propid_wire::protocol::{encode_frame, Decoder, EscProtocol};

fn cfg() -> SamplerConfig {
    SamplerConfig {
        stop_timeout: Duration::from_millis(100),
        max_run: None,
        reconnect_initial: Duration::from_millis(1),
        reconnect_max: Duration::from_millis(2),
        protocol: WireProtocol::Auto,
        csv: CsvLinkOptions::default(),
        silence_timeout: SILENCE_TIMEOUT,
        stall_timeout: None,
    }
}

/// A recording of the simulated stand (`propid sim --record`: firmware + plan, faster than
/// real time): one operating point, `pulses` pulses; and what it holds.
fn stand(pulses: u32) -> (Vec<u8>, RecordSummary) {
    let mut cfg = SimConfig::default();
    cfg.experiment.levels = vec![0.4];
    cfg.experiment.pulses_per_level = pulses;
    let mut bytes = Vec::new();
    let sum = record(&cfg, 60.0, &mut bytes).unwrap();
    assert!(sum.finished);
    (bytes, sum)
}

/// SAMPLE frames the recording holds intact.
fn samples_sent(sum: &RecordSummary) -> u64 {
    sum.firmware.samples - sum.faults.samples_lost()
}

#[test]
fn csv_stream_is_decoded_by_auto_and_by_csv() {
    let mut csv = String::from("t_us,throttle,thrust_N\n");
    for k in 0..100 {
        let thr = if k % 25 == 10 { 3500 } else { 3000 };
        csv += &format!("{},{thr},1.0\n", 5_000 + k * 1000);
    }
    for protocol in [WireProtocol::Auto, WireProtocol::Csv] {
        let src = ScriptedSource::new(vec![Step::Data(csv.clone().into_bytes())]);
        let (tx, rx) = crossbeam_channel::bounded(1024);
        let c = SamplerConfig { protocol, ..cfg() };
        let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), c).run();
        assert!(out.error.is_none(), "{:?}", out.error);
        assert_eq!(out.stats.wire, "csv");
        assert_eq!(out.stats.samples, 100);
        assert_eq!(out.stats.frames_ok, 101);
        assert_eq!(out.stats.samples_lost, 0);
        let items: Vec<Item> = rx.try_iter().collect();
        let notices = items
            .iter()
            .filter(|i| **i == Item::Notice(Notice::CsvLink));
        assert_eq!(notices.count(), 1);
        let samples: Vec<&SampleItem> = items
            .iter()
            .filter_map(|i| match i {
                Item::Sample(s) => Some(s),
                _ => None,
            })
            .collect();
        assert_eq!(samples.len(), 100);
        let pulses = samples
            .iter()
            .filter(|s| s.flags & crate::daemon::item::flags::IMPULSE_ACTIVE != 0)
            .count();
        assert_eq!(pulses, 4);
        assert!(samples.iter().enumerate().all(|(k, s)| s.index == k as u64));
    }
}

#[test]
fn binary_stream_passes_detection() {
    let (bytes, sum) = stand(1);
    let src = ScriptedSource::new(vec![Step::Data(bytes)]);
    let (tx, _rx) = crossbeam_channel::bounded(1 << 16);
    let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), cfg()).run();
    assert!(out.error.is_none());
    assert_eq!(out.stats.samples, samples_sent(&sum));
    assert_eq!(out.stats.frames_ok, sum.decode.frames_ok);
}

#[test]
fn hangup_reconnects_and_counts_everything_once() {
    let (bytes, sum) = stand(2);
    let half = bytes.len() / 2;
    let mut src = ScriptedSource::new(vec![
        Step::Data(bytes[..half].to_vec()),
        Step::Stall,
        Step::Hangup,
        Step::Data(bytes[half..].to_vec()),
    ]);
    src.refuse_reconnects = 2;
    let (tx, rx) = crossbeam_channel::bounded(1 << 16);
    let s = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), cfg());
    let out = s.run();
    assert!(out.error.is_none());
    assert_eq!(out.stats.reconnects, 1);
    assert_eq!(out.stats.samples, samples_sent(&sum));
    assert_eq!(out.stats.frames_ok, sum.decode.frames_ok);
    assert_eq!(out.stats.samples_lost, 0);
    let notices: Vec<Notice> = rx
        .try_iter()
        .filter_map(|i| match i {
            Item::Notice(n) => Some(n),
            _ => None,
        })
        .collect();
    assert_eq!(
        notices,
        vec![
            Notice::Disconnected,
            Notice::Reconnected { device_node: None }
        ]
    );
}

#[test]
fn full_queue_is_counted_as_overflow_never_waited_for() {
    let (bytes, sum) = stand(2);
    // what the sampler queues for this stream: the first HELLO's segment, every SAMPLE
    // and every EVENT (ACKs, LOGs and repeated HELLOs of the same boot are not queued)
    let mut items = 1u64;
    Decoder::new().push(&bytes, |f| {
        if matches!(f.msg, Message::Sample(_) | Message::Event(_)) {
            items += 1;
        }
    });
    let src = ScriptedSource::new(vec![Step::Data(bytes)]);
    let (tx, rx) = crossbeam_channel::bounded(16);
    let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), cfg()).run();
    let queued: Vec<Item> = rx.try_iter().collect();
    assert_eq!(queued.len(), 16);
    // every sample and event beyond the 16 queued items was dropped and counted
    assert_eq!(out.stats.overflows, items - 16);
    assert_eq!(out.stats.samples, samples_sent(&sum));
    // every dropped sample is lost to the worker: counted in samples_lost
    let queued_samples = queued
        .iter()
        .filter(|i| matches!(i, Item::Sample(_)))
        .count() as u64;
    assert_eq!(out.stats.samples_lost, samples_sent(&sum) - queued_samples);
}

fn frame(seq: u16, msg: Message) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(seq, &msg, &mut buf);
    buf[..n].to_vec()
}

fn sample(index: u32) -> Message {
    Message::Sample(Sample {
        sample_index: index,
        t_us: index.wrapping_mul(1000),
        throttle: 4000,
        flags: SampleFlags(SampleFlags::THRUST_VALID.bits()),
        thrust_n: 1.0,
        torque_nm: f32::NAN,
        rpm: f32::NAN,
        voltage_v: f32::NAN,
        current_a: f32::NAN,
    })
}

#[test]
fn index_jump_beyond_the_largest_gap_is_a_new_segment_not_a_bridged_gap() {
    let hello = Message::Hello(Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::from_u8(5),
        fw_version: 1,
        boot_id: 77,
        t_us: 0,
        sample_rate_hz: 1000,
        channels: 1,
        motor_poles: 14,
        caps: 0,
        name: Hello::name_field("t"),
    });
    let mut bytes = frame(0, hello);
    let indices = [0u32, 1, 2, 3, 200_000, 200_001];
    for (seq, &i) in indices.iter().enumerate() {
        bytes.extend(frame(seq as u16 + 1, sample(i)));
    }
    let src = ScriptedSource::new(vec![Step::Data(bytes)]);
    let (tx, rx) = crossbeam_channel::bounded(64);
    let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), cfg()).run();
    let kinds: Vec<String> = rx
        .try_iter()
        .map(|i| match i {
            Item::Sample(s) => format!("sample {}", s.index),
            Item::Gap { before, count } => format!("gap {count} before {before}"),
            Item::Segment { boot_id } => format!("segment {boot_id}"),
            other => format!("{other:?}"),
        })
        .collect();
    assert_eq!(
        kinds,
        [
            "segment 77",
            "sample 0",
            "sample 1",
            "sample 2",
            "sample 3",
            "segment 0",
            "gap 199996 before 200000",
            "sample 200000",
            "sample 200001",
        ]
    );
    let s = &out.stats;
    assert_eq!((s.samples, s.samples_lost), (6, 199_996));
    assert_eq!((s.gaps, s.large_gaps), (1, 1));
}

/// A live link that never says anything.
struct Silent;
impl Source for Silent {
    fn read(&mut self, _: &mut [u8]) -> Result<usize, SourceError> {
        std::thread::sleep(Duration::from_millis(2));
        Ok(0)
    }
    fn write_all(&mut self, _: &[u8]) -> Result<(), SourceError> {
        Ok(())
    }
    fn reconnect(&mut self) -> Result<(), SourceError> {
        Ok(())
    }
    fn is_live(&self) -> bool {
        true
    }
    fn describe(&self) -> String {
        "silent".into()
    }
}

/// A plan that only counts how often it was told the link is up.
struct Counting(std::sync::Arc<std::sync::atomic::AtomicUsize>);
impl Plan for Counting {
    fn on_connect(&mut self, _: u64) {
        self.0.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    }
    fn on_frame(&mut self, _: u64, _: &Frame) {}
    fn poll(&mut self, _: u64) {}
    fn abort(&mut self, _: u64) {}
    fn on_stall(&mut self, _: u64) {}
    fn next(&mut self, _: &mut dyn FnMut(u16, &Message), _: &mut dyn FnMut(PlanNote)) {}
    fn status(&self) -> PlanStatus {
        PlanStatus::Running
    }
}

#[test]
fn a_silent_auto_link_is_reported_once_and_the_plan_starts_anyway() {
    let connects = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let plan: Box<dyn Plan> = Box::new(Counting(connects.clone()));
    let (tx, rx) = crossbeam_channel::bounded(64);
    let c = SamplerConfig {
        silence_timeout: Duration::from_millis(30),
        max_run: Some(Duration::from_millis(150)),
        ..cfg()
    };
    let out = Sampler::new(
        Box::new(Silent),
        tx,
        Some(plan),
        None,
        Shutdown::manual(),
        c,
    )
    .run();
    assert!(out.error.is_none());
    assert_eq!(out.stats.wire, "undecided");
    let items: Vec<Item> = rx.try_iter().collect();
    assert_eq!(
        items,
        vec![
            Item::Notice(Notice::NoData),
            Item::Notice(Notice::StopUnacknowledged)
        ]
    );
    assert_eq!(connects.load(std::sync::atomic::Ordering::SeqCst), 1);
}

#[test]
fn shutdown_sends_stop_and_reports_it_unacknowledged_without_a_device() {
    let src = ScriptedSource::new(vec![Step::Stall; 1000]);
    let (tx, rx) = crossbeam_channel::bounded(64);
    let stop = Shutdown::manual();
    stop.request();
    let out = Sampler::new(Box::new(src), tx, None, None, stop, cfg()).run();
    assert!(out.error.is_none());
    let items: Vec<Item> = rx.try_iter().collect();
    assert_eq!(items, vec![Item::Notice(Notice::StopUnacknowledged)]);
}

/// A live link that sends `bytes` once after each (re)open, then nothing; counts its closes
/// and reopens and what it was sent.
struct SpeaksOnce {
    bytes: Vec<u8>,
    pending: bool,
    open: bool,
    log: std::sync::Arc<std::sync::Mutex<(u32, u32, Vec<u8>)>>,
}
impl Source for SpeaksOnce {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, SourceError> {
        if !self.open {
            return Err(SourceError::Disconnected {
                what: "speaks-once".into(),
                source: std::io::Error::other("closed"),
            });
        }
        if std::mem::take(&mut self.pending) {
            buf[..self.bytes.len()].copy_from_slice(&self.bytes);
            return Ok(self.bytes.len());
        }
        std::thread::sleep(Duration::from_millis(2));
        Ok(0)
    }
    fn write_all(&mut self, b: &[u8]) -> Result<(), SourceError> {
        self.log.lock().unwrap().2.extend_from_slice(b);
        Ok(())
    }
    fn close(&mut self) {
        self.open = false;
        self.log.lock().unwrap().0 += 1;
    }
    fn reconnect(&mut self) -> Result<(), SourceError> {
        self.open = true;
        self.pending = true;
        self.log.lock().unwrap().1 += 1;
        Ok(())
    }
    fn is_live(&self) -> bool {
        true
    }
    fn describe(&self) -> String {
        "speaks-once".into()
    }
}

#[test]
fn a_link_silent_past_the_stall_timeout_gets_stop_a_warning_and_a_reopen_each_time_it_stalls() {
    let log = std::sync::Arc::new(std::sync::Mutex::new((0, 0, Vec::new())));
    let src = SpeaksOnce {
        bytes: frame(1, sample(0)),
        pending: true,
        open: true,
        log: log.clone(),
    };
    let (tx, rx) = crossbeam_channel::bounded(1024);
    let c = SamplerConfig {
        protocol: WireProtocol::Tsp,
        stall_timeout: Some(Duration::from_millis(40)),
        stop_timeout: Duration::from_millis(60),
        max_run: Some(Duration::from_millis(600)),
        ..cfg()
    };
    let out = Sampler::new(Box::new(src), tx, None, None, Shutdown::manual(), c).run();
    assert!(out.error.is_none());
    let items: Vec<Item> = rx.try_iter().collect();
    let stalls: Vec<&Item> = items
        .iter()
        .filter(|i| matches!(i, Item::Notice(Notice::LinkStalled { .. })))
        .collect();
    // every stall: ~40 ms silent, ~60 ms of STOP, ~1 ms closed; the device speaks after each
    // reopen, so each silence is a new stall
    let n = out.stats.stalls;
    assert!((2..=6).contains(&n), "{n} {items:?}");
    assert_eq!(stalls.len() as u64, n);
    match stalls[0] {
        Item::Notice(Notice::LinkStalled {
            silent_ms,
            stop_acknowledged,
        }) => {
            assert!(*silent_ms >= 40, "{silent_ms}");
            assert!(!stop_acknowledged);
        }
        _ => unreachable!(),
    }
    let (closes, reopens, written) = log.lock().unwrap().clone();
    assert_eq!(closes as u64, n);
    // the last stall may close the port with the run's time up: no reopen then
    let reopens = reopens as u64;
    assert!(reopens == n || reopens + 1 == n, "{reopens} {n}");
    assert_eq!(out.stats.reconnects, reopens);
    // the STOP of our own (no plan), re-sent every 50 ms, before each reopen
    let stop = frame(STOP_SEQ, Message::Stop);
    let stops = written.windows(stop.len()).filter(|w| *w == stop).count() as u64;
    assert!(stops >= n, "{stops}");
}

/// What a [`Played`] link was sent: (reads done then, the bytes).
type WriteLog = std::sync::Arc<std::sync::Mutex<Vec<(usize, Vec<u8>)>>>;

/// A live link that plays one read per entry of `reads`, then nothing (a read that waits
/// 2 ms); logs how many reads, empty ones too, were done when each write came.
struct Played {
    reads: std::collections::VecDeque<Vec<u8>>,
    done: usize,
    writes: WriteLog,
}
impl Source for Played {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, SourceError> {
        self.done += 1;
        let Some(r) = self.reads.pop_front() else {
            std::thread::sleep(Duration::from_millis(2));
            return Ok(0);
        };
        buf[..r.len()].copy_from_slice(&r);
        Ok(r.len())
    }
    fn write_all(&mut self, b: &[u8]) -> Result<(), SourceError> {
        self.writes.lock().unwrap().push((self.done, b.to_vec()));
        Ok(())
    }
    fn reconnect(&mut self) -> Result<(), SourceError> {
        Ok(())
    }
    fn is_live(&self) -> bool {
        true
    }
    fn describe(&self) -> String {
        "played".into()
    }
}

/// A plan that is over (a device reset) once it sees a HELLO of boot 2.
struct EndsOnReset(bool);
impl Plan for EndsOnReset {
    fn on_connect(&mut self, _: u64) {}
    fn on_frame(&mut self, _: u64, f: &Frame) {
        if matches!(&f.msg, Message::Hello(h) if h.boot_id == 2) {
            self.0 = true;
        }
    }
    fn poll(&mut self, _: u64) {}
    fn abort(&mut self, _: u64) {}
    fn on_stall(&mut self, _: u64) {}
    fn next(&mut self, _: &mut dyn FnMut(u16, &Message), _: &mut dyn FnMut(PlanNote)) {}
    fn status(&self) -> PlanStatus {
        if self.0 {
            PlanStatus::Halted
        } else {
            PlanStatus::Running
        }
    }
}

fn hello(boot_id: u32) -> Message {
    Message::Hello(Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::from_u8(5),
        fw_version: 1,
        boot_id,
        t_us: 0,
        sample_rate_hz: 1000,
        channels: 1,
        motor_poles: 14,
        caps: 0,
        name: Hello::name_field("t"),
    })
}

#[test]
fn a_device_reset_that_ends_the_plan_is_sent_stop_before_the_next_read() {
    let mut first = frame(0, hello(1));
    first.extend(frame(1, sample(0)));
    let reads = vec![first, frame(2, sample(1)), frame(0, hello(2))];
    let writes = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let src = Played {
        reads: reads.into(),
        done: 0,
        writes: writes.clone(),
    };
    let (tx, rx) = crossbeam_channel::bounded(1024);
    let c = SamplerConfig {
        protocol: WireProtocol::Tsp,
        max_run: Some(Duration::from_secs(5)),
        ..cfg()
    };
    let plan: Box<dyn Plan> = Box::new(EndsOnReset(false));
    let out = Sampler::new(Box::new(src), tx, Some(plan), None, Shutdown::manual(), c).run();
    assert!(out.plan_halted, "the run ends on the fault");
    let stop = frame(STOP_SEQ, Message::Stop);
    let writes = writes.lock().unwrap();
    let first_stop = writes.iter().find(|(_, b)| *b == stop).expect("STOP sent");
    // at once: in the turn that read the reset's HELLO, not HALT_DRAIN later
    assert_eq!(first_stop.0, 3, "{writes:?}");
    let items: Vec<Item> = rx.try_iter().collect();
    assert!(items.contains(&Item::Notice(Notice::StopUnacknowledged)));
}
