//! The worker's unit tests: windows per level, unreliable models, overflow holes, failures.

use super::*;
use crate::daemon::fixtures::report;
use crate::daemon::item::{flags, EventItem};
use crate::daemon::window::OutputChannel;
use propid_numerics::{IdentError, ModelReport};
use serde_json::{json, Value};
use std::time::Instant;

/// A fake identifier: reports the window length and pulse count as the "model".
struct Fake {
    last: Option<(usize, usize)>,
    fail_every: usize,
    /// Every n-th model has an unstable pole (0 = never).
    unstable_every: usize,
    calls: usize,
}

impl Identifier for Fake {
    fn identify(&mut self, v: &WindowView<'_>) -> Result<(), IdentifyError> {
        self.calls += 1;
        if self.fail_every > 0 && self.calls % self.fail_every == 0 {
            return Err(IdentError::NoPulse.into());
        }
        self.last = Some((v.input.len(), v.pulse_starts.len()));
        Ok(())
    }
    fn report(&self) -> Result<ModelReport, IdentifyError> {
        let (n, p) = self.last.ok_or(IdentifyError::NoModel)?;
        let unstable = self.unstable_every > 0 && self.calls % self.unstable_every == 0;
        let re = if unstable { 3.0 } else { -30.0 };
        Ok(report(
            json!({"order": 2, "fn_hz": n as f64, "zeta": 0.5, "dc_gain": 1.0,
            "pulses": p, "poles_s": [[re, 40.0], [re, -40.0]]}),
        ))
    }
    /// One outlier in every other window.
    fn outliers(&self) -> usize {
        self.calls % 2
    }
}

fn sample(index: u64, raw: u16, f: u16) -> Item {
    Item::Sample(SampleItem {
        index,
        t_us: index * 1000,
        throttle_raw: raw,
        flags: f,
        thrust_n: 1.0,
        torque_nm: 0.0,
        rpm: 0.0,
        voltage_v: f32::NAN,
        current_a: f32::NAN,
        received: Instant::now(),
    })
}

fn run_levels(fail_every: usize, unstable_every: usize) -> Vec<Value> {
    let (publisher, lines) = Publisher::capture();
    let fake = Fake {
        last: None,
        fail_every,
        unstable_every,
        calls: 0,
    };
    let window = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
    let (tx, rx) = crossbeam_channel::bounded(100_000);
    let mut i = 0;
    for level in [3000u16, 4500, 6000] {
        for rel in 0..400u64 {
            let pulse = rel % 100 == 50;
            let f = if pulse { flags::IMPULSE_ACTIVE } else { 0 };
            let raw = if pulse { level + 800 } else { level };
            tx.send(sample(i, raw, f)).unwrap();
            i += 1;
        }
        for _ in 0..10 {
            tx.send(sample(i, level, flags::RAMP_ACTIVE)).unwrap();
            i += 1;
        }
    }
    tx.send(Item::Event(EventItem {
        code: 3,
        arg: 0,
        t_us: 5,
        sample_index: 5,
    }))
    .unwrap();
    drop(tx);
    let out = Worker::new(window, fake, publisher).run(rx);
    assert_eq!(out.stats.pulses, 12);
    let v = lines
        .lock()
        .unwrap()
        .iter()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    v
}

#[test]
fn publishes_models_per_level_and_the_schedule() {
    let lines = run_levels(0, 0);
    let models: Vec<&Value> = lines.iter().filter(|l| l["type"] == "model").collect();
    // 4 pulses per level, K = 2: one model at pulse 3, one at the level end.
    assert_eq!(models.len(), 6);
    assert_eq!(models[0]["operating_point"], 0.3);
    assert_eq!(models[0]["reason"], "pulses");
    assert_eq!(models[1]["reason"], "level_end");
    assert_eq!(models[0]["pulses"], 2);
    assert_eq!(models[0]["order"], 2);
    // the outliers left out, said only when there are some
    assert_eq!(models[0]["outliers"], 1);
    assert!(models[1].get("outliers").is_none(), "{}", models[1]);
    assert!(lines
        .iter()
        .any(|l| l["type"] == "warning" && l["kind"] == "watchdog_trip"));
    let sched = lines.last().unwrap();
    assert_eq!(sched["type"], "schedule");
    let rows = sched["models"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[2]["operating_point"], 0.6);
}

