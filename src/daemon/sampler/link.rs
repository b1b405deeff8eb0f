//! The link's recoveries: reopening after a disconnection (with backoff), the host-side stall
//! watchdog, and STOP sent until acknowledged.
//!
//! **Disconnection** (EIO, hang-up, EOF, a port that vanished): a `disconnected` warning, then
//! the path is opened again with exponential backoff (`reconnect_initial_ms` doubling up to
//! `reconnect_max_ms`) until it works; every attempt opens the configured path anew, so a
//! symlink (the udev rule's `/dev/propid-stand`, `/dev/serial/by-id/...`) re-pointed to a new
//! device node is followed. Each success is a `reconnected` event naming the device node the
//! path now resolves to (`device_node`) and counts in `reconnects`.
//!
//! **Stall** (`[device] stall_timeout_ms`): a live link that has spoken but then sends nothing
//! — no sample, no ACK, no HELLO — for the timeout. The plan is told (it queues a STOP and stops
//! commanding; [`super::Plan::on_stall`]), STOP is re-sent every 50 ms until acknowledged or
//! `stop_timeout_ms`, a `link_stalled` warning says how long it was silent and whether the STOP
//! was acknowledged, and the port is closed, left closed for `reconnect_initial_ms` (a board
//! that resets when its port opens, as the DTR line resets an Arduino, gets to see it) and
//! reopened; counted in `stalls` and `reconnects`. A link still silent after its reopen is
//! reopened again after each further timeout, left closed for a delay that backs off as for a
//! vanished port (`reconnect_initial_ms` doubling to `reconnect_max_ms`), without another
//! warning, until it speaks; its first byte then is a `link_resumed` event (how long it was
//! silent). The same holds for a passive CSV bench (no plan, nothing to stop but a STOP line
//! it may ignore) that stops streaming: warned once, counted once, said when rows return.

use std::time::{Duration, Instant};

use super::{Sampler, RESEND, STOP_SEQ};
use crate::daemon::item::{Item, Notice};
use crate::daemon::shutdown::Shutdown;
use crate::daemon::source::{Backoff, SourceError};
use crate::daemon::DaemonError;
use propid_wire::protocol::message::Message;
use propid_wire::protocol::MAX_FRAME_LEN;

impl Sampler {
    /// The host-side watchdog (see the module documentation). Before the link's first byte the
    /// silence is [`Self::check_silence`]'s (`no_data`).
    pub(super) fn check_stall(&mut self) -> Result<(), DaemonError> {
        let Some(limit) = self.cfg.stall_timeout else {
            return Ok(());
        };
        if self.wire.format().is_none() {
            return Ok(());
        }
        let silent = self.last_rx.max(self.connected_at).elapsed();
        if silent < limit {
            return Ok(());
        }
        if !self.heard_since_connect {
            // still silent since the last reopen: again, after the next backoff delay
            let delay = self.silent_backoff().next_delay();
            return self.reopen(delay, false);
        }
        self.handler.stats.stalls += 1;
        let now = self.now_us();
        if let Some(p) = self.handler.plan.as_mut() {
            p.on_stall(now);
        }
        let stop_acknowledged = self.send_stop();
        let silent_ms = self.last_rx.elapsed().as_millis() as u64;
        self.handler.send(Item::Notice(Notice::LinkStalled {
            silent_ms,
            stop_acknowledged,
        }));
        self.stalled = true;
        self.stall_backoff = None;
        let delay = self.silent_backoff().next_delay();
        self.reopen(delay, true)
    }

    /// The backoff of the reopens of a link silent since a stall (`reconnect_initial_ms`
    /// doubling to `reconnect_max_ms`); cleared by the link's next byte.
    fn silent_backoff(&mut self) -> &mut Backoff {
        let (initial, max) = (self.cfg.reconnect_initial, self.cfg.reconnect_max);
        self.stall_backoff
            .get_or_insert_with(|| Backoff::new(initial, max))
    }

    /// A byte arrived: after a stall, a `link_resumed` event (how long nothing was heard, from
    /// the last byte before, [`Sampler::last_rx`] not yet updated); the reopen backoff is over.
    pub(super) fn heard(&mut self) {
        self.stall_backoff = None;
        if std::mem::take(&mut self.stalled) {
            let silent_ms = self.last_rx.elapsed().as_millis() as u64;
            self.handler
                .send(Item::Notice(Notice::LinkResumed { silent_ms }));
        }
    }

