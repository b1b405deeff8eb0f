//! What the plan does when the link comes back: after a reconnect it asks the device whether it
//! is the same boot; after a device reset or a stall it re-arms only when the configuration
//! says so (`rearm_on_reset`).
//!
//! - [`Experiment::reconnected`]: the link was reopened mid-plan. A HELLO_REQ goes out in place
//!   of the command in flight (which waits, as do the plan's timers; heartbeats go on). Its ACK
//!   comes after the device's HELLO: the same boot id → the waiting command is re-sent with its
//!   seq (a device that executed it answers DUPLICATE) and the plan goes on; a new boot id →
//!   [`Notice::DeviceReset`].
//! - A device reset ([`Notice::DeviceReset`]): the device boots disarmed. Without
//!   `rearm_on_reset` the plan is over; with it the plan hand-shakes again, sends STOP (a device
//!   back in the same boot after a stall may still be armed and would refuse ARM), ARMs and
//!   resumes at the operating point it was working on (its pulses from the first; the points
//!   done stay done).
//! - [`Experiment::link_stalled`]: the host heard nothing (no data, no ACK) for its stall timeout.
//!   One STOP goes out untracked (a device that does not answer cannot acknowledge it: the
//!   caller re-sends it for a bounded time) and the plan is over; with `rearm_on_reset` the next
//!   [`Experiment::reconnected`] re-arms as after a reset.
//! - Re-arms are bounded (`max_rearms`): a device that resets or stalls once more after that
//!   many re-arms ends the plan with [`Notice::RearmLimit`] (after the `DeviceReset` notice,
//!   which then says `rearm: false`).

use super::plan::{Experiment, InFlight, Notice, Output, Phase};
use crate::protocol::Message;

impl Experiment {
    /// The link was reopened at `now_us` (not the first connection: that is [`Self::start`]).
    pub fn reconnected(&mut self, now_us: u64) {
        if self.rearm_pending {
            return self.rearm(now_us);
        }
        if !self.phase.mid_plan() || self.verifying.is_some() {
            return; // a handshake or a STOP in flight is re-sent by its retries
        }
        let displaced = self.in_flight.take();
        self.verifying = Some(displaced);
        self.send(Message::HelloReq, now_us);
    }

    /// The host heard nothing from the device for its stall timeout: STOP (once, untracked) and
    /// the plan is over, or waits to re-arm at the next [`Self::reconnected`]
    /// (`rearm_on_reset`). Nothing happens before the plan starts, once it is over, or while a
    /// shutdown STOP is in flight.
    pub fn link_stalled(&mut self, _now_us: u64) {
        let armed = self.phase.mid_plan();
        let resumable = matches!(
            self.phase,
            Phase::Handshake
                | Phase::Arming
                | Phase::Ramping
                | Phase::Settling
                | Phase::Pulsing
                | Phase::Program
        );
        if !armed && !resumable {
            return;
        }
        if matches!(
            self.phase,
            Phase::Ramping | Phase::Settling | Phase::Pulsing | Phase::Program
        ) {
            self.resume_level = self.level_idx;
        }
        self.phase = Phase::Halted;
        self.in_flight = None;
        self.verifying = None;
        self.next_heartbeat_us = None;
        self.wait_until_us = None;
        if armed {
            let seq = self.next_seq();
            self.out.push_back(Output::Send {
                seq,
                msg: Message::Stop,
            });
        }
        let wanted = self.cfg.rearm_on_reset && resumable;
        self.rearm_pending = wanted && self.may_rearm();
        if wanted && !self.rearm_pending {
            self.notice(Notice::RearmLimit {
                rearms: self.rearms,
            });
        }
    }

    /// Whether another re-arm is within `max_rearms`.
    fn may_rearm(&self) -> bool {
        self.rearms < self.cfg.max_rearms
    }

    /// True while the plan is over after a stall but re-arms at the next reconnect.
    pub fn rearm_pending(&self) -> bool {
        self.rearm_pending
    }

    /// Times the plan re-armed (after resets and stalls).
    pub fn rearms(&self) -> u32 {
        self.rearms
    }

