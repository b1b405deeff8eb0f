use super::*;
use crate::protocol::message::{Event, EventCode, Hello, Message, Sample, SampleFlags};
use crate::protocol::EscProtocol;
use crate::protocol::Frame;
use crate::record::{Record, RecordEvent, RecordEventKind};
use crate::stream::IngestError;

const ALL: SampleFlags = SampleFlags(0x3F | 1 << 10);

fn sample(i: u32, t_us: u32, flags: SampleFlags) -> Frame {
    Frame {
        seq: i as u16,
        msg: Message::Sample(Sample {
            sample_index: i,
            t_us,
            throttle: 2000 + (i % 7) as u16,
            flags,
            thrust_n: i as f32,
            torque_nm: 0.5,
            rpm: 1000.0,
            voltage_v: 16.0,
            current_a: 2.0,
        }),
    }
}

fn hello(boot_id: u32) -> Frame {
    Frame {
        seq: 0,
        msg: Message::Hello(Hello {
            proto_minor: 0,
            esc_protocol: EscProtocol::DShot600,
            fw_version: 1,
            boot_id,
            t_us: 0,
            sample_rate_hz: 1000,
            channels: 0x1F,
            motor_poles: 14,
            caps: 0xF,
            name: [0; 16],
        }),
    }
}

fn event(code: EventCode, idx: u32) -> Frame {
    Frame {
        seq: 0,
        msg: Message::Event(Event {
            code,
            arg: 0,
            t_us: 0,
            sample_index: idx,
        }),
    }
}

fn build(frames: &[Frame]) -> (Record, AssembleStats, BuildStats) {
    let mut b = RecordBuilder::new(AssembleOptions::default());
    for f in frames {
        b.push_frame(f);
    }
    b.finish().unwrap()
}

#[test]
fn clean_stream_is_uniform_with_all_channels() {
    let frames: Vec<Frame> = (0..100).map(|i| sample(i, 1000 * i + 7, ALL)).collect();
    let (r, a, b) = build(&frames);
    assert_eq!(r.len(), 100);
    assert_eq!(r.missing_count(), 0);
    assert_eq!(r.dt_s, 1e-3);
    assert_eq!(r.t0_s, 7e-6);
    let names: Vec<&str> = r.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "throttle",
            "thrust_N",
            "torque_Nm",
            "rpm",
            "voltage_V",
            "current_A"
        ]
    );
    assert_eq!(r.channel("thrust_N").unwrap().data[42], 42.0);
    assert_eq!(r.channel("throttle").unwrap().data[3], 0.2003);
    assert_eq!((a.samples, a.samples_lost, a.segments), (100, 0, 1));
    assert_eq!(b.invalid_samples, 0);
}

#[test]
fn index_gaps_become_missing_samples_never_bridged() {
    let idx = [0u32, 1, 2, 5, 6, 7, 9];
    let frames: Vec<Frame> = idx.iter().map(|&i| sample(i, 1000 * i, ALL)).collect();
    let (r, a, _) = build(&frames);
    assert_eq!(r.len(), 10);
    let missing: Vec<usize> = (0..10).filter(|&k| r.missing[k]).collect();
    assert_eq!(missing, [3, 4, 8]);
    assert!(r.channel("thrust_N").unwrap().data[3].is_nan());
    assert_eq!(r.channel("thrust_N").unwrap().data[9], 9.0);
    assert_eq!((a.samples_lost, a.gaps), (3, 2));
    assert_eq!(r.dt_s, 1e-3);
}

#[test]
fn device_clock_wrap_is_unwrapped() {
    let start = u32::MAX - 2500;
    let frames: Vec<Frame> = (0..10)
        .map(|i| sample(i, start.wrapping_add(1000 * i), ALL))
        .collect();
    let (r, a, _) = build(&frames);
    assert_eq!(a.clock_wraps, 1);
    assert!((r.dt_s - 1e-3).abs() < 1e-15);
    assert_eq!(r.len(), 10);
}

