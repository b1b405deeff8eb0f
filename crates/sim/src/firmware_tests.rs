//! Unit tests of the firmware: every command and result code, duplicates, the watchdog, pulse
//! timing, the clock wrap. The stand is an exact [`EchoStand`] so values can be checked exactly.

use super::*;
use crate::config::FaultConfig;
use crate::dynamics::EchoStand;
use propid_wire::protocol::message::{msg_type, ACK_DUPLICATE};
use propid_wire::protocol::{
    encode_raw, Ack, AckResult, Arm, Decoder, Frame, Impulse, SetRate, SetThrottle,
};

struct Bench {
    fw: Firmware<EchoStand>,
    dec: Decoder,
    frames: Vec<Frame>,
    seq: u16,
}

impl Bench {
    fn with(cfg: StandConfig) -> Self {
        let faults = FaultInjector::new(&FaultConfig::default(), 1);
        let mut b = Bench {
            fw: Firmware::new(&cfg, EchoStand::new(10.0), 0xB007_1D00, faults),
            dec: Decoder::new(),
            frames: Vec::new(),
            seq: 100,
        };
        b.pump();
        b
    }

    fn new() -> Self {
        Self::with(StandConfig::default())
    }

    fn pump(&mut self) {
        let mut out = Vec::new();
        self.fw.drain_output(u64::MAX, &mut out);
        let frames = &mut self.frames;
        self.dec.push(&out, |f| frames.push(f));
        assert_eq!(self.dec.stats().dropped.total(), 0);
    }

    fn run_to(&mut self, t_us: u64) {
        self.fw.advance(t_us);
        self.pump();
    }

    /// Sends `msg` with a fresh seq at `t_us`; returns its ACK.
    fn cmd(&mut self, t_us: u64, msg: Message) -> Ack {
        self.seq += 1;
        self.cmd_seq(t_us, self.seq, msg)
    }

    fn cmd_seq(&mut self, t_us: u64, seq: u16, msg: Message) -> Ack {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(seq, &msg, &mut buf);
        self.raw(t_us, &buf[..n], seq)
    }

    fn raw(&mut self, t_us: u64, bytes: &[u8], seq: u16) -> Ack {
        self.frames.clear();
        self.fw.feed(t_us, bytes);
        self.pump();
        let acks: Vec<Ack> = self
            .acks()
            .into_iter()
            .filter(|a| a.cmd_seq == seq)
            .collect();
        assert_eq!(acks.len(), 1, "exactly one ACK: {:?}", self.frames);
        acks[0]
    }

    fn acks(&self) -> Vec<Ack> {
        self.frames
            .iter()
            .filter_map(|f| match f.msg {
                Message::Ack(a) => Some(a),
                _ => None,
            })
            .collect()
    }

    fn samples(&self) -> Vec<Sample> {
        self.frames
            .iter()
            .filter_map(|f| match f.msg {
                Message::Sample(s) => Some(s),
                _ => None,
            })
            .collect()
    }

    fn events(&self) -> Vec<Event> {
        self.frames
            .iter()
            .filter_map(|f| match f.msg {
                Message::Event(e) => Some(e),
                _ => None,
            })
            .collect()
    }

    fn armed(&mut self, t_us: u64) {
        let a = self.cmd(t_us, Message::Arm(Arm::new(500)));
        assert_eq!(a.result, AckResult::Ok);
    }
}

fn thr(level: u16, ramp_ms: u16) -> Message {
    Message::SetThrottle(SetThrottle { level, ramp_ms })
}

fn imp(level: u16, width_us: u32) -> Message {
    Message::Impulse(Impulse { level, width_us })
}

#[test]
fn boot_sends_hello_reset_cause_and_log_then_one_sample_per_period() {
    let mut b = Bench::new();
    assert!(
        matches!(b.frames[0].msg, Message::Hello(h) if h.boot_id == 0xB007_1D00
        && h.sample_rate_hz == 1000 && h.channels == 0b11111)
    );
    assert_eq!(b.events()[0].code, EventCode::ResetCause);
    assert!(matches!(b.frames[2].msg, Message::Log(_)));
    b.frames.clear();
    b.run_to(10_000);
    let s = b.samples();
    assert_eq!(s.len(), 10);
    for (k, x) in s.iter().enumerate() {
        assert_eq!(x.sample_index, k as u32);
        assert_eq!(x.t_us, 1000 * (k as u32 + 1));
        assert!(!x.is_armed());
        assert!(x
            .flags
            .contains(SampleFlags::THRUST_VALID | SampleFlags::CURRENT_VALID));
    }
    let seqs: Vec<u16> = b.frames.iter().map(|f| f.seq).collect();
    assert!(seqs.windows(2).all(|w| w[1] == w[0].wrapping_add(1)));
}

