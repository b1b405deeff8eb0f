//! Known sequences, the stream against the record, holds and steps. The rules each caller had
//! before, kept as oracles (on the commands they were written for, the one rule answers the
//! same), are in `tests/oracles.rs`.

use proptest::prelude::*;

use super::*;

const R: SegmentRules = SegmentRules::DEFAULT;

/// `(value, samples)` runs laid end to end.
fn seq(parts: &[(f64, usize)]) -> Vec<f64> {
    parts
        .iter()
        .flat_map(|&(v, n)| std::iter::repeat_n(v, n))
        .collect()
}

fn found(u: &[f64], rules: &SegmentRules) -> Vec<(usize, usize, f64)> {
    pulses(Command::new(u), rules)
        .map(|p| (p.start, p.width, p.amplitude))
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

/// Feeds `u` to a classifier sample by sample and returns, per sample, whether it ends up
/// marked as a pulse sample (held samples are decided later, as a delay line would).
fn stream_marks(u: &[f64], rules: &SegmentRules) -> (Vec<bool>, Vec<PulseRun>) {
    let mut c = PulseClassifier::new(*rules);
    let (mut marks, mut held, mut found) = (Vec::new(), Vec::new(), Vec::new());
    for (k, &v) in u.iter().enumerate() {
        match c.push(v) {
            Decision::Pass => marks.push(false),
            Decision::Hold => held.push(k),
            Decision::Release { hold } => {
                marks.extend(held.drain(..).map(|_| false));
                if hold {
                    held.push(k);
                } else {
                    marks.push(false);
                }
            }
            Decision::Pulse(p) => {
                assert_eq!((p.start, p.width), (held[0], held.len()));
                marks.extend(held.drain(..).map(|_| true));
                marks.push(false);
                found.push(p);
            }
        }
        assert!(held.len() <= rules.max_pulse_samples, "held {}", held.len());
    }
    if c.flush() {
        marks.extend(held.drain(..).map(|_| false));
    }
    assert!(held.is_empty());
    (marks, found)
}

#[test]
fn a_staircase_has_one_level_per_step_and_no_pulse() {
    let u = seq(&[(0.3, 100), (0.4, 80), (0.5, 120), (0.3, 50)]);
    let lv = levels(Command::new(&u), &R);
    let got: Vec<_> = lv.iter().map(|l| (l.start, l.end, l.value)).collect();
    assert_eq!(
        got,
        [
            (0, 100, 0.3),
            (100, 180, 0.4),
            (180, 300, 0.5),
            (300, 350, 0.3)
        ]
    );
    assert!(found(&u, &R).is_empty());
    assert!(is_piecewise_constant(Command::new(&u), &R));
    assert!(is_ramped_staircase(Command::new(&u), &R));
}

#[test]
fn a_ramped_staircase_keeps_its_ramps_in_the_level_before() {
    let mut u = seq(&[(0.3, 100)]);
    u.extend((1..=20).map(|k| 0.3 + 0.01 * k as f64)); // ramp 0.31 ..= 0.5, one sample each
    u.extend(seq(&[(0.5, 100)]));
    let cmd = Command::new(&u);
    let got: Vec<_> = levels(cmd, &R).iter().map(|l| (l.start, l.end)).collect();
    assert_eq!(
        got,
        [(0, 119), (119, 220)],
        "the ramp's last value is the level"
    );
    assert!(found(&u, &R).is_empty(), "a monotone ramp has no pulse");
    assert!(is_ramped_staircase(cmd, &R));
    // mostly ramp: not a ramped staircase, but a ramp
    let mut r: Vec<f64> = (0..400).map(|k| 0.2 + 0.001 * k as f64).collect();
    r.extend(seq(&[(0.6, 40)]));
    assert!(!is_ramped_staircase(Command::new(&r), &R));
    assert!(!is_piecewise_constant(Command::new(&r), &R));
    assert!(is_ramp(Command::new(&r), &R));
    let w = ramp_windows(Command::new(&r), &R);
    assert_eq!(w.len(), 4);
    assert!(w
        .windows(2)
        .all(|p| p[1].value > p[0].value && p[1].start == p[0].end));
}

#[test]
fn pulses_of_both_signs_and_several_widths_at_several_levels() {
    let u = seq(&[
        (0.3, 60),
        (0.35, 1), // +, 1 sample
        (0.3, 60),
        (0.25, 3), // −, 3 samples
        (0.3, 60),
        (0.6, 100), // a step
        (0.7, 32),  // +, the widest
        (0.6, 60),
        (0.5, 33), // one sample too wide: a step down and back up
        (0.6, 60),
        (0.55, 1),
        (0.6, 1),  // one sample back at the level is enough
        (0.65, 2), // +, right after the return of the last one
        (0.6, 40),
    ]);
    let got = found(&u, &R);
    let want = [
        (60, 1, 0.05),
        (121, 3, -0.05),
        (284, 32, 0.1),
        (469, 1, -0.05),
        (471, 2, 0.05),
    ];
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert_eq!((g.0, g.1), (w.0, w.1), "{got:?}");
        assert!(close(g.2, w.2), "{got:?}");
    }
    let p = pulses(Command::new(&u), &R).nth(1).unwrap();
    assert_eq!((p.before_start, p.level), (61, 0.3));
    // the levels hold their pulses: 0.3 and 0.6 (0.5 held 33 samples is a level of its own)
    let lv: Vec<_> = levels(Command::new(&u), &R)
        .iter()
        .map(|l| (l.start, l.value))
        .collect();
    assert_eq!(lv, [(0, 0.3), (184, 0.6), (376, 0.5), (409, 0.6)]);
}

