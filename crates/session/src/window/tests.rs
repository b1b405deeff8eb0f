//! The window's rules, sample by sample: pulses, levels, gaps, segments, capacity.

use super::*;

fn sample(index: u64, throttle_raw: u16, flags: u16) -> SampleItem {
    SampleItem {
        index,
        t_us: index * 1000,
        throttle_raw,
        flags,
        thrust_n: 1.0,
        torque_nm: 0.1,
        rpm: 1000.0,
        voltage_v: f32::NAN,
        current_a: f32::NAN,
        received: Instant::now(),
    }
}

/// Feeds `n` samples at `level`, a pulse every `spacing` samples from `first_pulse`.
fn feed(
    w: &mut Window,
    start: u64,
    n: u64,
    level: u16,
    first_pulse: u64,
    spacing: u64,
    log: &mut Vec<(Reason, usize, usize, f64)>,
) {
    for i in start..start + n {
        let rel = i - start;
        let pulse = rel >= first_pulse && (rel - first_pulse) % spacing == 0;
        let (thr, f) = if pulse {
            (level + 500, flags::IMPULSE_ACTIVE)
        } else {
            (level, 0)
        };
        w.on_sample(&sample(i, thr, f), |v| {
            log.push((v.reason, v.input.len(), v.pulse_starts.len(), v.level))
        });
    }
}

#[test]
fn identifies_every_k_pulses_and_at_level_end() {
    let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    // 5 pulses at spacing 100 from sample 50: models at pulse 3 and pulse 5 start, then
    // the level end with one pulse pending identifies nothing.
    feed(&mut w, 0, 500, 3000, 50, 100, &mut log);
    assert_eq!(log.len(), 2);
    assert_eq!((log[0].0, log[0].1, log[0].2), (Reason::Pulses, 250, 2));
    assert_eq!(log[0].3, 0.3);
    // the restarted window keeps 50 samples of baseline before pulse 3
    assert_eq!((log[1].0, log[1].1, log[1].2), (Reason::Pulses, 250, 2));
    w.on_sample(&sample(500, 3000, flags::RAMP_ACTIVE), |_| {
        panic!("only one pulse pending")
    });
    assert_eq!(w.level(), None);
}

#[test]
fn a_ramp_without_flags_ends_at_the_level_it_reached() {
    // a CSV bench's ramp: 0.30 -> 0.447 in steps of 0.0035 (below the 0.005 tolerance), no
    // RAMP_ACTIVE, the window restarting every second step (last at 0.447); then 0.45
    let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    feed(&mut w, 0, 100, 3000, 1000, 100, &mut log);
    for (k, thr) in (3000..=4500).step_by(35).enumerate() {
        w.on_sample(&sample(100 + k as u64, thr, 0), |_| {});
    }
    feed(&mut w, 143, 400, 4500, 50, 100, &mut log);
    assert_eq!(w.level(), Some(0.45));
    // the ramp away: its first steps are within the tolerance, then the level ends
    for (k, thr) in [4480u16, 4460, 4440, 4420, 4400].into_iter().enumerate() {
        w.on_sample(&sample(543 + k as u64, thr, 0), |v| {
            log.push((v.reason, v.input.len(), v.pulse_starts.len(), v.level))
        });
    }
    assert_eq!(log.len(), 2, "{log:?}");
    assert_eq!(log[1].0, Reason::LevelEnd);
    assert!(log.iter().all(|l| l.3 == 0.45), "{log:?}");
}

#[test]
fn level_end_identifies_complete_pulses() {
    let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    feed(&mut w, 0, 300, 3000, 50, 100, &mut log); // pulses at 50, 150, 250
    assert_eq!(log.len(), 1);
    feed(&mut w, 300, 100, 4500, 1000, 100, &mut log); // new level, no pulses
    assert_eq!(log.len(), 1, "one pending pulse is not enough");
    let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    feed(&mut w, 0, 200, 3000, 50, 100, &mut log); // pulses at 50, 150
    feed(&mut w, 200, 10, 4500, 1000, 100, &mut log);
    assert_eq!(log.len(), 1);
    assert_eq!((log[0].0, log[0].1, log[0].2), (Reason::LevelEnd, 200, 2));
    assert_eq!(w.level(), Some(0.45));
}

