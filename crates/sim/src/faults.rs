//! Fault injection on the device's output: bit flips, garbage bursts, dropped samples, stalls.
//! (Hang-ups close the pty and are done by the [`pty`](super::pty) runner; it counts them here.)
//!
//! Faults are applied to whole encoded frames, so that each one has an exact, countable effect
//! on the host's decoder:
//! - a **bit flip** changes one bit of one byte of a frame, never the 0x00 delimiter and never
//!   into a 0x00, so the frame stays one frame and fails its CRC (or COBS): one dropped frame;
//! - a **garbage burst** is `n` random non-zero bytes and one 0x00, inserted between frames:
//!   one dropped frame (of whatever kind the decoder finds);
//! - a **dropped sample** is a SAMPLE not sent: its `sample_index` is missing at the host;
//! - a **drop burst** is `drop_burst_samples` consecutive SAMPLEs not sent (a link losing a
//!   run of bytes), starting at a SAMPLE with probability `drop_burst_prob`; each counts as a
//!   dropped sample;
//! - a **stall** holds all output for `stall_ms`, then sends it at once (nothing lost).
//!
//! Drops, flips and bursts also come at exact places, by `sample_index`
//! (`drop_samples_at`, `corrupt_samples_at`, `garbage_before_samples_at`), for tests that
//! assert exact counts and positions; they add to the random ones.
//!
//! The host therefore sees `samples_lost = dropped_samples + corrupted_samples` and
//! `frames_dropped = corrupted_frames + garbage_bursts` (summed over the kinds). Events are drawn
//! from a seeded generator: the same seed gives the same faults. Bursts and stalls arrive as a
//! Poisson process (exponential gaps with the configured rate).

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Exp};

use super::config::FaultConfig;

/// What a frame carries, for the faults that depend on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameKind {
    /// A SAMPLE (may be dropped).
    Sample,
    /// Anything else (HELLO, ACK, EVENT, LOG, CSV comment lines).
    Other,
}

/// Every injected fault, counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct FaultStats {
    /// Frames with one flipped bit (each costs the host one frame).
    pub corrupted_frames: u64,
    /// Of those, SAMPLE frames (each also costs the host one sample).
    pub corrupted_samples: u64,
    /// Garbage bursts inserted (each costs the host one dropped frame; the chance that random
    /// bytes pass COBS, the CRC, `ver` and `type` together is below 1e-7 per burst).
    pub garbage_bursts: u64,
    /// Garbage bytes inserted, delimiters included.
    pub garbage_bytes: u64,
    /// SAMPLE frames not sent.
    pub dropped_samples: u64,
    /// Stalls.
    pub stalls: u64,
    /// Hang-ups (pty master closed).
    pub hangups: u64,
    /// Re-opens after a hang-up (each a new boot).
    pub reopens: u64,
    /// Freezes (firmware hung with the port open, until the host closes it: a new boot).
    pub freezes: u64,
    /// Resets with the port kept open (`reset_every_s`: a new boot on the same pty).
    pub resets: u64,
    /// SAMPLEs taken while the link was down (no host had the port open, or the link was cut
    /// for a hang-up): never sent, and not faults (no host could see them).
    pub samples_unsent: u64,
    /// SAMPLEs lost where the link was cut (a hang-up, a reset, the host closing the port):
    /// those not yet on the wire, and those dropped or corrupted after the last SAMPLE that
    /// reached the wire (no later sample of that boot shows the host the jump). They are not in
    /// `dropped_samples`/`corrupted_samples`; faults on frames never put on the wire are not
    /// counted at all.
    pub samples_cut: u64,
}

impl FaultStats {
    /// Samples the host cannot receive because of injected faults.
    pub fn samples_lost(&self) -> u64 {
        self.dropped_samples + self.corrupted_samples
    }

    /// Frames the host's decoder must drop because of injected faults.
    pub fn frames_dropped(&self) -> u64 {
        self.corrupted_frames + self.garbage_bursts
    }
}