#[test]
fn sample_index_wrap_is_not_a_reset() {
    let frames: Vec<Frame> = (0..6u32)
        .map(|i| sample((u32::MAX - 2).wrapping_add(i), 1000 * i, ALL))
        .collect();
    let (r, a, _) = build(&frames);
    assert_eq!((r.len(), a.segments, a.resets_inferred), (6, 1, 0));
}

#[test]
fn new_boot_id_starts_a_segment() {
    let mut frames = vec![hello(1)];
    frames.extend((0..5).map(|i| sample(100 + i, 1000 * i, ALL)));
    frames.push(hello(1)); // periodic HELLO, same boot: nothing happens
    frames.extend((5..8).map(|i| sample(100 + i, 1000 * i, ALL)));
    frames.push(hello(2));
    frames.extend((0..4).map(|i| sample(i, 50 + 1000 * i, ALL)));
    let (r, a, _) = build(&frames);
    assert_eq!(r.len(), 12);
    assert_eq!(
        r.events,
        [RecordEvent {
            sample: 8,
            kind: RecordEventKind::SegmentStart
        }]
    );
    assert_eq!((a.segments, a.samples_lost), (2, 0));
    assert_eq!(r.dt_s, 1e-3);
}

#[test]
fn backward_index_is_an_inferred_reset_and_duplicates_are_dropped() {
    let frames = [
        sample(10, 0, ALL),
        sample(11, 1000, ALL),
        sample(11, 1000, ALL),
        sample(0, 0, ALL),
        sample(1, 1000, ALL),
    ];
    let (r, a, _) = build(&frames);
    assert_eq!(r.len(), 4);
    assert_eq!((a.duplicates, a.resets_inferred, a.segments), (1, 1, 2));
    assert_eq!(r.events[0].kind, RecordEventKind::SegmentStart);
    assert_eq!(r.events[0].sample, 2);
}

#[test]
fn impulse_events_land_on_their_exact_sample() {
    let mut frames = vec![event(EventCode::ImpulseStart, 52)]; // before any sample: pending
    frames.extend((50..60).map(|i| sample(i, 1000 * i, ALL)));
    frames.push(event(EventCode::ImpulseEnd, 55));
    frames.push(event(EventCode::WatchdogTrip, 58));
    frames.push(event(EventCode::TareDone, 58)); // not a record event
    frames.push(event(EventCode::ImpulseStart, 40)); // before the segment: dropped
    frames.push(event(EventCode::ImpulseStart, 70)); // after the end: dropped at finish
    let (r, a, _) = build(&frames);
    let ev: Vec<(usize, RecordEventKind)> = r.events.iter().map(|e| (e.sample, e.kind)).collect();
    assert_eq!(
        ev,
        [
            (2, RecordEventKind::ImpulseStart),
            (5, RecordEventKind::ImpulseEnd),
            (8, RecordEventKind::WatchdogTrip)
        ]
    );
    assert_eq!(r.impulse_starts().collect::<Vec<_>>(), [2]);
    assert_eq!((a.events, a.events_dropped), (3, 2));
}

#[test]
fn channels_follow_the_valid_flags_of_the_first_sample() {
    let thrust_only = SampleFlags::THRUST_VALID;
    let frames = [
        sample(0, 0, thrust_only),
        sample(1, 1000, thrust_only | SampleFlags::RPM_VALID),
        sample(2, 2000, SampleFlags(0)), // thrust not valid: whole sample missing
        sample(3, 3000, thrust_only),
    ];
    let (r, a, b) = build(&frames);
    let names: Vec<&str> = r.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["throttle", "thrust_N"]);
    assert_eq!(r.missing, [false, false, true, false]);
    assert!(r.channel("throttle").unwrap().data[2].is_nan());
    assert_eq!(b.invalid_samples, 1);
    assert_eq!(b.thrust_held, 4);
    assert_eq!(a.samples, 4);
}

#[test]
fn huge_gap_starts_a_segment_instead_of_filling() {
    let mut b = RecordBuilder::new(AssembleOptions {
        max_gap_samples: 10,
    });
    for i in [0u32, 1, 2, 100, 101] {
        b.push_frame(&sample(i, 1000 * i, ALL));
    }
    let (r, a, _) = b.finish().unwrap();
    assert_eq!(r.len(), 5);
    assert_eq!((a.samples_lost, a.large_gaps, a.segments), (97, 1, 2));
    assert_eq!(r.events[0].kind, RecordEventKind::SegmentStart);
    assert_eq!(r.dt_s, 1e-3);
}

