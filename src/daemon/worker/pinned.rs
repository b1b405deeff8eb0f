//! Every kind of line the worker publishes, pinned byte for byte: keys, their order (sorted),
//! number formatting and the fixed messages, as `pinned_lines.jsonl` holds them (one line each,
//! in order). A change of the published bytes fails here.

use super::*;
use crate::daemon::fixtures::report;
use crate::daemon::item::{flags, EventItem, Notice, PlanNote};
use crate::daemon::window::OutputChannel;
use propid_numerics::{IdentError, ModelReport};
use serde_json::json;
use std::time::Instant;

/// The fixture's model report; `unstable` puts the poles in the right half-plane.
fn pinned_report(unstable: bool) -> ModelReport {
    let re = if unstable { 3.0 } else { -39.25 };
    report(json!({"poles_s": [[re, 68.0], [re, -68.0]]}))
}

/// Identifications 1 and 4 give the pinned model, 2 an unstable one, 3 fails.
struct Pinned {
    calls: usize,
}

impl Identifier for Pinned {
    fn identify(&mut self, _: &WindowView<'_>) -> Result<(), IdentifyError> {
        self.calls += 1;
        match self.calls {
            3 => Err(IdentError::NoPulse.into()),
            _ => Ok(()),
        }
    }
    fn report(&self) -> Result<ModelReport, IdentifyError> {
        Ok(pinned_report(self.calls == 2))
    }
}

fn sample(index: u64, throttle_raw: u16, flags: u16) -> Item {
    Item::Sample(SampleItem {
        index,
        t_us: index * 1000,
        throttle_raw,
        flags,
        thrust_n: 1.0,
        torque_nm: 0.0,
        rpm: 0.0,
        voltage_v: f32::NAN,
        current_a: f32::NAN,
        received: Instant::now(),
    })
}

/// The lines of a run that publishes every kind the worker knows.
fn pinned_run() -> Vec<String> {
    let (publisher, lines) = Publisher::capture();
    let window = Window::new(1000, 1, 0.005, OutputChannel::Thrust);
    let mut w = Worker::new(window, Pinned { calls: 0 }, publisher);
    w.handle(Item::Segment { boot_id: 7 });
    for n in [
        Notice::Disconnected,
        Notice::Reconnected {
            device_node: Some("/dev/ttyACM1".into()),
        },
        Notice::Stopped,
        Notice::StopUnacknowledged,
        Notice::CsvLink,
        Notice::PassiveBench,
        Notice::NoData,
        Notice::LinkStalled {
            silent_ms: 1200,
            stop_acknowledged: false,
        },
        Notice::LinkResumed { silent_ms: 2500 },
    ] {
        w.handle(Item::Notice(n));
    }
    for n in [
        PlanNote::Connected { boot_id: 7 },
        PlanNote::Armed,
        PlanNote::LevelReached {
            index: 0,
            level: 0.3,
        },
        PlanNote::PulseFired,
        PlanNote::LevelDone {
            index: 0,
            level: 0.3,
        },
        PlanNote::Finished,
        PlanNote::Stopped,
        PlanNote::DeviceReset {
            new_boot_id: 8,
            rearm: false,
        },
        PlanNote::DeviceReset {
            new_boot_id: 9,
            rearm: true,
        },
        PlanNote::WatchdogTripped,
        PlanNote::Refused { command: "ARM" },
        PlanNote::LinkFailed { command: "PULSE" },
        PlanNote::RearmLimit { rearms: 3 },
        PlanNote::LimitUnchecked {
            which: "max_temperature_c",
            why: "no SAMPLE (nor CSV row) carries a temperature",
        },
        PlanNote::LimitTripped {
            which: "max_current_a",
            value: 12.5,
            limit: 10.0,
        },
    ] {
        w.handle(Item::Plan(n));
    }
    for code in [1u8, 2, 3, 4, 5, 6, 7, 8, 9, 42] {
        w.handle(Item::Event(EventItem {
            code,
            arg: 3,
            t_us: 1_500,
            sample_index: 2,
        }));
    }
    // level 0.3, a pulse every 100 samples from 50: models at the starts of pulses 2, 3, 4
    for i in 0..380u64 {
        if i == 300 {
            w.handle(Item::Gap {
                before: 305,
                count: 5,
            });
            continue;
        }
        if (301..305).contains(&i) {
            continue;
        }
        // 320..323 never arrive and no gap announces them
        if (320..323).contains(&i) {
            continue;
        }
        let pulse = i % 100 == 50;
        let f = if pulse { flags::IMPULSE_ACTIVE } else { 0 };
        w.handle(sample(i, if pulse { 3500 } else { 3000 }, f));
    }
    // a new level without pulses fills the window (capacity 1000)
    for i in 380..1400u64 {
        w.handle(sample(i, 4500, 0));
    }
    let out = w.finish();
    drop(out.publisher);
    let lines = lines.lock().unwrap().clone();
    lines
}

#[test]
fn every_published_line_is_pinned() {
    let got = pinned_run();
    // A deliberate change of the published lines is pinned again with
    // `PROPID_REPIN=1 cargo test --release -p propid --lib pinned`; review the diff.
    if std::env::var_os("PROPID_REPIN").is_some() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/src/daemon/worker/pinned_lines.jsonl"
        );
        std::fs::write(path, got.join("\n") + "\n").expect("write the pinned lines");
        return;
    }
    let want: Vec<&str> = include_str!("pinned_lines.jsonl").lines().collect();
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g, w);
    }
}