/// Applies the configured faults to the device's output stream.
#[derive(Debug)]
pub struct FaultInjector {
    cfg: FaultConfig,
    rng: StdRng,
    stats: FaultStats,
    next_garbage_us: Option<u64>,
    next_stall_us: Option<u64>,
    stall_until_us: u64,
    pending: Vec<u8>,
    delimiter: u8,
    enabled: bool,
    /// The next SAMPLE frame gets a flipped bit (`corrupt_samples_at`).
    corrupt_next_sample: bool,
    /// SAMPLEs still to drop in the current drop burst.
    burst_left: u32,
    /// False while the link is down ([`Self::set_link_up`]): nothing is queued.
    link_up: bool,
    /// Clean SAMPLE frames in `pending`.
    pending_samples: u64,
    /// Faults counted on the frames in `pending` (corrupted frames, garbage bursts).
    pending_faults: FaultStats,
    /// SAMPLEs dropped and corrupted since the last clean SAMPLE that went on the wire: counted
    /// as faults only once a clean SAMPLE after them goes on the wire too (the host sees the
    /// jump), and only when one went before them since the link came up or the device booted.
    unseen: (u64, u64),
    /// `unseen` when the first and the latest clean SAMPLE in `pending` were queued.
    pending_clean: Option<((u64, u64), (u64, u64))>,
    /// A clean SAMPLE went on the wire since the link came up or the device booted.
    anchored: bool,
}

impl FaultInjector {
    /// An injector with the faults of `cfg`, drawing from `seed`.
    pub fn new(cfg: &FaultConfig, seed: u64) -> Self {
        let mut cfg = cfg.clone();
        for list in [
            &mut cfg.drop_samples_at,
            &mut cfg.corrupt_samples_at,
            &mut cfg.garbage_before_samples_at,
        ] {
            list.sort_unstable();
            list.dedup();
        }
        let mut inj = FaultInjector {
            cfg,
            rng: StdRng::seed_from_u64(seed ^ 0x0fa1_75ee_d000_0000),
            stats: FaultStats::default(),
            next_garbage_us: None,
            next_stall_us: None,
            stall_until_us: 0,
            pending: Vec::new(),
            delimiter: 0,
            enabled: true,
            corrupt_next_sample: false,
            burst_left: 0,
            link_up: true,
            pending_samples: 0,
            pending_faults: FaultStats::default(),
            unseen: (0, 0),
            pending_clean: None,
            // a recording is read from its first byte; a pty's link starts down
            anchored: true,
        };
        inj.next_garbage_us = inj.gap_us(inj.cfg.garbage_bursts_per_s, 0);
        inj.next_stall_us = inj.gap_us(inj.cfg.stalls_per_s, 0);
        inj
    }

    /// Uses `delimiter` as the frame end (0x00 for TSP/1, `\n` for CSV lines): flips never
    /// create it and garbage bursts end with it.
    pub fn with_delimiter(mut self, delimiter: u8) -> Self {
        self.delimiter = delimiter;
        self
    }

    /// Switches injection on or off (on by default). While off, frames pass unchanged and no
    /// fault is drawn or counted; scheduled bursts and stalls that fall due are skipped. The pty
    /// runner switches it off while no host has the slave open, so that the counts cover only
    /// output a host could have received.
    pub fn set_enabled(&mut self, on: bool) {
        self.enabled = on;
    }

    /// The faults configured (the firmware reads its own misbehaviours here).
    pub fn config(&self) -> &FaultConfig {
        &self.cfg
    }

    /// The counts so far.
    pub fn stats(&self) -> FaultStats {
        self.stats
    }

    /// Counts a hang-up done by the runner.
    pub fn note_hangup(&mut self) {
        self.stats.hangups += 1;
    }

    /// Counts a re-open done by the runner.
    pub fn note_reopen(&mut self) {
        self.stats.reopens += 1;
    }

    /// Counts a freeze done by the runner.
    pub fn note_freeze(&mut self) {
        self.stats.freezes += 1;
    }

    /// A new boot restarts the device clock at 0: the next garbage burst and stall are drawn
    /// again on the new clock (the processes are memoryless, so their rates hold).
    pub fn new_boot(&mut self) {
        self.stall_until_us = 0;
        self.next_garbage_us = self.gap_us(self.cfg.garbage_bursts_per_s, 0);
        self.next_stall_us = self.gap_us(self.cfg.stalls_per_s, 0);
    }

    /// Counts a reset with the port open done by the runner.
    pub fn note_reset(&mut self) {
        self.stats.resets += 1;
    }

    /// Forgets output not yet sent (the link went away with it): [`Self::cut`].
    pub fn discard_pending(&mut self) {
        self.cut();
    }