    /// The ACK of the reconnect's HELLO_REQ: the device is the same boot (a new one's HELLO
    /// comes first). The displaced command goes out again with its seq.
    pub(super) fn verified(&mut self, displaced: Option<InFlight>, now_us: u64) {
        if let Some(mut f) = displaced {
            f.sent_us = now_us;
            f.first_sent_us = now_us;
            f.resends = 0;
            self.in_flight = Some(f);
            self.out.push_back(Output::Send {
                seq: f.seq,
                msg: f.msg,
            });
        }
    }

    /// A HELLO with a new boot id: re-arm (when allowed and the plan was not ending) or halt.
    pub(super) fn device_reset(&mut self, old: u32, new: u32, now_us: u64) {
        let working = self.rearm_pending
            || matches!(
                self.phase,
                Phase::Handshake
                    | Phase::Arming
                    | Phase::Ramping
                    | Phase::Settling
                    | Phase::Pulsing
                    | Phase::Program
            );
        let wanted = self.cfg.rearm_on_reset && working;
        let rearm = wanted && self.may_rearm();
        let n = Notice::DeviceReset {
            old_boot_id: old,
            new_boot_id: new,
            rearm,
        };
        if !rearm {
            if wanted {
                self.notice(n);
                return self.halt(Notice::RearmLimit {
                    rearms: self.rearms,
                });
            }
            return self.halt(n);
        }
        self.notice(n);
        if matches!(
            self.phase,
            Phase::Ramping | Phase::Settling | Phase::Pulsing | Phase::Program
        ) {
            self.resume_level = self.level_idx;
        }
        self.rearm(now_us);
    }

    /// A new handshake, then ARM and the operating point [`Self::resume_level`].
    fn rearm(&mut self, now_us: u64) {
        self.rearm_pending = false;
        self.verifying = None;
        self.phase = Phase::Handshake;
        self.boot_id = None;
        self.rate_hz = None;
        self.handshake_acked = false;
        self.in_flight = None;
        self.next_heartbeat_us = None;
        self.wait_until_us = None;
        self.pulses = 0;
        self.rearms += 1;
        self.send(Message::HelloReq, now_us);
    }
}

#[cfg(test)]
mod tests {
    use super::super::ExperimentConfig;
    use super::*;
    use crate::protocol::message::msg_type;
    use crate::protocol::{Ack, AckResult, Frame, Hello};

    fn cfg(rearm: bool) -> ExperimentConfig {
        ExperimentConfig {
            levels: vec![0.3, 0.5],
            ramp_ms: 50,
            settle_ms: 50,
            pulse_spacing_ms: 40,
            pulses_per_level: 3,
            rearm_on_reset: rearm,
            ..ExperimentConfig::default()
        }
    }

    fn frame(msg: Message) -> Frame {
        Frame { seq: 0, msg }
    }

    fn hello(boot_id: u32) -> Frame {
        frame(Message::Hello(Hello {
            proto_minor: 0,
            esc_protocol: crate::protocol::EscProtocol::None,
            fw_version: 1,
            boot_id,
            t_us: 0,
            sample_rate_hz: 1000,
            channels: 1,
            motor_poles: 0,
            caps: 0,
            name: Hello::name_field("t"),
        }))
    }

    fn ack(seq: u16, cmd_type: u8) -> Frame {
        frame(Message::Ack(Ack {
            cmd_seq: seq,
            cmd_type,
            result: AckResult::Ok,
            ack_flags: 0,
            t_us: 0,
        }))
    }

    fn drain(p: &mut Experiment) -> (Vec<(u16, Message)>, Vec<Notice>) {
        let (mut s, mut n) = (Vec::new(), Vec::new());
        while let Some(o) = p.next_output() {
            match o {
                Output::Send { seq, msg } => s.push((seq, msg)),
                Output::Notice(x) => n.push(x),
            }
        }
        (s, n)
    }

    /// Hand-shake (boot `boot`), ARM, reach the first level and fire one pulse: returns the
    /// plan with the pulse's IMPULSE in flight and the time.
    fn pulsing(rearm: bool, boot: u32) -> (Experiment, u16, u64) {
        let mut p = Experiment::new(cfg(rearm), 0).unwrap();
        p.start(0);
        drain(&mut p);
        p.on_frame(&hello(boot), 10);
        p.on_frame(&ack(0, msg_type::HELLO_REQ), 20);
        drain(&mut p);
        p.on_frame(&ack(1, msg_type::ARM), 30);
        let (s, _) = drain(&mut p);
        let set = s
            .iter()
            .find(|(_, m)| matches!(m, Message::SetThrottle(_)))
            .unwrap();
        p.on_frame(&ack(set.0, msg_type::SET_THROTTLE), 40);
        p.poll(200_000);
        let (s, n) = drain(&mut p);
        assert!(
            matches!(n[0], Notice::LevelReached { index: 0, .. }),
            "{n:?}"
        );
        let imp = s
            .iter()
            .find(|(_, m)| matches!(m, Message::Impulse(_)))
            .unwrap();
        (p, imp.0, 200_000)
    }

