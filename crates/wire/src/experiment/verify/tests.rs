//! The plan against a stand that lies: driven frame by frame, the commands it sends checked.

use super::super::{ExperimentConfig, Output};
use super::*;
use crate::protocol::message::throttle_level;
use crate::protocol::{Ack, AckResult, EscProtocol, Event, EventCode, Frame, Hello};

fn cfg() -> ExperimentConfig {
    ExperimentConfig {
        levels: vec![0.4, 0.5],
        ramp_ms: 0,
        settle_ms: 50,
        pulse_spacing_ms: 40,
        pulses_per_level: 4,
        ..ExperimentConfig::default()
    }
}

fn frame(msg: Message) -> Frame {
    Frame { seq: 0, msg }
}

fn hello() -> Frame {
    frame(Message::Hello(Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::None,
        fw_version: 1,
        boot_id: 7,
        t_us: 0,
        sample_rate_hz: 1000,
        channels: 1,
        motor_poles: 0,
        caps: 0,
        name: Hello::name_field("t"),
    }))
}

fn ack(seq: u16, cmd_type: u8, result: AckResult) -> Frame {
    frame(Message::Ack(Ack {
        cmd_seq: seq,
        cmd_type,
        result,
        ack_flags: 0,
        t_us: 0,
    }))
}

fn sample(index: u32, throttle: f64, flags: SampleFlags) -> Frame {
    frame(Message::Sample(Sample {
        sample_index: index,
        t_us: index * 1000,
        throttle: throttle_level(throttle),
        flags,
        thrust_n: 0.0,
        torque_nm: 0.0,
        rpm: 0.0,
        voltage_v: 0.0,
        current_a: 0.0,
    }))
}

/// A scripted stand: ACKs every command with `answer(msg)`, and says what it applies
/// (`applied(commanded, in_pulse)`): every command the plan sends and every notice, in order.
struct Stand {
    plan: Experiment,
    now: u64,
    index: u32,
    sent: Vec<Message>,
    notices: Vec<Notice>,
    /// What the honest device would apply now (the last SET_THROTTLE) and a pulse running.
    commanded: f64,
    pulse: Option<(f64, u32)>,
}

impl Stand {
    fn new(cfg: ExperimentConfig) -> Stand {
        let mut plan = Experiment::new(cfg, 0).unwrap();
        plan.start(0);
        Stand {
            plan,
            now: 0,
            index: 0,
            sent: Vec::new(),
            notices: Vec::new(),
            commanded: 0.0,
            pulse: None,
        }
    }

    /// Runs `ms` milliseconds: one sample per ms (`lie` turns the honest throttle and flags into
    /// what the stand reports), commands answered with `answer`.
    fn run(
        &mut self,
        ms: u64,
        answer: &dyn Fn(&Message) -> AckResult,
        executes: bool,
        lie: &dyn Fn(f64, SampleFlags) -> (f64, SampleFlags),
    ) {
        for _ in 0..ms {
            self.now += 1000;
            self.plan.poll(self.now);
            self.drain(answer, executes);
            let (mut u, mut flags) = (self.commanded, SampleFlags::ARMED);
            if let Some((level, left)) = self.pulse {
                u = level;
                flags.insert(SampleFlags::IMPULSE_ACTIVE);
                self.pulse = (left > 1).then_some((level, left - 1));
            }
            let (u, flags) = lie(u, flags);
            let s = sample(self.index, u, flags);
            self.index += 1;
            self.plan.on_frame(&s, self.now);
            self.drain(answer, executes);
            if self.plan.is_over() && self.plan.next_output().is_none() {
                return;
            }
        }
    }

    fn drain(&mut self, answer: &dyn Fn(&Message) -> AckResult, executes: bool) {
        while let Some(o) = self.plan.next_output() {
            match o {
                Output::Notice(n) => self.notices.push(n),
                Output::Send { seq, msg } => {
                    self.sent.push(msg);
                    let result = answer(&msg);
                    if matches!(msg, Message::HelloReq) {
                        self.plan.on_frame(&hello(), self.now);
                    }
                    if result == AckResult::Ok && executes {
                        match msg {
                            Message::SetThrottle(s) => self.commanded = s.level as f64 / 10_000.0,
                            Message::Impulse(i) => {
                                self.pulse = Some((i.level as f64 / 10_000.0, 1));
                                let e = Event {
                                    code: EventCode::ImpulseStart,
                                    arg: i.level,
                                    t_us: 0,
                                    sample_index: self.index,
                                };
                                self.plan.on_frame(&frame(Message::Event(e)), self.now);
                            }
                            Message::Stop | Message::Disarm => self.commanded = 0.0,
                            _ => {}
                        }
                    }
                    if !matches!(msg, Message::Heartbeat) {
                        let a = ack(seq, msg.msg_type(), result);
                        self.plan.on_frame(&a, self.now);
                    }
                }
            }
        }
    }

    /// The commands sent, heartbeats left out.
    fn commands(&self) -> Vec<&'static str> {
        self.sent
            .iter()
            .filter(|m| !matches!(m, Message::Heartbeat))
            .map(|m| m.name())
            .collect()
    }
}

fn ok(_: &Message) -> AckResult {
    AckResult::Ok
}

fn honest(u: f64, f: SampleFlags) -> (f64, SampleFlags) {
    (u, f)
}

#[test]
fn an_honest_stand_finishes_the_plan() {
    let mut s = Stand::new(cfg());
    s.run(5_000, &ok, true, &honest);
    assert!(s.notices.contains(&Notice::Finished), "{:?}", s.notices);
    assert_eq!(s.commands().iter().filter(|c| **c == "IMPULSE").count(), 8);
}

