//! Tests of the experiment plan, against the real firmware state machine where it matters.

use crate::config::{FaultConfig, StandConfig};
use crate::dynamics::EchoStand;
use crate::faults::FaultInjector;
use crate::firmware::Firmware;
use crate::record::run_loop;
use propid_wire::experiment::*;
use propid_wire::protocol::message::msg_type;
use propid_wire::protocol::{
    encode_frame, Ack, AckResult, Decoder, Event, EventCode, Frame, Hello, Message, Sample,
    MAX_FRAME_LEN,
};

fn quick() -> ExperimentConfig {
    ExperimentConfig {
        levels: vec![0.3, 0.5],
        ramp_ms: 50,
        settle_ms: 50,
        pulse_spacing_ms: 40,
        pulses_per_level: 3,
        ..ExperimentConfig::default()
    }
}

fn firmware() -> Firmware<EchoStand> {
    let faults = FaultInjector::new(&FaultConfig::default(), 1);
    Firmware::new(&StandConfig::default(), EchoStand::new(10.0), 42, faults)
}

fn drain(plan: &mut Experiment) -> (Vec<(u16, Message)>, Vec<Notice>) {
    let (mut sends, mut notices) = (Vec::new(), Vec::new());
    while let Some(o) = plan.next_output() {
        match o {
            Output::Send { seq, msg } => sends.push((seq, msg)),
            Output::Notice(n) => notices.push(n),
        }
    }
    (sends, notices)
}

fn hello(boot_id: u32) -> Frame {
    Frame {
        seq: 0,
        msg: Message::Hello(Hello {
            proto_minor: 0,
            esc_protocol: propid_wire::protocol::EscProtocol::None,
            fw_version: 1,
            boot_id,
            t_us: 0,
            sample_rate_hz: 1000,
            channels: 1,
            motor_poles: 0,
            caps: 0,
            name: Hello::name_field("t"),
        }),
    }
}

fn ack(seq: u16, t: u8, result: AckResult) -> Frame {
    Frame {
        seq: 1,
        msg: Message::Ack(Ack {
            cmd_seq: seq,
            cmd_type: t,
            result,
            ack_flags: 0,
            t_us: 0,
        }),
    }
}

#[test]
fn whole_plan_against_the_firmware_fires_every_pulse_once_with_alternating_sign() {
    let mut fw = firmware();
    let mut plan = Experiment::new(quick(), 0).unwrap();
    let mut rec = Vec::new();
    let sum = run_loop(&mut fw, &mut plan, 5.0, &mut rec).unwrap();
    assert!(sum.finished, "{:?}", sum.notices);
    assert_eq!((sum.pulses, sum.levels_done), (6, 2));
    assert_eq!(fw.stats().pulses, 6);
    assert!(!fw.is_armed());
    // Decode the recording: pulse levels alternate around each operating point.
    let mut dec = Decoder::new();
    let mut frames = Vec::new();
    dec.push(&rec, |f| frames.push(f));
    let starts: Vec<u16> = frames
        .iter()
        .filter_map(|f| match f.msg {
            Message::Event(Event {
                code: EventCode::ImpulseStart,
                arg,
                ..
            }) => Some(arg),
            _ => None,
        })
        .collect();
    assert_eq!(starts, vec![3500, 2500, 4000, 5500, 4500, 6000]);
    let samples: Vec<Sample> = frames
        .iter()
        .filter_map(|f| match f.msg {
            Message::Sample(s) => Some(s),
            _ => None,
        })
        .collect();
    assert!(samples
        .windows(2)
        .all(|w| w[1].sample_index == w[0].sample_index + 1));
    // The plan outlasts the 500 ms watchdog many times over: heartbeats kept it quiet.
    assert!(sum.seconds > 1.0 && fw.stats().watchdog_trips == 0);
}