    #[test]
    fn a_reconnect_to_the_same_boot_resends_the_displaced_command_and_goes_on() {
        let (mut p, imp, t) = pulsing(false, 11);
        p.reconnected(t + 1000);
        let (s, _) = drain(&mut p);
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].1, Message::HelloReq);
        let req = s[0].0;
        // waits paused while the device is asked (only heartbeats and the HELLO_REQ's re-send)
        p.poll(t + 500_000);
        assert!(drain(&mut p)
            .0
            .iter()
            .all(|(seq, m)| *m == Message::Heartbeat || *seq == req));
        p.on_frame(&hello(11), t + 600_000);
        p.on_frame(&ack(req, msg_type::HELLO_REQ), t + 600_100);
        let (s, n) = drain(&mut p);
        assert!(n.is_empty(), "{n:?}");
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].0, imp, "the IMPULSE again with its seq");
        assert!(matches!(s[0].1, Message::Impulse(_)));
        assert_eq!(p.phase(), Phase::Pulsing);
    }

    #[test]
    fn a_reset_without_rearm_ends_the_plan() {
        let (mut p, _, t) = pulsing(false, 11);
        p.reconnected(t);
        drain(&mut p);
        p.on_frame(&hello(12), t + 100);
        let (s, n) = drain(&mut p);
        assert!(s.is_empty());
        assert_eq!(
            n,
            vec![Notice::DeviceReset {
                old_boot_id: 11,
                new_boot_id: 12,
                rearm: false
            }]
        );
        assert_eq!(p.phase(), Phase::Halted);
        assert!(!p.rearm_pending());
    }

    #[test]
    fn a_reset_with_rearm_hand_shakes_arms_and_resumes_at_the_interrupted_level() {
        let (mut p, _, t) = pulsing(true, 11);
        // the second level was being worked on
        p.level_idx = 1;
        p.on_frame(&hello(12), t);
        let (s, n) = drain(&mut p);
        assert_eq!(
            n,
            vec![Notice::DeviceReset {
                old_boot_id: 11,
                new_boot_id: 12,
                rearm: true
            }]
        );
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].1, Message::HelloReq);
        p.on_frame(&hello(12), t + 10);
        p.on_frame(&ack(s[0].0, msg_type::HELLO_REQ), t + 20);
        let (s, n) = drain(&mut p);
        assert_eq!(
            n,
            vec![Notice::Connected {
                boot_id: 12,
                sample_rate_hz: 1000
            }]
        );
        assert_eq!(s[0].1, Message::Stop, "the motor stopped before the re-arm");
        p.on_frame(&ack(s[0].0, msg_type::STOP), t + 25);
        let (s, n) = drain(&mut p);
        assert!(n.is_empty());
        assert!(matches!(s[0].1, Message::Arm(_)));
        p.on_frame(&ack(s[0].0, msg_type::ARM), t + 30);
        let (s, n) = drain(&mut p);
        assert_eq!(n, vec![Notice::Armed]);
        let level = match s[0].1 {
            Message::SetThrottle(st) => st.level,
            ref m => panic!("{m:?}"),
        };
        assert_eq!(level, crate::protocol::message::throttle_level(0.5));
        assert_eq!(p.rearms(), 1);
    }

    #[test]
    fn rearms_stop_at_max_rearms_after_resets_and_after_stalls() {
        // max_rearms = 1: the first reset re-arms, the second ends the plan and says why
        let (mut p, _, t) = pulsing(true, 11);
        p.cfg.max_rearms = 1;
        p.on_frame(&hello(12), t);
        let (s, _) = drain(&mut p);
        assert_eq!(p.rearms(), 1);
        p.on_frame(&hello(12), t + 10);
        p.on_frame(&ack(s[0].0, msg_type::HELLO_REQ), t + 20);
        drain(&mut p);
        assert_eq!(p.phase(), Phase::Arming);
        p.on_frame(&hello(13), t + 30);
        let (s, n) = drain(&mut p);
        assert!(s.is_empty(), "{s:?}");
        assert_eq!(
            n,
            vec![
                Notice::DeviceReset {
                    old_boot_id: 12,
                    new_boot_id: 13,
                    rearm: false
                },
                Notice::RearmLimit { rearms: 1 }
            ]
        );
        assert!(p.is_over());
        // max_rearms = 0: a stall is not re-armed at all
        let (mut p, _, t) = pulsing(true, 11);
        p.cfg.max_rearms = 0;
        p.link_stalled(t);
        let (s, n) = drain(&mut p);
        assert_eq!(s.len(), 1, "the STOP");
        assert_eq!(n, vec![Notice::RearmLimit { rearms: 0 }]);
        assert!(!p.rearm_pending());
        p.reconnected(t + 1_000_000);
        assert!(drain(&mut p).0.is_empty());
        assert_eq!(p.phase(), Phase::Halted);
    }

    #[test]
    fn an_unanswered_command_is_a_stall_only_when_nothing_at_all_is_heard_and_a_watchdog_runs() {
        for (watchdog, samples_flow, failed) in [
            (false, false, true),
            (true, true, true),
            (true, false, false),
        ] {
            let (mut p, imp, t) = pulsing(false, 11);
            p.set_stall_watchdog(watchdog);
            for k in 1..=20u64 {
                if samples_flow {
                    p.on_frame(&hello(11), t + k * 10_000);
                }
                p.poll(t + k * 10_000 + 1);
            }
            let (s, n) = drain(&mut p);
            // three re-sends of the IMPULSE with its seq either way
            assert_eq!(s.iter().filter(|(q, _)| *q == imp).count(), 3);
            let link_failed = n.iter().any(|x| matches!(x, Notice::LinkFailed { .. }));
            assert_eq!(link_failed, failed, "{watchdog} {samples_flow}");
            assert_eq!(p.is_over(), failed);
        }
    }

    #[test]
    fn a_frame_already_on_its_way_when_the_command_went_out_does_not_make_a_stall_a_failure() {
        // The device freezes just as the IMPULSE goes out; one frame it sent before that is
        // read 5 ms after the send (a loaded host), then nothing: still a stall. Frames that
        // go on arriving through the re-sends are a deaf device: a link failure.
        for (frames_until_us, failed) in [(5_000u64, false), (200_000, true)] {
            let (mut p, imp, t) = pulsing(false, 11);
            p.set_stall_watchdog(true);
            let mut heard = 0;
            for k in 1..=400u64 {
                let now = t + k * 1_000;
                if k * 1_000 <= frames_until_us && k % 5 == 0 {
                    p.on_frame(&hello(11), now);
                    heard += 1;
                }
                p.poll(now + 1);
            }
            assert!(heard > 0);
            let (s, n) = drain(&mut p);
            assert_eq!(s.iter().filter(|(q, _)| *q == imp).count(), 3);
            let link_failed = n.iter().any(|x| matches!(x, Notice::LinkFailed { .. }));
            assert_eq!(link_failed, failed, "frames until {frames_until_us} µs");
        }
    }

    #[test]
    fn a_stall_sends_one_untracked_stop_and_rearms_at_the_next_reconnect_only_if_allowed() {
        for rearm in [false, true] {
            let (mut p, _, t) = pulsing(rearm, 11);
            p.link_stalled(t);
            let (s, n) = drain(&mut p);
            assert!(n.is_empty());
            assert_eq!(s.len(), 1);
            assert_eq!(s[0].1, Message::Stop);
            assert!(p.is_over());
            assert_eq!(p.rearm_pending(), rearm);
            // never re-sent: no retry, no link failure
            for k in 1..100 {
                p.poll(t + k * 10_000);
            }
            assert!(drain(&mut p).0.is_empty());
            p.reconnected(t + 2_000_000);
            let (s, _) = drain(&mut p);
            if rearm {
                assert_eq!(s.len(), 1);
                assert_eq!(s[0].1, Message::HelloReq);
                assert_eq!(p.phase(), Phase::Handshake);
            } else {
                assert!(s.is_empty());
                assert_eq!(p.phase(), Phase::Halted);
            }
        }
    }
}