#[test]
fn gaps_are_masked_not_bridged() {
    let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
    let mut seen = None;
    w.on_sample(&sample(0, 3000, 0), |_| {});
    w.on_sample(&sample(1, 3000, 0), |_| {});
    assert!(!w.on_gap(3, |_| {}));
    w.on_sample(&sample(5, 3500, flags::IMPULSE_ACTIVE), |_| {});
    w.on_sample(&sample(6, 3000, 0), |_| {});
    w.finish(|v| {
        seen = Some((
            v.missing.to_vec(),
            v.pulse_starts.to_vec(),
            v.input[2].is_nan(),
            v.dt_s,
        ))
    });
    let (missing, starts, nan, dt) = seen.unwrap();
    assert_eq!(missing, vec![false, false, true, true, true, false, false]);
    assert_eq!(starts, vec![5]);
    assert!(nan);
    assert!((dt - 1e-3).abs() < 1e-12);
}

#[test]
fn unannounced_index_jump_is_masked_not_bridged() {
    // The sampler's queue overflowed: samples 2..=4 and their gap notice never arrived.
    let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
    let mut seen = None;
    w.on_sample(&sample(0, 3000, 0), |_| {});
    w.on_sample(&sample(1, 3000, flags::IMPULSE_ACTIVE), |_| {});
    let o = w.on_sample(&sample(5, 3000, 0), |_| {});
    assert_eq!(o.unannounced_lost, 3);
    w.on_sample(&sample(6, 3000, 0), |_| {});
    w.finish(|v| seen = Some((v.missing.to_vec(), v.pulse_starts.to_vec(), v.dt_s)));
    let (missing, starts, dt) = seen.unwrap();
    assert_eq!(missing, vec![false, false, true, true, true, false, false]);
    assert_eq!(starts, vec![1]);
    assert!((dt - 1e-3).abs() < 1e-12);
}

#[test]
fn a_pulse_whose_sample_was_lost_still_counts_when_the_device_announced_it() {
    // K = 2, pulses every 100 samples from 50; the sample of pulse 2 (index 150) is lost but its
    // EVENT IMPULSE_START came: the window closes at pulse 3 with pulses 1 and 2, as without
    // the loss (without the event, pulses 1 and 3 would make the first window).
    let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    feed(&mut w, 0, 150, 3000, 50, 100, &mut log);
    w.on_pulse_event(150);
    assert!(w.on_gap(1, |_| panic!("one pulse held")));
    feed(&mut w, 151, 99, 3000, 1000, 1000, &mut log);
    assert!(log.is_empty());
    let mut starts = Vec::new();
    w.on_sample(&sample(250, 3500, flags::IMPULSE_ACTIVE), |v| {
        starts = v.pulse_starts.to_vec();
        assert!(v.missing[150]);
    });
    assert_eq!(starts, vec![50, 150]);
    // an event whose sample arrives is the sample's flag's business: one edge, not two
    w.on_pulse_event(350);
    let mut n = 0;
    feed(&mut w, 251, 200, 3000, 99, 1000, &mut log);
    w.on_sample(&sample(451, 3500, flags::IMPULSE_ACTIVE), |v| {
        n = v.pulse_starts.len();
    });
    assert_eq!(n, 2);
    // an event for a sample beyond the gap stays pending, one before it is dropped
    w.on_pulse_event(500);
    assert!(!w.on_gap(10, |_| {}));
}

#[test]
fn announced_gap_is_not_counted_twice() {
    let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
    w.on_sample(&sample(0, 3000, 0), |_| {});
    assert!(!w.on_gap(3, |_| {}));
    let o = w.on_sample(&sample(4, 3000, 0), |_| {});
    assert_eq!(o.unannounced_lost, 0);
    assert_eq!(w.len(), 5);
}

#[test]
fn index_going_back_closes_the_window_like_a_segment() {
    let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    feed(&mut w, 100, 100, 3000, 50, 1000, &mut log);
    assert!(log.is_empty());
    let mut reasons = Vec::new();
    w.on_sample(&sample(0, 3000, 0), |v| reasons.push(v.reason));
    assert_eq!(reasons, vec![Reason::Segment]);
    assert_eq!(w.len(), 1, "the new segment starts a fresh window");
}

#[test]
fn full_window_restarts_without_allocating() {
    let mut w = Window::new(64, 4, 0.005, OutputChannel::Thrust);
    let cap = w.input.capacity();
    let mut log = Vec::new();
    let mut overflowed = 0;
    for i in 0..200 {
        let o = w.on_sample(&sample(i, 3000, 0), |v| log.push(v.reason));
        overflowed += u32::from(o.overflowed);
    }
    assert!(log.is_empty());
    assert_eq!(overflowed, 3);
    assert!(w.len() <= 64);
    assert_eq!(w.input.capacity(), cap);
}

