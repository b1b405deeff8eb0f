//! The worker's hot path allocates nothing: window bookkeeping and the core identification
//! over a whole experiment recorded from the simulated stand (noise and quantisation on),
//! counted by a global allocator. A few isolated outlier samples (3 N spikes) make the
//! outlier rule leave some out on the way.

use crate::counting_alloc;

use counting_alloc::allocations;
use propid::daemon::identify::CoreIdentifier;
use propid::daemon::item::SampleItem;
use propid::daemon::window::{OutputChannel, Window};
use propid::daemon::worker::Identifier;
use propid::daemon::Config;
use propid_numerics::svd::SvdChoice;
use propid_sim::SimConfig;
use propid_wire::protocol::message::Message;
use propid_wire::protocol::Decoder;
use std::time::Instant;

#[test]
fn window_and_identification_allocate_nothing_on_both_svd_paths() {
    for svd in [SvdChoice::Auto, SvdChoice::Dense, SvdChoice::Truncated] {
        window_and_identification_allocate_nothing(svd);
    }
}

fn window_and_identification_allocate_nothing(svd: SvdChoice) {
    let cfg = Config::default();
    // three operating points of 8 pulses, 0.01 N of noise, 1 mN quantisation
    let mut bytes = Vec::new();
    let sum = propid_sim::record::record(&SimConfig::default(), 120.0, &mut bytes).unwrap();
    assert!(sum.finished);
    let mut frames = Vec::new();
    Decoder::new().push(&bytes, |f| frames.push(f));
    let now = Instant::now();
    let samples: Vec<SampleItem> = frames
        .into_iter()
        .filter_map(|f| match f.msg {
            Message::Sample(s) => Some(SampleItem {
                index: u64::from(s.sample_index),
                t_us: u64::from(s.t_us),
                throttle_raw: s.throttle,
                flags: s.flags.bits(),
                // an isolated spike every ~5 s of samples
                thrust_n: s.thrust_n
                    + if s.sample_index % 5003 == 2500 {
                        3.0
                    } else {
                        0.0
                    },
                torque_nm: f32::NAN,
                rpm: f32::NAN,
                voltage_v: f32::NAN,
                current_a: f32::NAN,
                received: now,
            }),
            _ => None,
        })
        .collect();
    let mut window = Window::new(
        cfg.identify.max_window_samples,
        cfg.identify.pulses_per_model as usize,
        cfg.identify.level_tolerance,
        OutputChannel::Thrust,
    );
    let mut id = CoreIdentifier::new(&cfg).unwrap().with_svd(svd);
    let mut ok = 0u32;
    let mut failed = 0u32;
    let mut outliers = 0usize;
    // counted on this thread only (the test harness's other threads may allocate)
    let (allocs, ()) = allocations(|| {
        for s in &samples {
            window.on_sample(s, |v| match id.identify(v) {
                Ok(()) => {
                    ok += 1;
                    outliers += id.outliers();
                }
                Err(_) => failed += 1,
            });
        }
        window.finish(|v| match id.identify(v) {
            Ok(()) => {
                ok += 1;
                outliers += id.outliers();
            }
            Err(_) => failed += 1,
        });
    });
    assert_eq!((ok, failed), (6, 0), "{svd:?}");
    assert!(outliers > 0, "the spikes in windows are left out ({svd:?})");
    assert_eq!(allocs, 0, "allocations in the hot path ({svd:?})");
}

/// The sampler's side of the recording: each read is copied into a preallocated chunk and
/// handed to the recorder thread; when the recorder falls behind (a pipe whose reader never
/// reads) the bytes are dropped and counted. Neither allocates on the sampler's thread.
#[test]
fn the_recording_allocates_nothing_per_read_on_the_sampler() {
    use propid::daemon::recorder::{Recorder, CHUNK, CHUNKS};
    use std::os::unix::ffi::OsStrExt;
    use std::os::unix::fs::OpenOptionsExt;
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    let c = std::ffi::CString::new(fifo.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let _reader = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(&fifo)
        .unwrap();
    let read = [5u8; 4096];
    for path in [dir.path().join("rec.tsp"), fifo] {
        let mut r = Recorder::create(&path, Some(1 << 20)).unwrap();
        let mut notes = 0;
        r.tick(&mut |_| notes += 1); // the first file's note
        let (allocs, ()) = allocations(|| {
            for _ in 0..2 * CHUNKS * CHUNK / read.len() {
                r.write(&read);
                r.tick(&mut |_| notes += 1);
            }
        });
        assert_eq!(allocs, 0, "{path:?}");
        let mut last = Vec::new();
        r.finish(std::time::Duration::from_millis(200), &mut |n| last.push(n));
        assert!(notes >= 1);
        if path.ends_with("pipe") {
            assert!(r.bytes_dropped() > 0, "the pipe is never read");
        }
    }
}
