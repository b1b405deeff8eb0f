//! The injector's faults, one by one, and the cut's accounting.

use super::*;

fn frame(n: usize) -> Vec<u8> {
    let mut f = vec![0x11u8; n];
    f.push(0);
    f
}

#[test]
fn clean_config_passes_bytes_unchanged() {
    let mut inj = FaultInjector::new(&FaultConfig::default(), 1);
    inj.push_frame(&frame(10), FrameKind::Sample);
    let mut out = Vec::new();
    inj.drain_ready(1_000_000, &mut out);
    assert_eq!(out, frame(10));
    assert_eq!(inj.stats(), FaultStats::default());
}

#[test]
fn bit_flips_keep_frame_boundaries_and_are_counted() {
    let cfg = FaultConfig {
        bit_flip_per_byte: 0.05,
        ..FaultConfig::default()
    };
    let mut inj = FaultInjector::new(&cfg, 7);
    let mut out = Vec::new();
    for _ in 0..1000 {
        inj.push_frame(&frame(20), FrameKind::Sample);
    }
    inj.drain_ready(0, &mut out);
    let changed = out
        .chunks(21)
        .filter(|c| *c != frame(20).as_slice())
        .count() as u64;
    assert_eq!(
        out.iter().filter(|&&b| b == 0).count(),
        1000,
        "delimiters intact"
    );
    let s = inj.stats();
    assert_eq!(changed, s.corrupted_frames);
    // those after the last clean frame wait for one: no host could see them lost yet
    assert_eq!(s.corrupted_samples + inj.unseen.1, s.corrupted_frames);
    // P(frame) = 1 - 0.95^20 = 0.64
    assert!((500..800).contains(&s.corrupted_frames), "{s:?}");
}

#[test]
fn dropped_samples_never_touch_other_frames() {
    let cfg = FaultConfig {
        drop_sample_prob: 0.5,
        ..FaultConfig::default()
    };
    let mut inj = FaultInjector::new(&cfg, 3);
    for _ in 0..100 {
        if !inj.before_sample(0) {
            inj.push_frame(&frame(5), FrameKind::Sample);
        }
        inj.push_frame(&frame(3), FrameKind::Other);
    }
    let mut out = Vec::new();
    inj.drain_ready(0, &mut out);
    let s = inj.stats();
    let dropped = s.dropped_samples + inj.unseen.0;
    assert!(dropped > 20 && dropped < 80, "{s:?}");
    assert_eq!(out.len() as u64, 100 * 4 + (100 - dropped) * 6);
}

#[test]
fn garbage_bursts_arrive_at_their_rate_and_end_in_a_delimiter() {
    let cfg = FaultConfig {
        garbage_bursts_per_s: 100.0,
        garbage_burst_bytes: 10,
        ..FaultConfig::default()
    };
    let mut inj = FaultInjector::new(&cfg, 5);
    let mut out = Vec::new();
    inj.drain_ready(1_000_000, &mut out);
    let s = inj.stats();
    assert!((60..140).contains(&s.garbage_bursts), "{s:?}");
    assert_eq!(out.len() as u64, s.garbage_bytes);
    assert_eq!(
        out.iter().filter(|&&b| b == 0).count() as u64,
        s.garbage_bursts
    );
}

#[test]
fn disabled_injector_passes_everything_and_counts_nothing() {
    let cfg = FaultConfig {
        bit_flip_per_byte: 0.1,
        garbage_bursts_per_s: 100.0,
        drop_sample_prob: 0.5,
        stalls_per_s: 50.0,
        ..FaultConfig::default()
    };
    let mut inj = FaultInjector::new(&cfg, 9);
    inj.set_enabled(false);
    let mut out = Vec::new();
    for k in 0..100 {
        assert!(!inj.before_sample(k as u32));
        inj.push_frame(&frame(20), FrameKind::Sample);
        inj.drain_ready(k * 10_000, &mut out);
    }
    assert_eq!(out, frame(20).repeat(100));
    assert_eq!(inj.stats(), FaultStats::default());
    inj.set_enabled(true);
    inj.drain_ready(2_000_000, &mut out);
    assert!(inj.stats().garbage_bursts > 0, "on again");
}