#[test]
fn unanswered_command_is_resent_with_the_same_seq_then_the_link_fails() {
    let mut plan = Experiment::new(quick(), 7).unwrap();
    plan.start(0);
    let (s, _) = drain(&mut plan);
    assert_eq!(s, vec![(7, Message::HelloReq)]);
    for k in 1..=3u64 {
        plan.poll(k * 50_000 - 1);
        assert!(drain(&mut plan).0.is_empty(), "not before 50 ms");
        plan.poll(k * 50_000);
        assert_eq!(drain(&mut plan).0, vec![(7, Message::HelloReq)]);
    }
    plan.poll(200_000);
    let (s, n) = drain(&mut plan);
    assert!(s.is_empty());
    assert_eq!(
        n,
        vec![Notice::LinkFailed {
            command: "HELLO_REQ",
            seq: 7
        }]
    );
    assert!(plan.is_over());
}

#[test]
fn device_reset_is_reported_and_never_re_armed() {
    let mut plan = Experiment::new(quick(), 0).unwrap();
    plan.start(0);
    drain(&mut plan);
    plan.on_frame(&hello(11), 100);
    plan.on_frame(&ack(0, msg_type::HELLO_REQ, AckResult::Ok), 200);
    let (s, n) = drain(&mut plan);
    assert_eq!(
        n,
        vec![Notice::Connected {
            boot_id: 11,
            sample_rate_hz: 1000
        }]
    );
    assert!(matches!(s[0].1, Message::Arm(_)));
    plan.on_frame(&ack(1, msg_type::ARM, AckResult::Ok), 300);
    drain(&mut plan);
    plan.on_frame(&hello(12), 400);
    let (s, n) = drain(&mut plan);
    assert!(s.is_empty());
    assert_eq!(
        n,
        vec![Notice::DeviceReset {
            old_boot_id: 11,
            new_boot_id: 12,
            rearm: false
        }]
    );
    for t in (500..2_000_000).step_by(10_000) {
        plan.poll(t);
    }
    assert!(drain(&mut plan).0.is_empty(), "no ARM, no heartbeat");
}

fn pulses_fired(notices: &[Notice]) -> u64 {
    notices
        .iter()
        .filter(|n| matches!(n, Notice::PulseFired { .. }))
        .count() as u64
}

/// Runs plan and firmware in lock step, losing the first IMPULSE's ACK (the device's output of
/// the step that executes it) and, when `lose_event`, its EVENT IMPULSE_START too (sent at the
/// next sample); returns the pulses the device fired, the plan's `PulseFired` notices and
/// whether an ACK said DUPLICATE.
fn lose_the_first_pulse_ack(cfg: ExperimentConfig, lose_event: bool) -> (u64, u64, bool) {
    let mut fw = firmware();
    let mut plan = Experiment::new(cfg, 0).unwrap();
    let mut dec = Decoder::new();
    let mut lost = false;
    let mut event_to_lose = lose_event;
    let mut dup_seen = false;
    let mut fired = 0;
    let pulse_start =
        |f: &Frame| matches!(f.msg, Message::Event(e) if e.code == EventCode::ImpulseStart);
    plan.start(0);
    for t in (0..3_000_000u64).step_by(1000) {
        let mut bytes = Vec::new();
        let mut impulse_sent = false;
        let (sends, notices) = drain(&mut plan);
        fired += pulses_fired(&notices);
        for (seq, msg) in sends {
            impulse_sent |= matches!(msg, Message::Impulse(_));
            let mut buf = [0u8; MAX_FRAME_LEN];
            let n = encode_frame(seq, &msg, &mut buf);
            bytes.extend_from_slice(&buf[..n]);
        }
        fw.feed(t, &bytes);
        fw.advance(t);
        let mut out = Vec::new();
        fw.drain_output(t, &mut out);
        if impulse_sent && !lost {
            lost = true; // the first IMPULSE's ACK never arrives
            continue;
        }
        let mut frames = Vec::new();
        dec.push(&out, |f| frames.push(f));
        if lost && event_to_lose && frames.iter().any(pulse_start) {
            event_to_lose = false;
            frames.retain(|f| !pulse_start(f));
        }
        for f in &frames {
            if let Message::Ack(a) = f.msg {
                dup_seen |= a.is_duplicate();
            }
            plan.on_frame(f, t);
        }
        plan.poll(t);
        if plan.is_over() {
            break;
        }
    }
    fired += pulses_fired(&drain(&mut plan).1);
    assert!(lost);
    assert_eq!(plan.phase(), Phase::Done);
    (fw.stats().pulses, fired, dup_seen)
}