#[test]
fn nominal_rate_when_the_clock_cannot_tell() {
    let (r, _, _) = build(&[hello(3), sample(0, 0, ALL)]);
    assert_eq!(r.dt_s, 1e-3);
    let mut b = RecordBuilder::default();
    b.push_frame(&sample(0, 0, ALL));
    assert_eq!(b.finish().unwrap_err(), IngestError::NoTimebase);
    assert_eq!(
        RecordBuilder::default().finish().unwrap_err(),
        IngestError::NoSamples
    );
}

#[test]
fn seq_jumps_count_link_losses_not_device_drops() {
    // Frames 0..10 with seq = index; frame seq 4 lost on the link (index 4 missing too), and
    // index 7 dropped by the device (seq continues).
    let mut frames = Vec::new();
    let mut seq = 0u16;
    for i in 0..10u32 {
        if i == 7 {
            continue; // device drop: no frame, no seq consumed
        }
        let mut f = sample(i, 1000 * i, ALL);
        f.seq = seq;
        seq += 1;
        if i != 4 {
            frames.push(f);
        }
    }
    let mut b = RecordBuilder::default();
    b.push_frame(&hello(1));
    frames.iter().for_each(|f| b.push_frame(f));
    let (r, a, st) = b.finish().unwrap();
    assert_eq!(r.missing_count(), 2);
    assert_eq!(a.samples_lost, 2);
    assert_eq!(st.link_frames_lost, 1);
}

#[test]
fn samples_of_a_new_boot_before_its_hello_make_one_segment() {
    let mut frames = vec![hello(1)];
    frames.extend((100..105).map(|i| sample(i, 1000 * i, ALL)));
    frames.extend((0..2).map(|i| sample(i, 1000 * i, ALL))); // new boot, HELLO late
    frames.push(hello(2));
    frames.extend((2..5).map(|i| sample(i, 1000 * i, ALL)));
    let (r, a, _) = build(&frames);
    assert_eq!(r.len(), 10);
    assert_eq!((a.segments, a.resets_inferred), (2, 1));
    let starts: Vec<usize> = r.events.iter().map(|e| e.sample).collect();
    assert_eq!(starts, [5]);
}

#[test]
fn absurd_indices_cannot_blow_up_the_record() {
    // Every other frame jumps by almost the largest fillable gap.
    let mut b = RecordBuilder::new(AssembleOptions {
        max_gap_samples: 1000,
    });
    let mut idx = 0u32;
    for i in 0..100u32 {
        b.push_frame(&sample(idx, 1000 * idx, ALL));
        idx += if i % 2 == 0 { 999 } else { 1 };
    }
    let (r, a, _) = b.finish().unwrap();
    // Filled samples stay within max_gap + 10 × received.
    assert!(r.missing_count() as u64 <= 1000 + 10 * 100);
    assert!(a.large_gaps > 0);
    assert_eq!(a.samples, 100);
    assert_eq!(a.samples_lost, 50 * 998);
}

