//! Frame handling: what each decoded frame becomes on the worker's queue (placed samples,
//! gaps, segments, events) and what the plan is shown, with the never-blocking queueing.

use crossbeam_channel::{Sender, TrySendError};
use std::time::Instant;

use super::Plan;
use crate::daemon::item::{EventItem, Item, SampleItem};
use crate::daemon::stats::LinkStats;
use crate::daemon::tracker::Tracker;
use propid_wire::protocol::detect::WireFormat;
use propid_wire::protocol::message::{msg_type, Frame, Message};

/// Frame handling, separate from the decoder so both can be borrowed at once.
pub(super) struct Handler {
    pub(super) tx: Sender<Item>,
    pub(super) lossless: bool,
    pub(super) tracker: Tracker,
    pub(super) stats: LinkStats,
    /// Samples dropped because the queue was full (part of `samples_lost`).
    pub(super) overflow_lost: u64,
    pub(super) plan: Option<Box<dyn Plan>>,
    pub(super) awaiting_stop: Option<u16>,
    pub(super) stop_acked: bool,
    pub(super) now_us: u64,
}

impl Handler {
    fn hello(&mut self, boot_id: u32, rate_hz: u16, wire: WireFormat) -> bool {
        match wire {
            WireFormat::Binary => self.tracker.hello(boot_id, rate_hz),
            WireFormat::Csv => self.tracker.hello_csv(boot_id, rate_hz),
        }
    }

    pub(super) fn send(&mut self, item: Item) {
        if self.lossless {
            let _ = self.tx.send(item);
            return;
        }
        match self.tx.try_send(item) {
            Ok(()) => {}
            Err(TrySendError::Full(item)) => {
                self.stats.overflows += 1;
                if matches!(item, Item::Sample(_)) {
                    self.overflow_lost += 1;
                }
            }
            Err(TrySendError::Disconnected(_)) => {}
        }
    }

    /// One frame, decoded from `wire` (a HELLO's rate of 0 is a lie on TSP/1, "not measured
    /// yet" on CSV: the tracker's rule).
    pub(super) fn on_frame(&mut self, frame: Frame, wire: WireFormat) {
        match &frame.msg {
            // one `segment` item per segment, as the tracker announces it (its "Announcing")
            Message::Hello(h) if self.hello(h.boot_id, h.sample_rate_hz, wire) => {
                self.send(Item::Segment { boot_id: h.boot_id });
            }
            Message::Sample(s) => {
                self.stats.samples += 1;
                let placed = self.tracker.sample(s.sample_index, s.t_us);
                if placed.announce {
                    self.send(Item::Segment { boot_id: 0 });
                }
                // After a new segment: a gap too long to mask (announced, not bridged).
                if placed.lost_before > 0 {
                    self.send(Item::Gap {
                        before: placed.index,
                        count: placed.lost_before,
                    });
                }
                if let Some((step_us, expected_us)) = placed.clock_jump {
                    // the window closes before this sample: no fit spans the jump
                    self.send(Item::ClockJump {
                        index: placed.index,
                        step_us,
                        expected_us,
                    });
                }
                if let Some((hello_hz, measured_hz)) = placed.rate_mismatch {
                    self.send(Item::RateMismatch {
                        hello_hz,
                        measured_hz,
                    });
                    if let Some(plan) = self.plan.as_mut() {
                        plan.on_rate_mismatch(self.now_us, hello_hz, measured_hz);
                    }
                }
                if placed.duplicate {
                    // dropped (counted in `duplicates`), as ingest does
                    if let Some(plan) = self.plan.as_mut() {
                        plan.on_frame(self.now_us, &frame);
                    }
                    return;
                }
                let item = SampleItem {
                    index: placed.index,
                    t_us: placed.t_us,
                    throttle_raw: s.throttle,
                    flags: s.flags.bits(),
                    thrust_n: valid(s.thrust_n, s.flags.bits(), 1 << 1),
                    torque_nm: valid(s.torque_nm, s.flags.bits(), 1 << 2),
                    rpm: valid(s.rpm, s.flags.bits(), 1 << 3),
                    voltage_v: valid(s.voltage_v, s.flags.bits(), 1 << 4),
                    current_a: valid(s.current_a, s.flags.bits(), 1 << 5),
                    received: Instant::now(),
                };
                self.send(Item::Sample(item));
            }
            Message::Event(e) => {
                let item = EventItem {
                    code: e.code.to_u8(),
                    arg: e.arg,
                    t_us: self.tracker.event_time(e.t_us),
                    sample_index: self.tracker.event_index(e.sample_index),
                };
                self.send(Item::Event(item));
            }
            Message::Ack(a)
                if Some(a.cmd_seq) == self.awaiting_stop && a.cmd_type == msg_type::STOP =>
            {
                self.stop_acked = true;
            }
            _ => {}
        }
        if let Some(plan) = self.plan.as_mut() {
            plan.on_frame(self.now_us, &frame);
        }
    }
}

/// A measurement whose VALID flag is clear is "not measured": NaN.
fn valid(v: f32, flags: u16, bit: u16) -> f32 {
    if flags & bit != 0 {
        v
    } else {
        f32::NAN
    }
}
