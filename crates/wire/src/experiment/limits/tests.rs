//! The limits: each one per sample, what counts as a measurement, the unchecked ones named once,
//! the plan refused by its keys, and the plan ended for good by a breach.

use super::super::{Experiment, ExperimentConfig, Notice, Output, Phase};
use super::*;
use crate::protocol::message::throttle_level;
use crate::protocol::{Ack, AckResult, EscProtocol, Frame, Hello, Message};

/// A sample at throttle `u` with every measured channel valid: 2 A, 3 N, 5000 rpm, 12 V.
fn sample(u: f64) -> Sample {
    Sample {
        sample_index: 0,
        t_us: 0,
        throttle: throttle_level(u),
        flags: SampleFlags(0x3F),
        thrust_n: 3.0,
        torque_nm: 0.05,
        rpm: 5000.0,
        voltage_v: 12.0,
        current_a: 2.0,
    }
}

fn all() -> Limits {
    Limits {
        max_current_a: Some(10.0),
        max_thrust_n: Some(8.0),
        max_rpm: Some(20_000.0),
        min_voltage_v: Some(10.5),
        max_temperature_c: Some(80.0),
        max_throttle: Some(0.7),
    }
}

#[test]
fn each_limit_trips_on_its_own_quantity_and_names_itself() {
    let l = all();
    assert_eq!(l.breach(&sample(0.5)), None);
    type Case = (&'static str, fn(&mut Sample), f64, f64);
    let cases: [Case; 5] = [
        ("max_current_a", |s| s.current_a = 12.5, 12.5, 10.0),
        ("max_thrust_n", |s| s.thrust_n = 8.25, 8.25, 8.0),
        ("max_rpm", |s| s.rpm = 21_000.0, 21_000.0, 20_000.0),
        ("min_voltage_v", |s| s.voltage_v = 10.25, 10.25, 10.5),
        ("max_throttle", |s| s.throttle = 7500, 0.75, 0.7),
    ];
    for (which, bend, value, limit) in cases {
        let mut s = sample(0.5);
        bend(&mut s);
        let t = l.breach(&s).unwrap_or_else(|| panic!("{which}: no trip"));
        assert_eq!((t.which, t.limit), (which, limit));
        assert!((t.value - value).abs() < 1e-9, "{which}: {t:?}");
        // the same sample with that limit unset trips nothing
        let mut none = l;
        match which {
            "max_current_a" => none.max_current_a = None,
            "max_thrust_n" => none.max_thrust_n = None,
            "max_rpm" => none.max_rpm = None,
            "min_voltage_v" => none.min_voltage_v = None,
            _ => none.max_throttle = None,
        }
        assert_eq!(none.breach(&s), None, "{which}");
    }
}

#[test]
fn at_the_limit_is_no_breach_and_the_throttle_has_the_devices_rounding() {
    let l = all();
    let mut s = sample(0.5);
    s.current_a = 10.0;
    s.voltage_v = 10.5;
    assert_eq!(l.breach(&s), None);
    // the applied throttle may exceed the limit by the device's rounding
    assert_eq!(l.breach(&sample(0.7 + THROTTLE_TOLERANCE * 0.9)), None);
    assert!(l.breach(&sample(0.7 + THROTTLE_TOLERANCE * 1.1)).is_some());
}

#[test]
fn only_a_valid_finite_measurement_counts() {
    let l = all();
    let mut s = sample(0.5);
    s.current_a = 50.0;
    s.flags = SampleFlags(s.flags.0 & !SampleFlags::CURRENT_VALID.0);
    assert_eq!(l.breach(&s), None, "not measured");
    let mut s = sample(0.5);
    s.thrust_n = f32::NAN;
    s.voltage_v = f32::NAN;
    assert_eq!(l.breach(&s), None, "not a number");
    let mut s = sample(0.5);
    s.thrust_n = f32::INFINITY;
    assert_eq!(l.breach(&s), None, "not a number either");
}

#[test]
fn bad_limits_are_refused_by_key() {
    assert!(Limits::default().validate().is_ok());
    assert!(all().validate().is_ok());
    let bad: [(&str, Limits); 6] = [
        (
            "max_current_a",
            Limits {
                max_current_a: Some(f64::NAN),
                ..all()
            },
        ),
        (
            "max_thrust_n",
            Limits {
                max_thrust_n: Some(0.0),
                ..all()
            },
        ),
        (
            "max_rpm",
            Limits {
                max_rpm: Some(-1.0),
                ..all()
            },
        ),
        (
            "min_voltage_v",
            Limits {
                min_voltage_v: Some(f64::INFINITY),
                ..all()
            },
        ),
        (
            "max_temperature_c",
            Limits {
                max_temperature_c: Some(900.0),
                ..all()
            },
        ),
        (
            "max_throttle",
            Limits {
                max_throttle: Some(1.2),
                ..all()
            },
        ),
    ];
    for (key, l) in bad {
        match l.validate() {
            Err(LimitsError::OutOfRange { key: k, .. }) => assert_eq!(k, key),
            other => panic!("{key}: {other:?}"),
        }
    }
}

#[test]
fn a_plan_above_max_throttle_is_refused_by_its_pair() {
    let plan = ExperimentConfig {
        levels: vec![0.3, 0.6],
        pulse_amplitudes: vec![0.05, 0.1],
        ..ExperimentConfig::default()
    };
    let l = |m: f64| Limits {
        max_throttle: Some(m),
        ..Limits::default()
    };
    // 0.6 + 0.1 = 0.7 is the top of the envelope: allowed at 0.7, refused below
    assert!(l(0.7).refuse_plan(&plan).is_ok());
    match l(0.68).refuse_plan(&plan) {
        Err(e @ LimitsError::PlanExceeds { .. }) => {
            let LimitsError::PlanExceeds { key, value, limit } = &e else {
                unreachable!()
            };
            assert_eq!(key, "levels[1] + pulse_amplitudes[1]", "{e}");
            assert!(value.ends_with("= 0.7"), "{e}");
            assert_eq!(*limit, 0.68);
            assert!(e.to_string().contains("max_throttle"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    // the first above it, in the plan's order; a level itself is named alone
    match l(0.38).refuse_plan(&plan) {
        Err(LimitsError::PlanExceeds { key, .. }) => {
            assert_eq!(key, "levels[0] + pulse_amplitudes[1]")
        }
        other => panic!("{other:?}"),
    }
    match l(0.5).refuse_plan(&plan) {
        Err(LimitsError::PlanExceeds { key, .. }) => assert_eq!(key, "levels[1]"),
        other => panic!("{other:?}"),
    }
    match l(0.25).refuse_plan(&plan) {
        Err(LimitsError::PlanExceeds { key, .. }) => assert_eq!(key, "levels[0]"),
        other => panic!("{other:?}"),
    }
    assert!(Limits::default().refuse_plan(&plan).is_ok());
    // the plan keeps it: set_limits refuses too, and leaves the plan unguarded
    let mut exp = Experiment::new(plan, 0).unwrap();
    assert!(exp.set_limits(l(0.5)).is_err());
}

#[test]
fn a_limit_the_stand_never_reports_is_named_once_after_the_first_samples() {
    let mut g = LimitGuard::new(all());
    let mut named = Vec::new();
    // a stand with thrust and current only
    let mut s = sample(0.0);
    s.flags = SampleFlags(SampleFlags::THRUST_VALID.0 | SampleFlags::CURRENT_VALID.0);
    for k in 0..3 * JUDGE_SAMPLES {
        let before = named.len();
        assert_eq!(g.sample(&s, &mut |w, _| named.push(w)), None);
        if k + 1 < JUDGE_SAMPLES {
            assert_eq!(named.len(), before, "named before {JUDGE_SAMPLES} samples");
        }
    }
    assert_eq!(named, ["max_rpm", "min_voltage_v", "max_temperature_c"]);
    // a limit named is still checked should its quantity appear
    s.flags.insert(SampleFlags::RPM_VALID);
    s.rpm = 25_000.0;
    let t = g.sample(&s, &mut |w, _| named.push(w)).unwrap();
    assert_eq!(t.which, "max_rpm");
    assert_eq!(named.len(), 3);
    // no limits, nothing named
    let mut g = LimitGuard::new(Limits::default());
    for _ in 0..2 * JUDGE_SAMPLES {
        g.sample(&s, &mut |w, _| panic!("{w}"));
    }
}

// --- the plan ---------------------------------------------------------------------------

fn frame(msg: Message) -> Frame {
    Frame { seq: 0, msg }
}

fn hello(boot_id: u32) -> Frame {
    frame(Message::Hello(Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::None,
        fw_version: 1,
        boot_id,
        t_us: 0,
        sample_rate_hz: 1000,
        channels: 0x1F,
        motor_poles: 0,
        caps: 0,
        name: Hello::name_field("t"),
    }))
}

/// A plan driven by an honest stand (every command acknowledged and applied, HELLO with
/// `boot_id`), sampling `current` at each millisecond: the commands sent and the notices.
struct Bench {
    plan: Experiment,
    now: u64,
    boot_id: u32,
    /// The throttle applied, and a pulse's level for the next sample.
    applied: f64,
    pulse: Option<f64>,
    sent: Vec<Message>,
    notices: Vec<Notice>,
}

impl Bench {
    fn new(cfg: ExperimentConfig, limits: Limits) -> Bench {
        let mut plan = Experiment::new(cfg, 0).unwrap();
        plan.set_limits(limits).unwrap();
        plan.start(0);
        let mut b = Bench {
            plan,
            now: 0,
            boot_id: 7,
            applied: 0.0,
            pulse: None,
            sent: Vec::new(),
            notices: Vec::new(),
        };
        b.drain();
        b
    }

    fn drain(&mut self) {
        while let Some(o) = self.plan.next_output() {
            match o {
                Output::Notice(n) => self.notices.push(n),
                Output::Send { seq, msg } => {
                    self.sent.push(msg);
                    match msg {
                        Message::HelloReq => self.plan.on_frame(&hello(self.boot_id), self.now),
                        Message::SetThrottle(t) => self.applied = t.level as f64 / 1e4,
                        Message::Impulse(i) => self.pulse = Some(i.level as f64 / 1e4),
                        Message::Stop | Message::Disarm => self.applied = 0.0,
                        _ => {}
                    }
                    if !matches!(msg, Message::Heartbeat) {
                        let a = Ack {
                            cmd_seq: seq,
                            cmd_type: msg.msg_type(),
                            result: AckResult::Ok,
                            ack_flags: 0,
                            t_us: 0,
                        };
                        self.plan.on_frame(&frame(Message::Ack(a)), self.now);
                    }
                }
            }
        }
    }

    /// `ms` milliseconds, a sample each with `current` A.
    fn run(&mut self, ms: u64, current: f32) {
        for _ in 0..ms {
            self.now += 1000;
            self.plan.poll(self.now);
            self.drain();
            let mut s = sample(self.applied);
            if let Some(p) = self.pulse.take() {
                s = sample(p);
                s.flags.insert(SampleFlags::IMPULSE_ACTIVE);
            }
            s.current_a = current;
            self.plan.on_frame(&frame(Message::Sample(s)), self.now);
            self.drain();
        }
    }

    fn tripped(&self) -> usize {
        self.notices
            .iter()
            .filter(|n| matches!(n, Notice::LimitTripped { .. }))
            .count()
    }
}

fn plan_cfg(rearm: bool) -> ExperimentConfig {
    ExperimentConfig {
        levels: vec![0.4],
        ramp_ms: 0,
        settle_ms: 50,
        pulse_spacing_ms: 40,
        pulses_per_level: 4,
        rearm_on_reset: rearm,
        ..ExperimentConfig::default()
    }
}

fn current_limit() -> Limits {
    Limits {
        max_current_a: Some(10.0),
        ..Limits::default()
    }
}

#[test]
fn a_breach_ends_the_plan_with_a_stop_at_once() {
    let mut b = Bench::new(plan_cfg(false), current_limit());
    b.run(100, 2.0);
    assert_eq!(b.plan.phase(), Phase::Pulsing, "{:?}", b.notices);
    let sent_before = b.sent.len();
    b.run(1, 11.0);
    assert!(b.plan.is_over());
    let n = b.notices.last().unwrap();
    assert_eq!(
        *n,
        Notice::LimitTripped {
            which: "max_current_a",
            value: 11.0,
            limit: 10.0
        }
    );
    // the STOP went out with the sample that tripped, and nothing after it
    assert_eq!(b.sent[sent_before..], [Message::Stop]);
    b.run(500, 11.0);
    assert_eq!(
        b.sent.len(),
        sent_before + 1,
        "{:?}",
        &b.sent[sent_before..]
    );
    assert_eq!(b.tripped(), 1);
}

#[test]
fn a_breach_is_never_rearmed_by_rearm_on_reset() {
    let mut b = Bench::new(plan_cfg(true), current_limit());
    b.run(100, 2.0);
    b.run(1, 11.0);
    let at_trip = b.sent.len();
    // the device resets (a new boot's HELLO), the link is reopened: neither re-arms
    b.boot_id = 8;
    b.plan.on_frame(&hello(8), b.now);
    b.plan.reconnected(b.now);
    b.plan.link_stalled(b.now);
    b.plan.reconnected(b.now);
    b.drain();
    b.run(500, 2.0);
    let after: Vec<_> = b.sent[at_trip..]
        .iter()
        .filter(|m| !matches!(m, Message::Stop))
        .collect();
    assert!(after.is_empty(), "{after:?}");
    assert!(b.plan.is_over() && !b.plan.rearm_pending());
}

#[test]
fn a_breach_while_waiting_to_rearm_cancels_the_rearm() {
    let mut b = Bench::new(plan_cfg(true), current_limit());
    b.run(100, 2.0);
    b.plan.link_stalled(b.now);
    b.drain();
    assert!(b.plan.rearm_pending());
    b.run(1, 11.0);
    assert_eq!(b.tripped(), 1);
    assert!(!b.plan.rearm_pending());
    let at_trip = b.sent.len();
    b.plan.reconnected(b.now);
    b.drain();
    b.run(200, 2.0);
    assert!(
        !b.sent[at_trip..]
            .iter()
            .any(|m| matches!(m, Message::Arm(_) | Message::SetThrottle(_))),
        "{:?}",
        &b.sent[at_trip..]
    );
}

#[test]
fn no_breach_after_the_plan_finished() {
    let mut b = Bench::new(plan_cfg(false), current_limit());
    b.run(3_000, 2.0);
    assert!(b.notices.contains(&Notice::Finished), "{:?}", b.notices);
    b.run(10, 50.0);
    assert_eq!(b.tripped(), 0);
}