#[test]
fn hello_every_second_and_on_request() {
    let mut b = Bench::new();
    b.frames.clear();
    b.run_to(2_500_000);
    let hellos = b
        .frames
        .iter()
        .filter(|f| matches!(f.msg, Message::Hello(_)))
        .count();
    assert_eq!(hellos, 2);
    let a = b.cmd(2_500_500, Message::HelloReq);
    assert_eq!(a.result, AckResult::Ok);
    let pos_hello = b
        .frames
        .iter()
        .position(|f| matches!(f.msg, Message::Hello(_)));
    let pos_ack = b
        .frames
        .iter()
        .position(|f| matches!(f.msg, Message::Ack(_)));
    assert!(pos_hello.unwrap() < pos_ack.unwrap(), "HELLO, then ACK");
}

#[test]
fn arm_checks_key_range_and_state() {
    let mut b = Bench::new();
    let bad_key = Message::Arm(Arm {
        watchdog_ms: 500,
        key: 0x1234,
    });
    assert_eq!(b.cmd(100, bad_key).result, AckResult::BadKey);
    assert_eq!(
        b.cmd(200, Message::Arm(Arm::new(50))).result,
        AckResult::OutOfRange
    );
    assert_eq!(
        b.cmd(300, Message::Arm(Arm::new(6000))).result,
        AckResult::OutOfRange
    );
    assert_eq!(
        b.cmd(400, Message::Arm(Arm::new(500))).result,
        AckResult::Ok
    );
    assert_eq!(b.events()[0].code, EventCode::Armed);
    assert_eq!(b.cmd(500, thr(3000, 0)).result, AckResult::Ok);
    assert_eq!(
        b.cmd(600, Message::Arm(Arm::new(500))).result,
        AckResult::BadState
    );
}

#[test]
fn set_throttle_states_ranges_and_timing() {
    let mut b = Bench::new();
    assert_eq!(b.cmd(100, thr(3000, 0)).result, AckResult::BadState);
    b.armed(200);
    assert_eq!(b.cmd(300, thr(10_001, 0)).result, AckResult::OutOfRange);
    let a = b.cmd(2_500, thr(3000, 0));
    assert_eq!(a.result, AckResult::Ok);
    assert_eq!(a.t_us, 3_000, "applied at the next boundary");
    b.frames.clear();
    b.run_to(6_000);
    let s = b.samples();
    // sample 2 (period 2000..3000) still at 0, 3.. at 3000; thrust read at the period's end.
    assert_eq!((s[0].sample_index, s[0].throttle), (2, 0));
    assert_eq!((s[1].sample_index, s[1].throttle), (3, 3000));
    assert_eq!(s[1].thrust_n, 3.0);
    assert!(s.iter().all(|x| x.is_armed()));
}

#[test]
fn ramp_is_linear_flagged_and_makes_impulse_busy() {
    let mut b = Bench::new();
    b.armed(100);
    b.cmd(500, thr(1000, 10)); // 0 -> 1000 over 10 ms from t = 1000
    b.frames.clear();
    b.run_to(13_000);
    let s = b.samples();
    let levels: Vec<u16> = s.iter().map(|x| x.throttle).collect();
    assert_eq!(
        &levels[..12],
        &[0, 0, 100, 200, 300, 400, 500, 600, 700, 800, 900, 1000]
    );
    assert!(s[2].flags.contains(SampleFlags::RAMP_ACTIVE));
    assert!(!s[11].flags.contains(SampleFlags::RAMP_ACTIVE));
    let mut b = Bench::new();
    b.armed(100);
    b.cmd(500, thr(1000, 100));
    assert_eq!(b.cmd(5_500, imp(2000, 1000)).result, AckResult::Busy);
}

