//! Recordings written by the simulated stand (`propid sim --record`, the firmware side of
//! TSP/1) read back through `ingest::read_record`: the record has every sample, the device's
//! impulse edges at their exact samples, the gaps of dropped and corrupted samples as missing
//! samples (counted, never bridged), and the device clock unwrapped.

use propid_ingest::read_record;
use propid_sim::config::SimConfig;
use propid_sim::record::record;
use propid_wire::protocol::{Decoder, Message};
use propid_wire::record::RecordEventKind;

fn sample_indices(bytes: &[u8]) -> Vec<u32> {
    let mut dec = Decoder::new();
    let mut idx = Vec::new();
    dec.push(bytes, |f| {
        if let Message::Sample(s) = f.msg {
            idx.push(s.sample_index)
        }
    });
    idx
}

#[test]
fn clean_recording_gives_a_complete_record_with_exact_impulse_edges() {
    let cfg = SimConfig::default();
    let mut bytes = Vec::new();
    let sum = record(&cfg, 12.0, &mut bytes).unwrap();
    let (r, s) = read_record(&bytes).unwrap();
    assert_eq!(r.missing_count(), 0);
    assert_eq!(r.len() as u64, sum.firmware.samples);
    assert_eq!(s.assemble.samples_lost, 0);
    assert_eq!(s.frames.unwrap().dropped.total(), 0);
    assert_eq!(s.build.link_frames_lost, 0);
    let rate = cfg.stand.sample_rate_hz as f64;
    assert!((r.dt_s * rate - 1.0).abs() < 1e-9, "dt {}", r.dt_s);
    assert!(r.channel("thrust_N").is_some());
    let throttle = &r.channel("throttle").unwrap().data;
    let starts: Vec<usize> = r.impulse_starts().collect();
    assert_eq!(starts.len() as u32, sum.pulses);
    assert!(!starts.is_empty());
    for k in starts {
        // The pulse sample differs from the sample before it (the setpoint).
        assert_ne!(throttle[k], throttle[k - 1], "pulse at {k}");
    }
    let ends = r
        .events
        .iter()
        .filter(|e| e.kind == RecordEventKind::ImpulseEnd)
        .count();
    assert_eq!(ends as u32, sum.pulses);
}

#[test]
fn faulty_recording_marks_exactly_the_lost_samples_missing() {
    let mut cfg = SimConfig::default();
    cfg.faults.bit_flip_per_byte = 0.001;
    cfg.faults.garbage_bursts_per_s = 10.0;
    cfg.faults.drop_sample_prob = 0.01;
    let mut bytes = Vec::new();
    let sum = record(&cfg, 6.0, &mut bytes).unwrap();
    let idx = sample_indices(&bytes);
    let inner: u64 = idx.windows(2).map(|w| (w[1] - w[0] - 1) as u64).sum();
    assert!(inner > 10);
    let (r, s) = read_record(&bytes).unwrap();
    assert_eq!(s.assemble.samples_lost, inner);
    assert_eq!(r.missing_count() as u64, inner);
    assert_eq!(r.len(), (idx[idx.len() - 1] - idx[0] + 1) as usize);
    assert_eq!(s.assemble.samples, idx.len() as u64);
    assert_eq!(
        s.frames.unwrap().dropped.total(),
        sum.faults.frames_dropped()
    );
    // Corrupted frames are link losses; dropped samples are not.
    assert_eq!(s.build.link_frames_lost, sum.faults.corrupted_frames);
    // NaN exactly at the missing samples.
    for c in &r.channels {
        for (k, v) in c.data.iter().enumerate() {
            assert_eq!(v.is_nan(), r.missing[k], "{} at {k}", c.name);
        }
    }
}

#[test]
fn device_clock_wrap_inside_a_recording() {
    let mut cfg = SimConfig::default();
    cfg.stand.initial_t_us = u32::MAX - 1_000_000; // wraps one second in
    let mut bytes = Vec::new();
    record(&cfg, 3.0, &mut bytes).unwrap();
    let (r, s) = read_record(&bytes).unwrap();
    assert_eq!(s.assemble.clock_wraps, 1);
    assert_eq!(s.assemble.segments, 1);
    let rate = cfg.stand.sample_rate_hz as f64;
    assert!((r.dt_s * rate - 1.0).abs() < 1e-9, "dt {}", r.dt_s);
}