    /// Closes the port and opens it again after `delay`; when it cannot be opened, the
    /// reconnect loop takes over. `announce`: a `reconnected` event on success.
    fn reopen(&mut self, delay: Duration, announce: bool) -> Result<(), DaemonError> {
        self.source.close();
        // never past the end of the run (`max_run_s`): the main loop then stops
        let left = self
            .cfg
            .max_run
            .map_or(delay, |m| m.saturating_sub(self.start.elapsed()));
        sleep_unless(&self.shutdown, delay.min(left));
        if self.shutdown.requested() || self.time_up() {
            return Ok(());
        }
        match self.source.reconnect() {
            Ok(()) => {
                self.reconnected(announce);
                Ok(())
            }
            Err(SourceError::Finished { .. }) => Ok(()),
            Err(_) => self.reconnect(),
        }
    }

    /// Reopens the source with backoff until it works or a stop is requested.
    pub(super) fn reconnect(&mut self) -> Result<(), DaemonError> {
        self.handler.send(Item::Notice(Notice::Disconnected));
        let mut backoff = Backoff::new(self.cfg.reconnect_initial, self.cfg.reconnect_max);
        loop {
            self.forward_record_notes();
            if self.shutdown.requested() || self.time_up() {
                return Ok(()); // the main loop sees the request; STOP cannot reach anyone
            }
            sleep_unless(&self.shutdown, backoff.next_delay());
            match self.source.reconnect() {
                Ok(()) => break,
                Err(SourceError::Finished { .. }) => return Ok(()),
                Err(_) => continue,
            }
        }
        self.reconnected(true);
        Ok(())
    }

    /// The link is open again: counted, announced (`announce`), the plan told.
    fn reconnected(&mut self, announce: bool) {
        self.handler.stats.reconnects += 1;
        if announce {
            let device_node = self.source.device_node();
            self.handler
                .send(Item::Notice(Notice::Reconnected { device_node }));
        }
        self.connected_at = Instant::now();
        self.heard_since_connect = false;
        self.start_plan(false);
    }

    /// Sends STOP until acknowledged or the stop timeout passes: through the plan when there is
    /// one (so it stops its heartbeats and pulses), re-sent every 50 ms with the same seq.
    pub(super) fn stop_device(&mut self) -> Result<(), DaemonError> {
        let now = self.now_us();
        if let Some(p) = self.handler.plan.as_mut() {
            p.abort(now);
        }
        let notice = if self.send_stop() {
            Notice::Stopped
        } else {
            Notice::StopUnacknowledged
        };
        self.handler.send(Item::Notice(notice));
        Ok(())
    }

    /// Sends the plan's queued STOP (or, without one, a STOP of our own) every 50 ms with the
    /// same seq until the device acknowledges it or the stop timeout passes, reading the link
    /// meanwhile; true when acknowledged.
    fn send_stop(&mut self) -> bool {
        self.handler.awaiting_stop = None;
        self.handler.stop_acked = false;
        let _ = self.send_plan_output();
        let seq = match self.handler.awaiting_stop {
            Some(seq) => seq,
            None => {
                // No plan, or the plan was over: a STOP of our own.
                self.handler.awaiting_stop = Some(STOP_SEQ);
                STOP_SEQ
            }
        };
        let n = self
            .wire
            .encode(seq, &Message::Stop, &mut self.cmd[..])
            .unwrap_or(0);
        let frame: [u8; MAX_FRAME_LEN] = self.cmd;
        let deadline = Instant::now() + self.cfg.stop_timeout;
        let mut next_send = Instant::now();
        while !self.handler.stop_acked && Instant::now() < deadline {
            if Instant::now() >= next_send {
                if self.source.write_all(&frame[..n]).is_err() {
                    break;
                }
                next_send += RESEND;
            }
            if self.read_once().is_err() {
                break;
            }
        }
        let _ = self.send_plan_output();
        self.handler.stop_acked
    }
}

/// Sleeps `d`, waking early when a stop is requested.
fn sleep_unless(shutdown: &Shutdown, d: Duration) {
    let end = Instant::now() + d;
    while !shutdown.requested() {
        let now = Instant::now();
        if now >= end {
            return;
        }
        std::thread::sleep((end - now).min(Duration::from_millis(10)));
    }
}