#[test]
fn a_pulse_at_a_level_change_is_a_step() {
    // up by 0.05 for 3 samples, then on to another level: never back, so no pulse
    let u = seq(&[(0.3, 60), (0.35, 3), (0.4, 60)]);
    assert!(found(&u, &R).is_empty());
    // a dip right after a step is a pulse on the new level, referred to its first samples
    let u = seq(&[(0.3, 60), (0.4, 5), (0.35, 2), (0.4, 60)]);
    let p: Vec<_> = pulses(Command::new(&u), &R).collect();
    assert_eq!(p.len(), 1);
    assert_eq!((p[0].start, p[0].width, p[0].before_start), (65, 2, 60));
    // two values in a row, then back: not one flat pulse (and neither value alone is one)
    let u = seq(&[(0.3, 60), (0.35, 2), (0.4, 2), (0.3, 60)]);
    assert!(found(&u, &R).is_empty());
}

#[test]
fn noise_on_the_command_needs_a_tolerance_above_it() {
    // ±0.002 of deterministic "noise" on two levels with pulses of 0.05
    let mut u = seq(&[
        (0.3, 100),
        (0.35, 2),
        (0.3, 100),
        (0.5, 100),
        (0.45, 1),
        (0.5, 100),
    ]);
    for (k, v) in u.iter_mut().enumerate() {
        *v += 0.002 * ((k * 7919 % 13) as f64 / 6.0 - 1.0);
    }
    let exact = SegmentRules::DEFAULT;
    assert!(!is_piecewise_constant(Command::new(&u), &exact));
    assert!(levels(Command::new(&u), &exact).is_empty());
    let noisy = SegmentRules {
        level_tolerance: 0.01,
        ..exact
    };
    let got = found(&u, &noisy);
    assert_eq!(
        got.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>(),
        [(100, 2), (302, 1)]
    );
    assert!((got[0].2 - 0.05).abs() < 0.005 && (got[1].2 + 0.05).abs() < 0.005);
    let lv: Vec<_> = levels(Command::new(&u), &noisy)
        .iter()
        .map(|l| (l.start, l.end))
        .collect();
    assert_eq!(lv, [(0, 202), (202, 403)]);
    assert!(is_piecewise_constant(Command::new(&u), &noisy));
}

