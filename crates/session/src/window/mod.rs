//! The worker's fixed-size window of samples at one operating point, and when to identify.
//!
//! All buffers are allocated once ([`Window::new`]) with the capacity `window_capacity` (the
//! plan's windows at the fastest rate, or `max_window_samples` when larger);
//! pushing, gaps and restarts never allocate (restarts move the kept tail with `copy_within`).
//!
//! # Rules (data-driven, so a live run and the replay of its recording decide identically)
//! - A sample with RAMP_ACTIVE is between operating points: the current window closes.
//! - A sample without IMPULSE_ACTIVE whose throttle differs from the window's level by more than
//!   `level_tolerance` starts a new operating point: the window closes and restarts there.
//!   The operating point published is the throttle held longest in the window (a CSV bench's
//!   ramp carries no RAMP_ACTIVE flag, and its steps next to a level fall within the tolerance
//!   of it); "off level" is measured from where the window started.
//! - A rising edge of IMPULSE_ACTIVE is a pulse start (the device sets the flag on exactly the
//!   samples during which the pulse throttle was applied). A pulse whose first sample was lost
//!   is still a pulse when the device's EVENT IMPULSE_START named its index
//!   ([`Window::on_pulse_event`]): its start is the missing sample, so the window still closes
//!   after the K pulses the plan fired (the core counts that pulse and leaves it out: its input
//!   is not known), instead of taking the next level's share of pulses.
//! - The window is identified when it holds K complete pulses: at the start of pulse K+1, or when
//!   the level ends, the window fills, a new device segment starts, or the stream ends. A pulse is
//!   complete when the next one starts or the level ends (the plan spaces pulses so the response
//!   has decayed by then).
//! - A device clock jump ([`Window::on_clock_jump`]) closes the window like a segment (what
//!   is complete, all before the jump, is identified; the rest is `window_interrupted` with
//!   `closed_by: "clock_jump"`): the window's `dt` comes from its own clock, and no fit spans
//!   a jump.
//! - After an identification the window restarts at the new pulse, keeping the second half of
//!   the last pulse's response (decayed: the new pulse's pre-pulse baseline). Each model is
//!   therefore from K fresh pulses, and the window stays bounded.
//! - Lost samples (gaps) are pushed as missing (NaN, masked), never bridged; a gap that does not
//!   fit restarts the window. The window also checks that sample indices are contiguous by
//!   itself: a jump the sampler could not announce (its queue was full, so the samples *and*
//!   the gap notice may have been dropped) is treated exactly like an announced gap, and an
//!   index going backwards (a new segment whose notice was dropped) closes the window like a
//!   segment. The identification core averages each lag over the pulses measured there (a pulse
//!   with holes still counts, nothing is interpolated) and the model says how many samples
//!   were missing (`missing_samples`).

mod view;

pub use view::{Outcome, OutputChannel, Reason, WindowView};

use std::time::Instant;

use super::item::{flags, SampleItem};

/// A window closed with fewer than K pulses (a new device segment, announced or seen as the
/// sample index going back; the operating point's end; the stream's end): not identified, and
/// reported, so that every pulse counted is in a model, a refusal or one of these.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interrupted {
    /// The window's operating point.
    pub operating_point: f64,
    /// Pulses it held (1..K).
    pub pulses: usize,
    /// Device time of its last sample, s (the old segment's clock).
    pub t_s: f64,
    /// What closed it.
    pub closed_by: Reason,
}

/// The fixed-capacity window.
#[derive(Debug)]
pub struct Window {
    cap: usize,
    k: usize,
    tol_raw: u16,
    channel: OutputChannel,
    input: Vec<f64>,
    output: Vec<f64>,
    missing: Vec<bool>,
    t_us: Vec<u64>,
    pulse_starts: Vec<usize>,
    first_index: u64,
    /// The level the window started at: the reference for "off level".
    level_raw: Option<u16>,
    /// The throttle held longest (consecutive samples off pulse) in the window, and for how
    /// long: the operating point published.
    held: (u16, usize),
    /// The current run of equal throttle values off pulse.
    run: (u16, usize),
    level_number: u32,
    levels_seen: u32,
    in_pulse: bool,
    last_received: Option<Instant>,
    /// Index the next sample must have (contiguity check); `None` before the first sample.
    next_index: Option<u64>,
    /// A pulse start the device announced (EVENT IMPULSE_START) whose sample has not come yet.
    announced_pulse: Option<u64>,
}

impl Window {
    /// Allocates the buffers once. `k` = pulses per model, `level_tolerance` as a fraction.
    pub fn new(cap: usize, k: usize, level_tolerance: f64, channel: OutputChannel) -> Window {
        let cap = cap.max(4);
        let k = k.max(1);
        Window {
            cap,
            k,
            tol_raw: (level_tolerance * 10_000.0).round().clamp(1.0, 10_000.0) as u16,
            channel,
            input: Vec::with_capacity(cap),
            output: Vec::with_capacity(cap),
            missing: Vec::with_capacity(cap),
            t_us: Vec::with_capacity(cap),
            pulse_starts: Vec::with_capacity(k + 1),
            first_index: 0,
            level_raw: None,
            held: (0, 0),
            run: (0, 0),
            level_number: 0,
            levels_seen: 0,
            in_pulse: false,
            last_received: None,
            next_index: None,
            announced_pulse: None,
        }
    }