#[test]
fn lost_ack_of_a_pulse_is_resent_and_answered_as_duplicate_without_a_second_pulse() {
    let (pulses, fired, dup_seen) = lose_the_first_pulse_ack(quick(), true);
    assert!(dup_seen);
    assert_eq!((pulses, fired), (6, 6), "six pulses, none fired twice");
}

#[test]
fn watchdog_trip_ends_the_plan() {
    let mut plan = Experiment::new(quick(), 0).unwrap();
    plan.start(0);
    plan.on_frame(&hello(1), 10);
    plan.on_frame(&ack(0, msg_type::HELLO_REQ, AckResult::Ok), 10);
    drain(&mut plan);
    let trip = Frame {
        seq: 5,
        msg: Message::Event(Event {
            code: EventCode::WatchdogTrip,
            arg: 0,
            t_us: 0,
            sample_index: 0,
        }),
    };
    plan.on_frame(&trip, 20);
    assert_eq!(drain(&mut plan).1, vec![Notice::WatchdogTripped]);
    assert!(plan.is_over());
}

#[test]
fn refused_arm_ends_the_plan_with_a_stop() {
    let mut plan = Experiment::new(quick(), 0).unwrap();
    plan.start(0);
    plan.on_frame(&hello(1), 10);
    plan.on_frame(&ack(0, msg_type::HELLO_REQ, AckResult::Ok), 10);
    drain(&mut plan);
    plan.on_frame(&ack(1, msg_type::ARM, AckResult::BadState), 20);
    let (s, n) = drain(&mut plan);
    assert_eq!(
        n,
        vec![Notice::Refused {
            command: "ARM",
            result: AckResult::BadState
        }]
    );
    assert_eq!(s, vec![(2, Message::Stop)]);
}

#[test]
fn abort_sends_stop_until_acknowledged() {
    let mut plan = Experiment::new(quick(), 0).unwrap();
    plan.start(0);
    drain(&mut plan);
    plan.abort(1000);
    let (s, _) = drain(&mut plan);
    assert_eq!(s, vec![(1, Message::Stop)]);
    plan.poll(51_000);
    assert_eq!(drain(&mut plan).0, vec![(1, Message::Stop)]);
    plan.on_frame(&ack(1, msg_type::STOP, AckResult::Ok), 60_000);
    assert_eq!(drain(&mut plan).1, vec![Notice::Stopped]);
    assert!(plan.is_over());
}

/// The soak's slack for a loaded host (`retry_ms = 1000`) and a pulse's ACK lost: a re-send
/// of the IMPULSE would come after the device's one-second repeat memory (and after eight
/// heartbeats pushed it out of the ring of eight), and the device would take it for a new
/// command: a second pulse the plan never counted (7 fired, 6 noticed). The pulse's EVENT
/// IMPULSE_START, received, tells the plan it fired: counted, not re-sent.
#[test]
fn lost_ack_of_a_pulse_with_its_event_received_is_counted_and_not_resent() {
    let cfg = ExperimentConfig {
        retry_ms: 1000,
        max_retries: 10,
        watchdog_ms: 5000,
        ..quick()
    };
    let (pulses, fired, dup_seen) = lose_the_first_pulse_ack(cfg, false);
    assert_eq!((pulses, fired), (6, 6), "six pulses, none fired twice");
    assert!(!dup_seen, "nothing re-sent");
}