#[test]
fn missing_samples_join_their_run_and_a_pulse_counts_them() {
    let nan = f64::NAN;
    let mut u = seq(&[(0.3, 40), (0.4, 1), (0.3, 40)]);
    u[41] = nan; // just after the pulse: it waits for the next measured sample
    u[10] = nan;
    let p: Vec<_> = pulses(Command::new(&u), &R).collect();
    assert_eq!((p.len(), p[0].start, p[0].width), (1, 40, 2));
    assert_eq!(pulse_at(&Command::new(&u), 40, &R), Some(p[0]));
    // the same through a mask, with finite values under it
    let v = seq(&[(0.3, 40), (0.4, 1), (0.3, 40)]);
    let mut m = vec![false; v.len()];
    m[41] = true;
    let q: Vec<_> = pulses(Command::with_missing(&v, &m), &R).collect();
    assert_eq!((q[0].start, q[0].width), (40, 2));
    // a record starting with missing samples: they belong to the first run
    let mut w = seq(&[(0.3, 50), (0.5, 50)]);
    w[..3].fill(nan);
    let runs: Vec<_> = Runs::new(Command::new(&w), &R).collect();
    assert_eq!((runs[0].start, runs[0].end, runs[0].value), (0, 50, 0.3));
    assert!(Runs::new(Command::new(&[nan, nan]), &R).next().is_none());
}

#[test]
fn the_stream_marks_exactly_the_pulses_of_the_record_and_flush_releases() {
    let u = seq(&[(0.3, 10), (0.4, 2), (0.3, 5), (0.2, 1), (0.3, 5), (0.5, 3)]);
    let (marks, got) = stream_marks(&u, &R);
    assert_eq!(marks.len(), u.len());
    let want: Vec<bool> = (0..u.len())
        .map(|k| (10..12).contains(&k) || k == 17)
        .collect();
    assert_eq!(marks, want);
    assert_eq!(got, pulses(Command::new(&u), &R).collect::<Vec<_>>());
    // a restart forgets the level: the first sample after it is a first sample
    let mut c = PulseClassifier::new(R);
    c.push(0.3);
    c.restart();
    assert_eq!((c.push(0.5), c.samples()), (Decision::Pass, 1));
    assert_eq!(c.push(0.6), Decision::Hold);
    assert!(c.flush());
    assert_eq!(
        c.push(0.6),
        Decision::Pass,
        "the flushed run goes on unheld"
    );
}

#[test]
fn zero_width_limit_finds_no_pulse_and_holds_nothing() {
    let rules = SegmentRules {
        max_pulse_samples: 0,
        ..R
    };
    let u = seq(&[(0.3, 10), (0.4, 1), (0.3, 10)]);
    let (marks, got) = stream_marks(&u, &rules);
    assert!(got.is_empty() && marks.iter().all(|m| !m));
}

#[test]
fn rules_are_one_documented_set() {
    assert_eq!(SegmentRules::default(), SegmentRules::DEFAULT);
    assert_eq!(SegmentRules::DEFAULT.max_pulse_samples, 32);
    assert_eq!(SegmentRules::DEFAULT.level_tolerance, 1e-9);
    let b = SegmentRules::CSV_BENCH;
    assert_eq!((b.level_tolerance, b.max_pulse_samples), (0.005, 64));
    assert_eq!(b.response, SegmentRules::DEFAULT.response);
    assert!(R.same(0.3, 0.3 + 1e-10) && !R.same(0.3, 0.3001) && !R.same(f64::NAN, 0.3));
}

/// Runs of values from a small grid (exact levels, as a logged command holds them).
fn grid_runs(max_len: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec((0usize..5, 1..max_len), 1..24).prop_map(|parts| {
        parts
            .iter()
            .flat_map(|&(v, n)| std::iter::repeat_n(0.3 + 0.05 * v as f64, n))
            .collect()
    })
}

proptest! {
    #[test]
    fn the_stream_gives_the_record_answer(u in grid_runs(40), w in 1usize..8, holes in prop::collection::vec(0usize..1000, 0..6)) {
        let mut u = u;
        for h in holes {
            let n = u.len();
            u[h % n] = f64::NAN;
        }
        let rules = SegmentRules { max_pulse_samples: w, ..R };
        let (marks, streamed) = stream_marks(&u, &rules);
        let offline: Vec<_> = pulses(Command::new(&u), &rules).collect();
        prop_assert_eq!(&streamed, &offline);
        let want: Vec<bool> = (0..u.len())
            .map(|k| offline.iter().any(|p| (p.start..p.start + p.width).contains(&k)))
            .collect();
        prop_assert_eq!(marks, want);
        for p in &offline {
            prop_assert_eq!(pulse_at(&Command::new(&u), p.start, &rules), Some(*p));
        }
    }
}