    /// Samples held.
    pub fn len(&self) -> usize {
        self.input.len()
    }

    /// Whether the window holds no sample.
    pub fn is_empty(&self) -> bool {
        self.input.is_empty()
    }

    /// The current operating point, if at one: the throttle held longest in the window (off
    /// pulse, within the tolerance of the level the window started at).
    pub fn level(&self) -> Option<f64> {
        self.level_raw.map(|_| f64::from(self.held.0) / 10_000.0)
    }

    /// Feeds one sample; calls `identify` when the rules say so (before the sample is added).
    pub fn on_sample(
        &mut self,
        s: &SampleItem,
        mut identify: impl FnMut(&WindowView<'_>),
    ) -> Outcome {
        let mut out = Outcome::default();
        match self.next_index {
            Some(next) if s.index > next => {
                out.unannounced_lost = s.index - next;
                out.pulse = self.on_gap(s.index - next, &mut identify);
            }
            Some(next) if s.index < next => out.cut = self.close(Reason::Segment, &mut identify),
            _ => {}
        }
        if self.announced_pulse.is_some_and(|p| p <= s.index) {
            // here (its flag marks it) or past
            self.announced_pulse = None;
        }
        self.next_index = Some(s.index + 1);
        if s.has(flags::RAMP_ACTIVE) {
            out.cut = out.cut.or(self.close(Reason::LevelEnd, &mut identify));
            return out;
        }
        let pulse = s.has(flags::IMPULSE_ACTIVE);
        let off_level = match self.level_raw {
            Some(l) => l.abs_diff(s.throttle_raw) > self.tol_raw,
            None => true,
        };
        if !pulse && off_level {
            out.cut = out.cut.or(self.close(Reason::LevelEnd, &mut identify));
            self.start_level(s);
            out.new_level = true;
        } else if self.level_raw.is_none() {
            // A pulse with no level to refer it to: wait for a steady sample.
            self.in_pulse = pulse;
            return out;
        } else if !pulse {
            // the operating point published is the throttle held longest (a ramp without
            // RAMP_ACTIVE flags has steps within the tolerance at both ends of a level); "off
            // level" stays measured from where the window started, so a slow ramp closes it
            self.run = match self.run {
                (v, n) if v == s.throttle_raw => (v, n + 1),
                _ => (s.throttle_raw, 1),
            };
            if self.run.1 > self.held.1 {
                self.held = self.run;
            }
        }
        if pulse && !self.in_pulse {
            out.pulse = true;
            self.pulse_start(&mut identify);
        }
        self.in_pulse = pulse;
        if self.input.len() == self.cap {
            out.overflowed = self.pulse_starts.len() < self.k;
            self.identify_if_complete(Reason::Full, &mut identify);
            self.clear();
            self.first_index = s.index;
        }
        self.push(s);
        out
    }

    /// The device announced a pulse starting at sample `index` (EVENT IMPULSE_START, sent before
    /// that sample): if the sample is lost, the gap that covers it marks the pulse start there.
    pub fn on_pulse_event(&mut self, index: u64) {
        if self.next_index.map_or(true, |next| index >= next) {
            self.announced_pulse = Some(index);
        }
    }

    /// `count` samples were lost before the next one: masked, or a restart if they do not fit.
    /// Returns true when an announced pulse started in the gap (a pulse start, as a rising
    /// edge would be; `identify` is called first when the window already holds K pulses).
    pub fn on_gap(&mut self, count: u64, mut identify: impl FnMut(&WindowView<'_>)) -> bool {
        let from = self.next_index;
        if let Some(next) = self.next_index.as_mut() {
            *next = next.saturating_add(count);
        }
        let lost_pulse = match (from, self.announced_pulse) {
            (Some(a), Some(p)) if p >= a && p - a < count => {
                self.announced_pulse = None;
                Some(p - a)
            }
            _ => None,
        };
        if self.level_raw.is_none() {
            return false;
        }
        if (self.input.len() as u64).saturating_add(count) >= self.cap as u64 {
            self.clear();
            self.level_raw = None;
            return false;
        }
        let t = self.t_us.last().copied().unwrap_or(0);
        for i in 0..count {
            if lost_pulse == Some(i) {
                self.pulse_start(&mut identify);
                // a wider pulse's next samples carry the flag: no second edge
                self.in_pulse = true;
            }
            self.input.push(f64::NAN);
            self.output.push(f64::NAN);
            self.missing.push(true);
            self.t_us.push(t);
        }
        lost_pulse.is_some()
    }

    /// A pulse starts at the next sample pushed: the window is identified first when it holds
    /// K pulses already.
    fn pulse_start(&mut self, identify: impl FnMut(&WindowView<'_>)) {
        if self.pulse_starts.len() >= self.k {
            self.identify_now(Reason::Pulses, identify);
            self.restart_keeping_tail();
        }
        if self.pulse_starts.len() < self.pulse_starts.capacity() {
            self.pulse_starts.push(self.input.len());
        }
    }

    /// A new device segment: what is complete is identified, the rest dropped. Returns the
    /// window the device's reset interrupted, if one was dropped with pulses in it (the
    /// worker publishes it as `window_interrupted`, so that no window goes silently).
    pub fn on_segment(&mut self, identify: impl FnMut(&WindowView<'_>)) -> Option<Interrupted> {
        self.next_index = None;
        self.announced_pulse = None;
        self.close(Reason::Segment, identify)
    }

    /// The device clock jumped before the next sample: what is complete is identified (its
    /// samples all precede the jump), the rest dropped and returned as for a segment; the
    /// index runs on (the next sample starts a new window at its level).
    pub fn on_clock_jump(&mut self, identify: impl FnMut(&WindowView<'_>)) -> Option<Interrupted> {
        self.close(Reason::ClockJump, identify)
    }

    /// End of the stream: what is complete is identified; returns the window left with fewer
    /// than K pulses, if any.
    pub fn finish(&mut self, identify: impl FnMut(&WindowView<'_>)) -> Option<Interrupted> {
        self.close(Reason::End, identify)
    }

    /// Closes the window: identified when it holds K pulses, otherwise returned as
    /// [`Interrupted`] when it held any pulse (a window without a pulse is not one the plan
    /// made).
    fn close(
        &mut self,
        reason: Reason,
        mut identify: impl FnMut(&WindowView<'_>),
    ) -> Option<Interrupted> {
        let pulses = self.pulse_starts.len();
        let interrupted = (pulses > 0 && pulses < self.k)
            .then(|| self.level())
            .flatten()
            .map(|operating_point| Interrupted {
                operating_point,
                pulses,
                t_s: self.t_us.last().copied().unwrap_or(0) as f64 * 1e-6,
                closed_by: reason,
            });
        self.identify_if_complete(reason, &mut identify);
        self.clear();
        self.level_raw = None;
        self.in_pulse = false;
        interrupted
    }

    fn identify_if_complete(&mut self, reason: Reason, identify: impl FnMut(&WindowView<'_>)) {
        if self.pulse_starts.len() >= self.k && self.level_raw.is_some() {
            self.identify_now(reason, identify);
        }
    }

    fn identify_now(&mut self, reason: Reason, mut identify: impl FnMut(&WindowView<'_>)) {
        let Some(level) = self.level() else { return };
        let view = WindowView {
            input: &self.input,
            output: &self.output,
            missing: &self.missing,
            pulse_starts: &self.pulse_starts,
            dt_s: self.dt_s(),
            level,
            level_number: self.level_number,
            first_index: self.first_index,
            last_t_us: self.t_us.last().copied().unwrap_or(0),
            last_received: self.last_received,
            reason,
        };
        identify(&view);
    }

    /// Sample period from the device clock over the window's measured samples:
    /// `(t_last − t_first) / (k_last − k_first)`, exact when the device clock is.
    fn dt_s(&self) -> f64 {
        let first = self.missing.iter().position(|m| !m);
        let last = self.missing.iter().rposition(|m| !m);
        match (first, last) {
            (Some(a), Some(b)) if b > a => {
                (self.t_us[b] - self.t_us[a]) as f64 * 1e-6 / (b - a) as f64
            }
            _ => f64::NAN,
        }
    }

    fn start_level(&mut self, s: &SampleItem) {
        self.clear();
        self.level_raw = Some(s.throttle_raw);
        self.run = (s.throttle_raw, 1);
        self.held = self.run;
        self.level_number = self.levels_seen;
        self.levels_seen += 1;
        self.first_index = s.index;
    }

    /// Keeps the second half of the span since the last pulse start as the next baseline.
    fn restart_keeping_tail(&mut self) {
        let last_start = self.pulse_starts.last().copied().unwrap_or(0);
        let from = last_start + (self.input.len() - last_start).div_ceil(2);
        let from = from.min(self.input.len());
        for buf in [&mut self.input, &mut self.output] {
            buf.copy_within(from.., 0);
        }
        self.missing.copy_within(from.., 0);
        self.t_us.copy_within(from.., 0);
        let keep = self.input.len() - from;
        self.input.truncate(keep);
        self.output.truncate(keep);
        self.missing.truncate(keep);
        self.t_us.truncate(keep);
        self.first_index += from as u64;
        self.pulse_starts.clear();
        self.held = self.run;
    }

    fn clear(&mut self) {
        self.input.clear();
        self.output.clear();
        self.missing.clear();
        self.t_us.clear();
        self.pulse_starts.clear();
    }

    fn push(&mut self, s: &SampleItem) {
        let y = self.channel.pick(s);
        let missing = !y.is_finite();
        self.input
            .push(if missing { f64::NAN } else { s.throttle() });
        self.output.push(if missing { f64::NAN } else { y });
        self.missing.push(missing);
        self.t_us.push(s.t_us);
        self.last_received = Some(s.received);
    }
}

#[cfg(test)]
mod tests;