#[test]
fn segment_identifies_complete_window_then_waits_for_a_level() {
    let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    feed(&mut w, 0, 100, 3000, 50, 1000, &mut log);
    let mut n = 0;
    let cut = w.on_segment(|v| {
        assert_eq!(v.reason, Reason::Segment);
        n += 1
    });
    assert_eq!(n, 1);
    assert_eq!(cut, None, "identified, not interrupted");
    assert_eq!(w.level(), None);
    // a pulse sample first after the reset is not referred to any level
    let o = w.on_sample(&sample(0, 3500, flags::IMPULSE_ACTIVE), |_| {});
    assert!(!o.pulse);
}

#[test]
fn a_segment_before_k_pulses_reports_the_interrupted_window() {
    let mut w = Window::new(10_000, 4, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    // 3 of 4 pulses at 0.3, then the device resets
    feed(&mut w, 0, 320, 3000, 50, 100, &mut log);
    assert!(log.is_empty());
    let cut = w.on_segment(|_| panic!("3 of 4 pulses: nothing to identify"));
    assert_eq!(
        cut,
        Some(Interrupted {
            operating_point: 0.3,
            pulses: 3,
            t_s: 0.319,
            closed_by: Reason::Segment,
        })
    );
    assert_eq!(w.level(), None);
    // a window without a pulse yet is not one the plan made: nothing is reported
    feed(&mut w, 0, 40, 3000, 50, 100, &mut log);
    assert_eq!(w.on_segment(|_| panic!("no pulse")), None);
}

#[test]
fn a_window_cut_by_the_index_going_back_or_the_level_end_or_the_stream_end_is_reported() {
    // A hang-up re-opened as a new boot whose HELLO the host never saw: the first sample of
    // the new boot (index back to 0) closes the old window. It held 1 of 4 pulses (the soak
    // found these 1-pulse windows missing from every outcome).
    let mut w = Window::new(10_000, 4, 0.005, OutputChannel::Thrust);
    let mut log = Vec::new();
    feed(&mut w, 0, 420, 3000, 50, 100, &mut log); // 4 pulses started (50..350)
    feed(&mut w, 420, 30, 3000, 1000, 100, &mut log);
    assert!(
        log.is_empty(),
        "4 pulses, no fifth started: not identified yet"
    );
    let o = w.on_sample(&sample(0, 3000, 0), |v| {
        log.push((v.reason, v.input.len(), v.pulse_starts.len(), v.level))
    });
    assert_eq!(log.len(), 1, "the complete window is identified at the cut");
    assert_eq!(o.cut, None, "4 of 4: identified, not cut");
    // now 1 pulse then the index goes back again
    feed(&mut w, 1, 120, 3000, 49, 100, &mut log);
    let o = w.on_sample(&sample(0, 3000, 0), |_| panic!("1 of 4 pulses"));
    let cut = o
        .cut
        .expect("a 1-pulse window cut by the index going back is reported");
    assert_eq!((cut.pulses, cut.closed_by), (1, Reason::Segment));
    // 2 pulses, then the operating point changes
    feed(&mut w, 1, 200, 4500, 49, 100, &mut log);
    let o = w.on_sample(&sample(201, 6000, 0), |_| panic!("2 of 4 pulses"));
    let cut = o
        .cut
        .expect("pulses left over at the level's end are reported");
    assert_eq!((cut.pulses, cut.operating_point), (2, 0.45));
    assert_eq!(cut.closed_by, Reason::LevelEnd);
    // 3 pulses, then the stream ends
    feed(&mut w, 202, 300, 6000, 49, 100, &mut log);
    let cut = w
        .finish(|_| panic!("3 of 4 pulses"))
        .expect("reported at the end");
    assert_eq!((cut.pulses, cut.closed_by), (3, Reason::End));
}

#[test]
fn missing_measurement_is_masked() {
    let mut w = Window::new(100, 1, 0.005, OutputChannel::Thrust);
    let mut s = sample(0, 3000, 0);
    w.on_sample(&s, |_| {});
    s.index = 1;
    s.thrust_n = f32::NAN;
    w.on_sample(&s, |_| {});
    assert_eq!(w.missing, vec![false, true]);
}