    /// Switches the link up or down (up by default). Going down cuts it ([`Self::cut`]); while
    /// it is down every SAMPLE is counted in `samples_unsent` and not sent, other frames are
    /// discarded. The pty runner takes it down while no host has the port open and from the
    /// moment a hang-up cuts the link.
    pub fn set_link_up(&mut self, up: bool) {
        if self.link_up && !up {
            self.cut();
        }
        self.link_up = up;
    }

    /// The link is cut here (a hang-up, a reset, the host gone): what is not on the wire yet is
    /// lost, and so are the samples dropped or corrupted since the last SAMPLE that went on the
    /// wire (the host never sees a later sample of this boot, so never a jump): all counted in
    /// `samples_cut` instead of as faults, as are those before the first SAMPLE on the wire of
    /// a connection or a boot. Faults on frames never sent are uncounted; the frames already on
    /// the wire keep theirs. The rule that keeps the host's counts exact:
    /// `samples_lost = dropped_samples + corrupted_samples` and
    /// `frames_dropped = corrupted_frames + garbage_bursts`, whatever the link did.
    pub fn cut(&mut self) {
        let s = &mut self.stats;
        s.samples_cut += self.unseen.0 + self.unseen.1 + self.pending_samples;
        s.corrupted_frames -= self.pending_faults.corrupted_frames;
        s.garbage_bursts -= self.pending_faults.garbage_bursts;
        s.garbage_bytes -= self.pending_faults.garbage_bytes;
        self.unseen = (0, 0);
        self.anchored = false;
        self.pending.clear();
        self.pending_samples = 0;
        self.pending_faults = FaultStats::default();
        self.pending_clean = None;
        self.burst_left = 0;
        self.corrupt_next_sample = false;
        self.stall_until_us = 0;
    }

    /// Next event of a Poisson process with `rate_per_s`, after `now_us`.
    fn gap_us(&mut self, rate_per_s: f64, now_us: u64) -> Option<u64> {
        let exp = Exp::new(rate_per_s).ok().filter(|_| rate_per_s > 0.0)?;
        let gap_s: f64 = exp.sample(&mut self.rng);
        Some(now_us + (gap_s * 1e6).min(1e15) as u64 + 1)
    }

    /// Runs the time-driven faults (garbage bursts, stalls) up to `now_us`.
    pub fn poll(&mut self, now_us: u64) {
        while let Some(t) = self.next_garbage_us.filter(|&t| t <= now_us) {
            if self.enabled {
                self.burst();
            }
            self.next_garbage_us = self.gap_us(self.cfg.garbage_bursts_per_s, t);
        }
        while let Some(t) = self.next_stall_us.filter(|&t| t <= now_us) {
            let mut end = t;
            if self.enabled {
                self.stats.stalls += 1;
                self.stall_until_us = t + self.cfg.stall_ms as u64 * 1000;
                end = self.stall_until_us;
            }
            self.next_stall_us = self.gap_us(self.cfg.stalls_per_s, end);
        }
    }

    fn burst(&mut self) {
        let n = self.cfg.garbage_burst_bytes as usize;
        for _ in 0..n {
            let mut b: u8 = self.rng.gen_range(1..=255);
            if b == self.delimiter {
                b = b.wrapping_add(1).max(1);
            }
            self.pending.push(b);
        }
        self.pending.push(self.delimiter);
        self.stats.garbage_bursts += 1;
        self.stats.garbage_bytes += n as u64 + 1;
        self.pending_faults.garbage_bursts += 1;
        self.pending_faults.garbage_bytes += n as u64 + 1;
    }

    /// The SAMPLE `index` is about to be sent: inserts a garbage burst before it when
    /// `garbage_before_samples_at` lists it, and decides whether the device drops it (listed in
    /// `drop_samples_at`, or drawn with `drop_sample_prob`; counted): true = not sent. A kept
    /// sample listed in `corrupt_samples_at` gets one flipped bit in [`Self::push_frame`].
    ///
    /// The firmware asks before it gives the sample a link `seq`, so the host sees a
    /// `sample_index` jump without a `seq` jump: a device-side drop (docs/PROTOCOL.md §3).
    pub fn before_sample(&mut self, index: u32) -> bool {
        self.corrupt_next_sample = false;
        if !self.link_up {
            self.stats.samples_unsent += 1;
            return true;
        }
        if !self.enabled {
            return false;
        }
        if self
            .cfg
            .garbage_before_samples_at
            .binary_search(&index)
            .is_ok()
        {
            self.burst();
        }
        let drop = self.cfg.drop_samples_at.binary_search(&index).is_ok()
            || (self.cfg.drop_sample_prob > 0.0 && self.rng.gen_bool(self.cfg.drop_sample_prob))
            || self.in_drop_burst();
        if drop {
            self.unseen.0 += 1;
            return true;
        }
        self.corrupt_next_sample = self.cfg.corrupt_samples_at.binary_search(&index).is_ok();
        false
    }