#[test]
fn impulse_edges_carry_the_exact_sample_index() {
    let mut b = Bench::new();
    b.armed(100);
    b.cmd(200, thr(3000, 0));
    b.run_to(5_000);
    let a = b.cmd(5_400, imp(3500, 3_000)); // 3 periods at 1 kHz
    assert_eq!((a.result, a.t_us), (AckResult::Ok, 6_000));
    assert_eq!(b.cmd(5_500, imp(3500, 1000)).result, AckResult::Busy);
    assert_eq!(b.cmd(5_600, thr(2000, 0)).result, AckResult::Busy);
    b.frames.clear();
    b.run_to(12_000);
    let ev = b.events();
    assert_eq!(ev.len(), 2);
    assert_eq!(
        (ev[0].code, ev[0].sample_index, ev[0].t_us),
        (EventCode::ImpulseStart, 6, 6_000)
    );
    assert_eq!(
        (ev[1].code, ev[1].sample_index, ev[1].t_us),
        (EventCode::ImpulseEnd, 9, 9_000)
    );
    for s in b.samples() {
        let inside = (6..9).contains(&s.sample_index);
        assert_eq!(s.throttle, if inside { 3500 } else { 3000 }, "{s:?}");
        assert_eq!(s.flags.contains(SampleFlags::IMPULSE_ACTIVE), inside);
        assert!((s.thrust_n as f64 - 10.0 * s.throttle as f64 / 1e4).abs() < 1e-5);
    }
    // Out of range widths and levels.
    assert_eq!(b.cmd(12_100, imp(3500, 0)).result, AckResult::OutOfRange);
    assert_eq!(
        b.cmd(12_200, imp(3500, 2_000_000)).result,
        AckResult::OutOfRange
    );
    assert_eq!(
        b.cmd(12_300, imp(10_001, 1000)).result,
        AckResult::OutOfRange
    );
    b.cmd(12_400, Message::Disarm);
    assert_eq!(b.cmd(12_500, imp(3500, 1000)).result, AckResult::BadState);
}

#[test]
fn duplicate_is_answered_but_never_fires_twice() {
    let mut b = Bench::new();
    b.armed(100);
    b.cmd(200, thr(3000, 0));
    let first = b.cmd_seq(5_000, 77, imp(4000, 1000));
    assert_eq!((first.result, first.ack_flags), (AckResult::Ok, 0));
    b.run_to(50_000);
    let again = b.cmd_seq(50_100, 77, imp(4000, 1000));
    assert_eq!(
        (again.result, again.ack_flags),
        (AckResult::Ok, ACK_DUPLICATE)
    );
    b.frames.clear();
    b.run_to(100_000);
    assert!(b.events().is_empty(), "no second pulse");
    assert_eq!(b.fw.stats().pulses, 1);
    // A refused command's repeat gets the stored refusal.
    let busy = b.cmd_seq(100_100, 78, thr(20_000, 0));
    let rep = b.cmd_seq(100_200, 78, thr(20_000, 0));
    assert_eq!(busy.result, AckResult::OutOfRange);
    assert_eq!(
        (rep.result, rep.ack_flags),
        (AckResult::OutOfRange, ACK_DUPLICATE)
    );
    // After one second the same seq is a new command (re-arm: the watchdog tripped meanwhile).
    b.armed(1_199_000);
    let late = b.cmd_seq(1_200_000, 77, imp(4000, 1000));
    assert_eq!((late.result, late.ack_flags), (AckResult::Ok, 0));
}

#[test]
fn watchdog_trips_without_commands_and_heartbeats_prevent_it() {
    let mut b = Bench::new();
    b.cmd(100, Message::Arm(Arm::new(200)));
    b.cmd(200, thr(3000, 0));
    for t in (100_000..1_000_000).step_by(100_000) {
        assert_eq!(b.cmd(t, Message::Heartbeat).result, AckResult::Ok);
    }
    assert!(b.fw.is_armed());
    b.frames.clear();
    b.run_to(1_300_000);
    let ev = b.events();
    assert_eq!(ev[0].code, EventCode::WatchdogTrip);
    assert_eq!(ev[0].t_us, 1_100_000, "200 ms after the last command");
    assert_eq!(ev[1].code, EventCode::Disarmed);
    assert!(!b.fw.is_armed());
    let last = *b.samples().last().unwrap();
    assert!(last.flags.contains(SampleFlags::WATCHDOG_TRIPPED));
    assert!(!last.is_armed() && last.throttle == 0);
    // Re-arming clears the tripped flag.
    b.armed(1_300_100);
    b.frames.clear();
    b.run_to(1_305_000);
    assert!(!b.samples()[3].flags.contains(SampleFlags::WATCHDOG_TRIPPED));
}