#[test]
fn faults_by_sample_index_are_placed_and_counted_exactly() {
    let cfg = FaultConfig {
        drop_samples_at: vec![11, 10, 500],
        corrupt_samples_at: vec![20, 700, 701, 10],
        garbage_before_samples_at: vec![30, 900, 10],
        ..FaultConfig::default()
    };
    let mut inj = FaultInjector::new(&cfg, 1);
    let mut out = Vec::new();
    let mut sent = Vec::new();
    for k in 0..1000u32 {
        if !inj.before_sample(k) {
            sent.push(k);
            inj.push_frame(&frame(20), FrameKind::Sample);
        }
        inj.push_frame(&frame(8), FrameKind::Other);
        inj.drain_ready(u64::from(k), &mut out);
    }
    let s = inj.stats();
    // 10 is dropped (a dropped sample cannot also be corrupted); its burst still comes
    assert_eq!(s.dropped_samples, 3);
    assert_eq!((s.corrupted_frames, s.corrupted_samples), (3, 3));
    assert_eq!(s.garbage_bursts, 3);
    assert_eq!(sent.len(), 997);
    // every corrupted frame and every burst is one dropped frame, nothing else is
    assert_eq!(
        out.iter().filter(|&&b| b == 0).count() as u64,
        997 + 1000 + s.garbage_bursts
    );
    let changed = out
        .split_inclusive(|&b| b == 0)
        .filter(|c| c.len() == 21 && *c != frame(20).as_slice())
        .count();
    assert_eq!(changed, 3);
}

#[test]
fn stall_holds_output_then_releases_all_of_it() {
    let cfg = FaultConfig {
        stalls_per_s: 10.0,
        stall_ms: 50,
        ..FaultConfig::default()
    };
    let mut inj = FaultInjector::new(&cfg, 11);
    let mut out = Vec::new();
    let mut t = 0;
    while inj.stats().stalls == 0 {
        t += 1000;
        inj.poll(t);
    }
    assert!(inj.stalled(t));
    inj.push_frame(&frame(4), FrameKind::Sample);
    inj.drain_ready(t, &mut out);
    assert!(out.is_empty());
    inj.drain_ready(t + 50_000, &mut out);
    assert_eq!(out, frame(4));
}

#[test]
fn a_cut_counts_what_never_reached_the_wire_as_cut_not_as_faults() {
    let cfg = FaultConfig {
        drop_samples_at: vec![1, 4],
        corrupt_samples_at: vec![5],
        garbage_before_samples_at: vec![6],
        ..FaultConfig::default()
    };
    let mut inj = FaultInjector::new(&cfg, 1);
    let mut out = Vec::new();
    let sample = |inj: &mut FaultInjector, k: u32| {
        if !inj.before_sample(k) {
            inj.push_frame(&frame(8), FrameKind::Sample);
        }
    };
    // 0 sent, 1 dropped, 2 sent: the host sees the drop
    for k in 0..3 {
        sample(&mut inj, k);
    }
    inj.drain_ready(0, &mut out);
    // 3 sent; 4 dropped, 5 corrupted, on the wire after 3 but before no later sample
    for k in 3..6 {
        sample(&mut inj, k);
    }
    inj.drain_ready(0, &mut out);
    // 6 queued behind a garbage burst, not on the wire when the link is cut
    sample(&mut inj, 6);
    inj.push_frame(&frame(3), FrameKind::Other);
    inj.set_link_up(false);
    let s = inj.stats();
    assert_eq!(s.dropped_samples, 1, "only the drop a later sample shows");
    assert_eq!(s.corrupted_samples, 0, "5 is never followed by a sample");
    assert_eq!(
        s.corrupted_frames, 1,
        "its frame was on the wire: the host drops it"
    );
    assert_eq!(s.garbage_bursts, 0, "the burst never went out");
    assert_eq!(s.samples_cut, 3, "4, 5 and 6");
    // while down: samples counted unsent, nothing queued
    sample(&mut inj, 7);
    inj.push_frame(&frame(3), FrameKind::Other);
    let mut late = Vec::new();
    inj.drain_ready(0, &mut late);
    assert!(late.is_empty());
    assert_eq!(inj.stats().samples_unsent, 1);
    // up again: a new boot's samples go out
    inj.set_link_up(true);
    sample(&mut inj, 0);
    inj.drain_ready(0, &mut late);
    assert_eq!(late, frame(8));
    let s = inj.stats();
    // 9 taken: 4 received whole (0, 2, 3, the new 0), the rest each counted once
    let accounted = s.dropped_samples + s.corrupted_samples + s.samples_cut + s.samples_unsent;
    assert_eq!(4 + accounted, 9);
}