    /// Whether this SAMPLE falls in a drop burst (one running, or one starting here).
    fn in_drop_burst(&mut self) -> bool {
        if self.burst_left > 0 {
            self.burst_left -= 1;
            return true;
        }
        if self.cfg.drop_burst_prob > 0.0 && self.rng.gen_bool(self.cfg.drop_burst_prob) {
            self.burst_left = self.cfg.drop_burst_samples.saturating_sub(1);
            return true;
        }
        false
    }

    /// Passes one encoded frame (ending in its 0x00 delimiter) through the faults into the
    /// output queue.
    pub fn push_frame(&mut self, frame: &[u8], kind: FrameKind) {
        if !self.link_up {
            return;
        }
        let before = self.stats.corrupted_frames;
        self.push_faulted(frame, kind);
        let corrupted = self.stats.corrupted_frames - before;
        self.pending_faults.corrupted_frames += corrupted;
        if kind == FrameKind::Sample && corrupted == 0 {
            self.pending_samples += 1;
            let first = self.pending_clean.map_or(self.unseen, |(f, _)| f);
            self.pending_clean = Some((first, self.unseen));
        }
    }

    fn push_faulted(&mut self, frame: &[u8], kind: FrameKind) {
        let start = self.pending.len();
        self.pending.extend_from_slice(frame);
        let body = frame.len().saturating_sub(1);
        let listed = kind == FrameKind::Sample && std::mem::take(&mut self.corrupt_next_sample);
        if self.enabled && listed && body > 0 {
            let at = start + self.rng.gen_range(0..body);
            self.flip(at);
            self.stats.corrupted_frames += 1;
            self.unseen.1 += 1;
        } else if self.enabled && self.cfg.bit_flip_per_byte > 0.0 && body > 0 {
            let p_frame = 1.0 - (1.0 - self.cfg.bit_flip_per_byte).powi(body as i32);
            if self.rng.gen_bool(p_frame.clamp(0.0, 1.0)) {
                let at = start + self.rng.gen_range(0..body);
                self.flip(at);
                self.stats.corrupted_frames += 1;
                if kind == FrameKind::Sample {
                    self.unseen.1 += 1;
                }
            }
        }
    }

    /// Flips one bit of `pending[i]` (not a delimiter), choosing a bit that does not turn it
    /// into the delimiter (two different bits cannot both do that).
    fn flip(&mut self, i: usize) {
        let byte = self.pending[i];
        let mut bit = self.rng.gen_range(0..8u32);
        if byte ^ (1 << bit) == self.delimiter {
            bit = (bit + 1) % 8;
        }
        self.pending[i] = byte ^ (1 << bit);
    }

    /// Moves the output that may go on the wire at `now_us` into `out` (nothing during a stall).
    pub fn drain_ready(&mut self, now_us: u64, out: &mut Vec<u8>) {
        self.poll(now_us);
        if now_us >= self.stall_until_us {
            out.append(&mut self.pending);
            if let Some(((d0, c0), (d, c))) = self.pending_clean.take() {
                // the losses before those samples are seen now, but for those before the first
                // sample of a connection or a boot (no earlier one shows the jump)
                let (lead_d, lead_c) = if self.anchored { (0, 0) } else { (d0, c0) };
                self.stats.samples_cut += lead_d + lead_c;
                self.stats.dropped_samples += d - lead_d;
                self.stats.corrupted_samples += c - lead_c;
                self.unseen.0 -= d;
                self.unseen.1 -= c;
                self.anchored = true;
            }
            self.pending_samples = 0;
            self.pending_faults = FaultStats::default();
        }
    }

    /// True while a stall holds the output.
    pub fn stalled(&self, now_us: u64) -> bool {
        now_us < self.stall_until_us
    }
}

#[cfg(test)]
mod tests;