#[test]
fn stop_is_always_accepted_and_cancels_a_running_pulse() {
    let mut b = Bench::new();
    assert_eq!(b.cmd(100, Message::Stop).result, AckResult::Ok);
    assert_eq!(
        b.cmd(150, Message::Disarm).result,
        AckResult::Ok,
        "idempotent"
    );
    b.armed(200);
    b.cmd(300, thr(3000, 0));
    b.cmd(1_500, imp(5000, 10_000));
    b.run_to(4_500);
    assert_eq!(b.cmd(4_600, Message::Stop).result, AckResult::Ok);
    let ev = b.events();
    assert_eq!(ev[0].code, EventCode::ImpulseEnd);
    assert_eq!((ev[0].sample_index, ev[0].t_us), (5, 5_000));
    assert_eq!(ev[1].code, EventCode::Disarmed);
    b.frames.clear();
    b.run_to(8_000);
    assert!(b
        .samples()
        .iter()
        .skip(1)
        .all(|s| s.throttle == 0 && !s.is_armed()));
}

#[test]
fn set_rate_and_tare_only_when_disarmed() {
    let mut b = Bench::new();
    b.armed(100);
    let rate = |hz| Message::SetRate(SetRate { sample_rate_hz: hz });
    assert_eq!(b.cmd(200, rate(2000)).result, AckResult::BadState);
    assert_eq!(b.cmd(300, Message::Tare).result, AckResult::BadState);
    b.cmd(400, Message::Disarm);
    assert_eq!(b.cmd(500, rate(5)).result, AckResult::OutOfRange);
    assert_eq!(b.cmd(600, rate(2000)).result, AckResult::Ok);
    assert!(matches!(b.frames[0].msg, Message::Hello(h) if h.sample_rate_hz == 2000));
    b.frames.clear();
    b.run_to(5_000);
    let t: Vec<u32> = b.samples().iter().map(|s| s.t_us).collect();
    assert!(t.windows(2).all(|w| w[1] - w[0] == 500), "{t:?}");
    assert_eq!(b.cmd(5_100, Message::Tare).result, AckResult::Ok);
    assert_eq!(b.events()[0].code, EventCode::TareDone);
}

#[test]
fn malformed_commands_are_refused_with_their_code() {
    let mut b = Bench::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    let cases = [
        (1, msg_type::SET_THROTTLE, &[1u8][..], AckResult::BadLength),
        (1, 0x2A, &[][..], AckResult::UnknownType),
        (1, msg_type::SAMPLE, &[0u8; 32][..], AckResult::UnknownType),
        (3, msg_type::STOP, &[][..], AckResult::Version),
    ];
    for (i, (ver, t, p, want)) in cases.into_iter().enumerate() {
        let seq = 500 + i as u16;
        let n = encode_raw(ver, t, seq, p, &mut buf).unwrap();
        let a = b.raw(1000 + i as u64, &buf[..n], seq);
        assert_eq!((a.cmd_type, a.result), (t, want));
    }
}

#[test]
fn device_clock_wraps_at_32_bits() {
    let cfg = StandConfig {
        initial_t_us: u32::MAX - 2_500,
        ..StandConfig::default()
    };
    let mut b = Bench::with(cfg);
    b.frames.clear();
    b.run_to(6_000);
    let t: Vec<u32> = b.samples().iter().map(|s| s.t_us).collect();
    assert_eq!(t[0], u32::MAX - 1_500);
    assert_eq!(t[3], 1_499);
    assert!(t.windows(2).all(|w| w[1].wrapping_sub(w[0]) == 1000));
}

#[test]
fn csv_dialect_answers_and_streams_rows() {
    let cfg = StandConfig {
        protocol: WireProtocol::Csv,
        ..StandConfig::default()
    };
    let faults = FaultInjector::new(&FaultConfig::default(), 1);
    let mut fw = Firmware::new(&cfg, EchoStand::new(10.0), 1, faults);
    fw.feed(100, b"PING\nARM 500\nTHR 3000\n");
    fw.advance(3_000);
    fw.feed(3_100, b"FLY\n");
    let mut out = Vec::new();
    fw.drain_output(u64::MAX, &mut out);
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("#ACK PING OK 100\n"), "{text}");
    assert!(text.contains("#ACK ARM OK 100\n"));
    assert!(text.contains("#ACK THR OK 1000\n"));
    assert!(text.contains("#ACK ? ERR 3\n"));
    assert!(text.contains("\n2000,3000,3.0000,"), "{text}");
}