#[test]
fn every_sample_says_what_happened_as_typed_items() {
    let mut a = SampleAssembler::new(AssembleOptions {
        max_gap_samples: 100,
    });
    let mut said = Vec::new();
    let mut push = |a: &mut SampleAssembler, i: u32, t: u32| {
        let mut items = Vec::new();
        a.sample(i, t, (), &mut |x| items.push(x));
        said.push(items);
    };
    assert_eq!(a.hello(7, 1000), HelloEffect::FirstBoot);
    push(&mut a, 10, u32::MAX - 1500);
    push(&mut a, 11, u32::MAX - 500);
    push(&mut a, 11, u32::MAX - 500); // duplicate
    push(&mut a, 14, 2500); // a gap of 2 and the clock wraps
    push(&mut a, 500, 3500); // a gap too long to fill
    push(&mut a, 3, 4500); // the index goes back
    assert_eq!(
        a.hello(8, 1000),
        HelloEffect::Adopted,
        "the reset was seen already"
    );
    assert_eq!(a.hello(8, 1000), HelloEffect::SameBoot);
    assert_eq!(a.hello(9, 1000), HelloEffect::NewBoot);
    push(&mut a, 0, 0);
    use Assembled as A;
    let sample = |k: usize, t_us: u64| A::Sample { k, t_us, value: () };
    let start = |k: usize, cause: SegmentCause| A::SegmentStart { k, cause };
    let t0 = u64::from(u32::MAX);
    assert_eq!(
        said,
        vec![
            vec![start(0, SegmentCause::First), sample(0, t0 - 1500)],
            vec![sample(1, t0 - 500)],
            vec![A::Duplicate],
            vec![
                A::ClockWrap,
                A::Missing { k: 2, count: 2 },
                sample(4, t0 + 2501)
            ],
            vec![
                start(5, SegmentCause::GapTooLong { lost: 485 }),
                sample(5, 3500)
            ],
            vec![start(6, SegmentCause::IndexBackwards), sample(6, 4500)],
            vec![start(7, SegmentCause::NewBoot), sample(7, 0)],
        ]
    );
    let s = a.stats();
    assert_eq!(
        (
            s.samples_lost,
            s.gaps,
            s.large_gaps,
            s.duplicates,
            s.segments,
            s.clock_wraps
        ),
        (487, 1, 1, 1, 4, 1)
    );
}

/// 1 kHz samples 0..n with the clock stepping by `jump_us` before sample `at` (and on).
fn jumped(n: u32, at: u32, jump_us: i64) -> Vec<Frame> {
    let mut frames = vec![hello(1)];
    frames.extend((0..n).map(|i| {
        let t = 1_000_000i64 + 1000 * i as i64 + if i >= at { jump_us } else { 0 };
        sample(i, t as u32, ALL)
    }));
    frames
}

#[test]
fn a_clock_jump_forward_or_back_keeps_the_samples_and_leaves_dt_alone() {
    for jump in [20_000i64, -500_000, 3_000_000] {
        let (r, a, _) = build(&jumped(1000, 400, jump));
        assert_eq!((a.clock_jumps, a.segments, r.len()), (1, 1, 1000), "{jump}");
        assert!(r.missing.iter().all(|m| !m), "{jump}");
        assert!((r.dt_s - 1e-3).abs() < 1e-12, "{jump}: dt {}", r.dt_s);
        assert_eq!(a.clock_backwards, u64::from(jump < 0));
        assert_eq!(a.rate_mismatches, 0);
    }
    // several, both ways (the replay: dt 0.021..0.028 s for 0.001 s; backward: 248 Hz)
    let mut frames = vec![hello(1)];
    let mut t = 0i64;
    for i in 0..3000u32 {
        t += match i % 500 {
            100 => 25_000,
            350 => -40_000,
            _ => 1000,
        };
        frames.push(sample(i, t as u32, ALL));
    }
    let (r, a, _) = build(&frames);
    assert_eq!(a.clock_jumps, 12);
    assert!((r.dt_s - 1e-3).abs() < 1e-12, "dt {}", r.dt_s);
}

#[test]
fn a_clock_jump_is_said_at_its_sample() {
    let mut a = SampleAssembler::new(AssembleOptions::default());
    a.hello(1, 1000);
    let mut said = Vec::new();
    for (i, t) in [
        (0u32, 0u32),
        (1, 1000),
        (2, 51_000),
        (3, 52_000),
        (4, 2_000),
    ] {
        a.sample(i, t, (), &mut |x| said.push(x));
    }
    use Assembled as A;
    let jumps: Vec<_> = said
        .iter()
        .filter(|x| matches!(x, A::ClockJump { .. } | A::ClockBackwards))
        .collect();
    assert_eq!(
        jumps,
        vec![
            &A::ClockJump {
                k: 2,
                step_us: 50_000,
                expected_us: 1000.0
            },
            &A::ClockBackwards,
            &A::ClockJump {
                k: 4,
                step_us: -50_000,
                expected_us: 1000.0
            },
        ]
    );
}