#[test]
fn a_runaway_throttle_is_stopped_after_the_mismatch_time() {
    let mut s = Stand::new(cfg());
    s.run(5_000, &ok, true, &|u, f| {
        (
            if f.contains(SampleFlags::ARMED) && u > 0.0 {
                1.0
            } else {
                u
            },
            f,
        )
    });
    let n = s.notices.last().unwrap();
    let Notice::ThrottleMismatch {
        applied, for_ms, ..
    } = n
    else {
        panic!("{:?}", s.notices)
    };
    assert_eq!(*applied, 1.0);
    assert!(*for_ms > THROTTLE_MISMATCH_MS && *for_ms < THROTTLE_MISMATCH_MS + 5);
    assert_eq!(s.commands().last(), Some(&"STOP"));
    assert!(s.plan.is_over());
}

#[test]
fn a_short_excursion_is_no_mismatch() {
    // one sample in 100 at full throttle (a glitch): below the mismatch time
    let mut s = Stand::new(cfg());
    let i = std::cell::Cell::new(0u32);
    s.run(5_000, &ok, true, &|u, f| {
        i.set(i.get() + 1);
        (if i.get() % 100 == 0 { 1.0 } else { u }, f)
    });
    assert!(s.notices.contains(&Notice::Finished), "{:?}", s.notices);
}

#[test]
fn levels_acknowledged_and_never_applied_stop_the_plan() {
    let mut s = Stand::new(cfg());
    s.run(5_000, &ok, false, &honest);
    assert_eq!(
        s.notices.last(),
        Some(&Notice::CommandsNotExecuted {
            command: "SET_THROTTLE",
            level: 0.4
        }),
        "{:?}",
        s.notices
    );
    // one pulse fired, its spacing waited, then STOP
    let c = s.commands();
    assert_eq!(c.iter().filter(|c| **c == "IMPULSE").count(), 1, "{c:?}");
    assert_eq!(c.last(), Some(&"STOP"));
}

#[test]
fn pulses_acknowledged_and_never_seen_stop_the_plan_after_the_limit() {
    // the level is applied (whatever was commanded), the pulses leave no trace: no flag, no
    // event
    let answer_and_ignore_pulses = |_: &Message| AckResult::Ok;
    let mut s = Stand::new(cfg());
    s.run(5_000, &answer_and_ignore_pulses, false, &|_, f| (0.4, f));
    assert!(
        matches!(
            s.notices.last(),
            Some(Notice::CommandsNotExecuted {
                command: "IMPULSE",
                ..
            })
        ),
        "{:?}",
        s.notices
    );
    let c = s.commands();
    let pulses = c.iter().filter(|c| **c == "IMPULSE").count() as u32;
    assert_eq!(pulses, PULSES_UNSEEN_LIMIT, "{c:?}");
    assert_eq!(c.last(), Some(&"STOP"));
}

#[test]
fn an_impulse_answered_busy_for_ever_is_a_refusal_after_max_retries() {
    let c = ExperimentConfig {
        pulse_spacing_ms: 200,
        ..cfg()
    };
    let mut s = Stand::new(c);
    s.run(
        5_000,
        &|m| match m {
            Message::Impulse(_) => AckResult::Busy,
            _ => AckResult::Ok,
        },
        true,
        &honest,
    );
    assert_eq!(
        s.notices.last(),
        Some(&Notice::Refused {
            command: "IMPULSE",
            result: AckResult::Busy
        }),
        "{:?}",
        s.notices
    );
    let c = s.commands();
    let tries = c.iter().filter(|c| **c == "IMPULSE").count() as u32;
    assert_eq!(tries, cfg().max_retries + 1, "{c:?}");
    assert_eq!(c.last(), Some(&"STOP"));
}

#[test]
fn busy_is_bounded_by_one_pulse_spacing_too() {
    let c = ExperimentConfig {
        max_retries: 10,
        pulse_spacing_ms: 50,
        ..cfg()
    };
    let mut s = Stand::new(c);
    s.run(
        5_000,
        &|m| match m {
            Message::Impulse(_) => AckResult::Busy,
            _ => AckResult::Ok,
        },
        true,
        &honest,
    );
    assert!(matches!(s.notices.last(), Some(Notice::Refused { .. })));
    // 20 ms apart: tries at 0, 20, 40, and the one at 60 ms is past the 50 ms spacing
    let tries = s.commands().iter().filter(|c| **c == "IMPULSE").count();
    assert_eq!(tries, 4);
}

#[test]
fn a_busy_answer_now_and_then_is_retried_as_before() {
    let n = std::cell::Cell::new(0u32);
    let mut s = Stand::new(cfg());
    s.run(
        5_000,
        &|m| match m {
            Message::Impulse(_) => {
                n.set(n.get() + 1);
                if n.get() % 2 == 1 {
                    AckResult::Busy
                } else {
                    AckResult::Ok
                }
            }
            _ => AckResult::Ok,
        },
        true,
        &honest,
    );
    assert!(s.notices.contains(&Notice::Finished), "{:?}", s.notices);
}

#[test]
fn a_sample_rate_other_than_the_hellos_stops_an_armed_plan() {
    let mut s = Stand::new(cfg());
    s.run(100, &ok, true, &honest);
    s.plan.sample_rate_disagrees(1000, 500.0, s.now);
    s.drain(&ok, true);
    assert_eq!(
        s.notices.last(),
        Some(&Notice::RateMismatch {
            hello_hz: 1000,
            measured_hz: 500.0
        })
    );
    assert_eq!(s.commands().last(), Some(&"STOP"));
}