#[test]
fn an_unreliable_model_is_a_warning_and_stays_out_of_the_schedule() {
    // models 2, 4, 6 (the level-end one of each level) have an unstable pole
    let lines = run_levels(0, 2);
    let models: Vec<&Value> = lines.iter().filter(|l| l["type"] == "model").collect();
    assert_eq!(models.len(), 3);
    assert!(models.iter().all(|m| m["reason"] == "pulses"));
    let bad: Vec<&Value> = lines
        .iter()
        .filter(|l| l["kind"] == "model_unreliable")
        .collect();
    assert_eq!(bad.len(), 3);
    assert_eq!(bad[0]["type"], "warning");
    assert_eq!(bad[0]["reasons"], json!(["unstable_pole"]));
    assert_eq!(
        bad[0]["reason"], "level_end",
        "the numbers are kept for inspection"
    );
    // the schedule keeps each level's last reliable model
    let sched = lines.last().unwrap();
    assert_eq!(sched["type"], "schedule");
    let rows = sched["models"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for (row, m) in rows.iter().zip(&models) {
        assert_eq!(row["fn_hz"], m["fn_hz"]);
    }
}

#[test]
fn overflow_hole_inside_a_pulse_window_is_masked_and_reported() {
    let (publisher, lines) = Publisher::capture();
    /// Reports the masked samples of the window as `pulses_skipped`.
    struct Masked(Vec<usize>);
    impl Identifier for Masked {
        fn identify(&mut self, v: &WindowView<'_>) -> Result<(), IdentifyError> {
            self.0.push(v.missing.iter().filter(|m| **m).count());
            Ok(())
        }
        fn report(&self) -> Result<ModelReport, IdentifyError> {
            Ok(report(json!({ "pulses_skipped": self.0.last() })))
        }
    }
    let window = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
    let mut w = Worker::new(window, Masked(Vec::new()), publisher);
    for i in (0..200u64).filter(|i| !(60..70).contains(i)) {
        let pulse = i == 50;
        let f = if pulse { flags::IMPULSE_ACTIVE } else { 0 };
        w.handle(sample(i, if pulse { 3800 } else { 3000 }, f));
    }
    let out = w.finish();
    drop(out.publisher);
    let lines = lines.lock().unwrap();
    let v: Vec<Value> = lines
        .iter()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(v
        .iter()
        .any(|l| l["kind"] == "overflow_gap" && l["count"] == 10 && l["before"] == 70));
    let models: Vec<&Value> = v.iter().filter(|l| l["type"] == "model").collect();
    assert_eq!(models.len(), 1);
    assert_eq!(
        models[0]["pulses_skipped"], 10,
        "the hole is masked, not bridged"
    );
    assert_eq!(models[0]["samples"], 200);
}

#[test]
fn failed_identification_is_a_warning_not_a_model() {
    let lines = run_levels(2, 0);
    let models = lines.iter().filter(|l| l["type"] == "model").count();
    let failed = lines
        .iter()
        .filter(|l| l["kind"] == "identification_failed")
        .count();
    assert_eq!((models, failed), (3, 3));
}

#[test]
fn a_reset_before_k_pulses_is_a_named_and_counted_interrupted_window() {
    let (publisher, lines) = Publisher::capture();
    let fake = Fake {
        last: None,
        fail_every: 0,
        unstable_every: 0,
        calls: 0,
    };
    let window = Window::new(10_000, 4, 0.005, OutputChannel::Thrust);
    let (tx, rx) = crossbeam_channel::bounded(10_000);
    // 0.45: 3 of 4 pulses, then the device resets (a new segment); the new boot ramps again
    for i in 0..330u64 {
        let pulse = i % 100 == 50;
        let f = if pulse { flags::IMPULSE_ACTIVE } else { 0 };
        tx.send(sample(i, if pulse { 5300 } else { 4500 }, f))
            .unwrap();
    }
    tx.send(Item::Segment { boot_id: 9 }).unwrap();
    tx.send(sample(0, 0, flags::RAMP_ACTIVE)).unwrap();
    drop(tx);
    let out = Worker::new(window, fake, publisher).run(rx);
    assert_eq!((out.stats.pulses, out.stats.models), (3, 0));
    assert_eq!(out.stats.windows_interrupted, 1);
    let lines: Vec<Value> = lines
        .lock()
        .unwrap()
        .iter()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let cut: Vec<&Value> = lines
        .iter()
        .filter(|l| l["kind"] == "window_interrupted")
        .collect();
    assert_eq!(cut.len(), 1, "{lines:#?}");
    assert_eq!(cut[0]["type"], "warning");
    assert_eq!(cut[0]["operating_point"], 0.45);
    assert_eq!(cut[0]["pulses"], 3);
    assert!(cut[0]["message"].as_str().unwrap().contains("reset"));
    // before the segment line that announces the new boot
    let at = |k: &str| lines.iter().position(|l| l["kind"] == k).unwrap();
    assert!(at("window_interrupted") < at("segment"));
}