#[test]
fn steps_are_held_levels_next_to_each_other_and_holds_are_the_steady_runs() {
    let rules = SegmentRules::DEFAULT;
    // 0.2 held, step to 0.5, held with a pulse, ramp (short runs) to 0.8, held, step down to 0.4.
    let mut u = seq(&[(0.2, 100), (0.5, 60), (0.6, 1), (0.5, 60)]);
    u.extend((1..10).map(|i| 0.5 + 0.03 * i as f64));
    u.extend(seq(&[(0.8, 80), (0.4, 70)]));
    let cmd = Command::new(&u);
    let st = steps(cmd, &rules);
    assert_eq!(st.len(), 2, "{st:?}");
    assert_eq!(
        (st[0].before_start, st[0].at, st[0].after_end),
        (0, 100, 160)
    );
    assert!(close(st[0].from, 0.2) && close(st[0].to, 0.5));
    let n = u.len();
    assert_eq!((st[1].at, st[1].after_end), (n - 70, n));
    assert!(close(st[1].from, 0.8) && close(st[1].to, 0.4));
    // The ramp into 0.8 is no step; the pulse splits 0.5 into two holds.
    let h: Vec<(usize, usize)> = holds(cmd, &rules).map(|r| (r.start, r.end)).collect();
    assert_eq!(
        h,
        vec![
            (0, 100),
            (100, 160),
            (161, 221),
            (n - 150, n - 70),
            (n - 70, n)
        ]
    );
    // An interpolated step (two samples between the levels, in order) is a step from its first
    // transition sample; a transition that overshoots or goes back is not.
    let mut v = seq(&[(0.2, 50)]);
    v.extend([0.3, 0.45]);
    v.extend(seq(&[(0.6, 50)]));
    let st = steps(Command::new(&v), &rules);
    assert_eq!(st.len(), 1);
    assert_eq!((st[0].at, st[0].after_end), (50, 102));
    let mut w = seq(&[(0.2, 50)]);
    w.extend([0.7, 0.45]);
    w.extend(seq(&[(0.6, 50)]));
    assert!(steps(Command::new(&w), &rules).is_empty());
    // A random-step sequence of short holds (≤ max_pulse_samples) has no step: they are pulses.
    assert!(steps(
        Command::new(&seq(&[(0.2, 30), (0.4, 30), (0.3, 30)])),
        &rules
    )
    .is_empty());
}

mod oracles;

#[test]
fn at_a_slow_rate_a_pulse_is_at_most_a_third_of_a_second_and_longer_holds_are_levels() {
    let at = |dt: f64| R.at_rate(dt).max_pulse_samples;
    // 100 Hz and faster: 32 samples is the shorter; 10 Hz: 3 samples (0.3 s); a sample
    // longer than a third of a second: no pulse, every run a level.
    let rates = (
        at(0.001),
        at(0.01),
        at(0.02),
        at(1.0 / 30.0),
        at(0.1),
        at(0.5),
    );
    assert_eq!(rates, (32, 32, 16, 10, 3, 0));
    assert_eq!(R.at_rate(f64::NAN), R);
    assert_eq!(R.at_rate(0.0), R);
    // A 10 Hz log holding each level 3 s: no level under the sample count alone, every level
    // and every step at its rate.
    let u = seq(&[(0.3, 30), (0.5, 30), (0.4, 30), (0.7, 30), (0.5, 30)]);
    let cmd = Command::new(&u);
    assert!(levels(cmd, &R).is_empty());
    let slow = R.at_rate(0.1);
    assert_eq!(levels(cmd, &slow).len(), 5);
    assert_eq!(steps(cmd, &slow).len(), 4);
    // A one-sample pulse is still a pulse at 10 Hz.
    let p = seq(&[(0.25, 30), (0.5, 1), (0.25, 30)]);
    assert_eq!(found(&p, &slow), vec![(30, 1, 0.25)]);
    // A table of steady averages, a row every 5 s: every row its own level, no pulse.
    let table = [0.1, 0.2, 0.3, 0.2, 0.4];
    let steady = R.at_rate(5.0);
    assert_eq!(levels(Command::new(&table), &steady).len(), 5);
    assert_eq!(found(&table, &steady), vec![]);
    assert_eq!(holds(Command::new(&table), &steady).count(), 5);
}
