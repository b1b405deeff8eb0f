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