#[test]
fn jitter_and_gaps_are_no_clock_jumps() {
    // a CSV bench's rows placed on the nearest index: ±0.5 period of jitter; gaps of 50
    let mut frames = vec![hello(1)];
    let mut i = 0u32;
    for k in 0..2000u32 {
        i += if k % 100 == 99 { 50 } else { 1 };
        let jitter = [0i64, 450, -450, 300, -200][k as usize % 5];
        frames.push(sample(i, (1000 * i as i64 + 5000 + jitter) as u32, ALL));
    }
    let (_, a, _) = build(&frames);
    assert_eq!((a.clock_jumps, a.rate_mismatches), (0, 0));
}

#[test]
fn a_hello_that_lies_about_the_rate_is_said_once_and_the_clock_is_believed() {
    // HELLO says 1000 Hz, the samples come at 500 Hz
    let mut a = SampleAssembler::new(AssembleOptions::default());
    a.hello(1, 1000);
    let mut mismatch = Vec::new();
    for i in 0..1000u32 {
        a.sample(i, 2000 * i, (), &mut |x| {
            if let Assembled::RateMismatch {
                hello_hz,
                measured_hz,
            } = x
            {
                mismatch.push((hello_hz, measured_hz));
            }
        });
    }
    assert_eq!(mismatch, vec![(1000, 500.0)]);
    // within two HELLO periods of the HELLO's: no jump, a rate
    assert_eq!(a.stats().clock_jumps, 0);
    assert!((a.dt_s().unwrap() - 2e-3).abs() < 1e-12);
    // 65 535 Hz claimed
    let mut a = SampleAssembler::new(AssembleOptions::default());
    a.hello(1, 65_535);
    let mut n = 0;
    for i in 0..1000u32 {
        a.sample(i, 1000 * i, (), &mut |x| {
            n += usize::from(matches!(x, Assembled::RateMismatch { .. }))
        });
    }
    assert_eq!((n, a.stats().rate_mismatches), (1, 1));
    assert_eq!(a.stats().clock_jumps, 1, "the first step only");
    assert!((a.dt_s().unwrap() - 1e-3).abs() < 1e-12);
}

#[test]
fn a_hello_rate_of_0_is_a_lie_on_tsp1_and_not_measured_yet_on_csv() {
    let mismatches = |csv: bool| {
        let mut a = SampleAssembler::new(AssembleOptions::default());
        if csv {
            a.hello_csv(1, 0);
        } else {
            a.hello(1, 0);
        }
        let mut said = Vec::new();
        for i in 0..1000u32 {
            a.sample(i, 1000 * i, (), &mut |x| {
                if let Assembled::RateMismatch {
                    hello_hz,
                    measured_hz,
                } = x
                {
                    said.push((hello_hz, measured_hz));
                }
            });
        }
        (said, a.stats().rate_mismatches, a.dt_s())
    };
    let (said, n, dt) = mismatches(false);
    assert_eq!((said, n), (vec![(0, 1000.0)], 1));
    assert!((dt.unwrap() - 1e-3).abs() < 1e-12, "the clock is believed");
    let (said, n, _) = mismatches(true);
    assert_eq!((said, n), (vec![], 0));
}

#[test]
fn a_binary_recording_s_rate_0_hello_is_a_lie_a_csv_bench_s_is_not() {
    let mut h = match hello(1).msg {
        Message::Hello(h) => h,
        _ => unreachable!(),
    };
    h.sample_rate_hz = 0;
    let frames: Vec<Frame> = std::iter::once(Frame {
        seq: 0,
        msg: Message::Hello(h),
    })
    .chain((0..300).map(|i| sample(i, 1000 * i, ALL)))
    .collect();
    let (_, st, _) = build(&frames);
    assert_eq!(st.rate_mismatches, 1);
    let mut b = RecordBuilder::new(AssembleOptions::default());
    b.push_hello(&h);
    frames[1..].iter().for_each(|f| b.push_frame(f));
    let (_, st, _) = b.finish().unwrap();
    assert_eq!(st.rate_mismatches, 0);
}
