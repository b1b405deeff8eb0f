//! The worker's fixed-size window of samples at one operating point, and when to identify.
//!
//! All buffers are allocated once ([`Window::new`]) with the capacity `max_window_samples`;
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
//!   samples during which the pulse throttle was applied).
//! - The window is identified when it holds K complete pulses: at the start of pulse K+1, or when
//!   the level ends, the window fills, a new device segment starts, or the stream ends. A pulse is
//!   complete when the next one starts or the level ends (the plan spaces pulses so the response
//!   has decayed by then).
//! - After an identification the window restarts at the new pulse, keeping the second half of
//!   the last pulse's response (decayed: the new pulse's pre-pulse baseline). Each model is
//!   therefore from K fresh pulses, and the window stays bounded.
//! - Lost samples (gaps) are pushed as missing (NaN, masked), never bridged; a gap that does not
//!   fit restarts the window. The window also checks that sample indices are contiguous by
//!   itself: a jump the sampler could not announce (its queue was full, so the samples *and*
//!   the gap notice may have been dropped) is treated exactly like an announced gap, and an
//!   index going backwards (a new segment whose notice was dropped) closes the window like a
//!   segment. The identification core leaves out, and counts (`pulses_skipped`), every pulse
//!   whose response window holds a missing sample.

use std::time::Instant;

use super::item::{flags, SampleItem};

/// Which output channel is identified.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputChannel {
    /// Thrust, N.
    Thrust,
    /// Torque, N·m.
    Torque,
    /// Rotor speed, rev/min.
    Rpm,
}

impl OutputChannel {
    /// From the config name (`thrust_N`, `torque_Nm`, `rpm`).
    pub fn from_name(name: &str) -> Option<OutputChannel> {
        match name {
            "thrust_N" => Some(OutputChannel::Thrust),
            "torque_Nm" => Some(OutputChannel::Torque),
            "rpm" => Some(OutputChannel::Rpm),
            _ => None,
        }
    }

    fn pick(self, s: &SampleItem) -> f64 {
        f64::from(match self {
            OutputChannel::Thrust => s.thrust_n,
            OutputChannel::Torque => s.torque_nm,
            OutputChannel::Rpm => s.rpm,
        })
    }
}

/// Why a window is identified (published as the model line's `reason`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    /// K pulses done and the next one started.
    Pulses,
    /// The operating point ended (ramp or level change).
    LevelEnd,
    /// The window reached its capacity.
    #[serde(rename = "window_full")]
    Full,
    /// The device started a new segment.
    Segment,
    /// The stream ended.
    End,
}

/// A read-only view of a window handed to the identifier.
#[derive(Debug, Clone, Copy)]
pub struct WindowView<'a> {
    /// Throttle, fraction 0..1 (NaN where missing).
    pub input: &'a [f64],
    /// The output channel (NaN where missing).
    pub output: &'a [f64],
    /// Missing-sample mask.
    pub missing: &'a [bool],
    /// Sample positions (in the window) of the pulse starts.
    pub pulse_starts: &'a [usize],
    /// Sample period from the device clock, s.
    pub dt_s: f64,
    /// Operating point: the throttle level, fraction 0..1.
    pub level: f64,
    /// Operating points seen so far (0-based number of this one).
    pub level_number: u32,
    /// Device sample index of the window's first sample.
    pub first_index: u64,
    /// Device time of the window's last sample, µs (unwrapped).
    pub last_t_us: u64,
    /// When the window's last sample was received (latency measurement).
    pub last_received: Option<Instant>,
    /// Why it is identified.
    pub reason: Reason,
}

/// What a sample did to the window, for counters and events.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Outcome {
    /// A pulse started at this sample.
    pub pulse: bool,
    /// A new operating point started at this sample.
    pub new_level: bool,
    /// The window was full and restarted without K pulses (data discarded).
    pub overflowed: bool,
    /// Samples missing just before this one that no gap announced (an index jump).
    pub unannounced_lost: u64,
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
                self.on_gap(s.index - next);
            }
            Some(next) if s.index < next => self.close(Reason::Segment, &mut identify),
            _ => {}
        }
        self.next_index = Some(s.index + 1);
        if s.has(flags::RAMP_ACTIVE) {
            self.close(Reason::LevelEnd, &mut identify);
            return out;
        }
        let pulse = s.has(flags::IMPULSE_ACTIVE);
        let off_level = match self.level_raw {
            Some(l) => l.abs_diff(s.throttle_raw) > self.tol_raw,
            None => true,
        };
        if !pulse && off_level {
            self.close(Reason::LevelEnd, &mut identify);
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
            if self.pulse_starts.len() >= self.k {
                self.identify_now(Reason::Pulses, &mut identify);
                self.restart_keeping_tail();
            }
            if self.pulse_starts.len() < self.pulse_starts.capacity() {
                self.pulse_starts.push(self.input.len());
            }
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

    /// `count` samples were lost before the next one: masked, or a restart if they do not fit.
    pub fn on_gap(&mut self, count: u64) {
        if let Some(next) = self.next_index.as_mut() {
            *next = next.saturating_add(count);
        }
        if self.level_raw.is_none() {
            return;
        }
        if (self.input.len() as u64).saturating_add(count) >= self.cap as u64 {
            self.clear();
            self.level_raw = None;
            return;
        }
        let t = self.t_us.last().copied().unwrap_or(0);
        for _ in 0..count {
            self.input.push(f64::NAN);
            self.output.push(f64::NAN);
            self.missing.push(true);
            self.t_us.push(t);
        }
    }

    /// A new device segment: what is complete is identified, the rest dropped.
    pub fn on_segment(&mut self, identify: impl FnMut(&WindowView<'_>)) {
        self.next_index = None;
        self.close(Reason::Segment, identify);
    }

    /// End of the stream.
    pub fn finish(&mut self, identify: impl FnMut(&WindowView<'_>)) {
        self.close(Reason::End, identify);
    }

    fn close(&mut self, reason: Reason, mut identify: impl FnMut(&WindowView<'_>)) {
        self.identify_if_complete(reason, &mut identify);
        self.clear();
        self.level_raw = None;
        self.in_pulse = false;
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
mod tests {
    use super::*;

    fn sample(index: u64, throttle_raw: u16, flags: u16) -> SampleItem {
        SampleItem {
            index,
            t_us: index * 1000,
            throttle_raw,
            flags,
            thrust_n: 1.0,
            torque_nm: 0.1,
            rpm: 1000.0,
            received: Instant::now(),
        }
    }

    /// Feeds `n` samples at `level`, a pulse every `spacing` samples from `first_pulse`.
    fn feed(
        w: &mut Window,
        start: u64,
        n: u64,
        level: u16,
        first_pulse: u64,
        spacing: u64,
        log: &mut Vec<(Reason, usize, usize, f64)>,
    ) {
        for i in start..start + n {
            let rel = i - start;
            let pulse = rel >= first_pulse && (rel - first_pulse) % spacing == 0;
            let (thr, f) = if pulse {
                (level + 500, flags::IMPULSE_ACTIVE)
            } else {
                (level, 0)
            };
            w.on_sample(&sample(i, thr, f), |v| {
                log.push((v.reason, v.input.len(), v.pulse_starts.len(), v.level))
            });
        }
    }

    #[test]
    fn identifies_every_k_pulses_and_at_level_end() {
        let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
        let mut log = Vec::new();
        // 5 pulses at spacing 100 from sample 50: models at pulse 3 and pulse 5 start, then
        // the level end with one pulse pending identifies nothing.
        feed(&mut w, 0, 500, 3000, 50, 100, &mut log);
        assert_eq!(log.len(), 2);
        assert_eq!((log[0].0, log[0].1, log[0].2), (Reason::Pulses, 250, 2));
        assert_eq!(log[0].3, 0.3);
        // the restarted window keeps 50 samples of baseline before pulse 3
        assert_eq!((log[1].0, log[1].1, log[1].2), (Reason::Pulses, 250, 2));
        w.on_sample(&sample(500, 3000, flags::RAMP_ACTIVE), |_| {
            panic!("only one pulse pending")
        });
        assert_eq!(w.level(), None);
    }

    #[test]
    fn a_ramp_without_flags_ends_at_the_level_it_reached() {
        // a CSV bench's ramp: 0.30 -> 0.447 in steps of 0.0035 (below the 0.005 tolerance), no
        // RAMP_ACTIVE, the window restarting every second step (last at 0.447); then 0.45
        let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
        let mut log = Vec::new();
        feed(&mut w, 0, 100, 3000, 1000, 100, &mut log);
        for (k, thr) in (3000..=4500).step_by(35).enumerate() {
            w.on_sample(&sample(100 + k as u64, thr, 0), |_| {});
        }
        feed(&mut w, 143, 400, 4500, 50, 100, &mut log);
        assert_eq!(w.level(), Some(0.45));
        // the ramp away: its first steps are within the tolerance, then the level ends
        for (k, thr) in [4480u16, 4460, 4440, 4420, 4400].into_iter().enumerate() {
            w.on_sample(&sample(543 + k as u64, thr, 0), |v| {
                log.push((v.reason, v.input.len(), v.pulse_starts.len(), v.level))
            });
        }
        assert_eq!(log.len(), 2, "{log:?}");
        assert_eq!(log[1].0, Reason::LevelEnd);
        assert!(log.iter().all(|l| l.3 == 0.45), "{log:?}");
    }

    #[test]
    fn level_end_identifies_complete_pulses() {
        let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
        let mut log = Vec::new();
        feed(&mut w, 0, 300, 3000, 50, 100, &mut log); // pulses at 50, 150, 250
        assert_eq!(log.len(), 1);
        feed(&mut w, 300, 100, 4500, 1000, 100, &mut log); // new level, no pulses
        assert_eq!(log.len(), 1, "one pending pulse is not enough");
        let mut w = Window::new(10_000, 2, 0.005, OutputChannel::Thrust);
        let mut log = Vec::new();
        feed(&mut w, 0, 200, 3000, 50, 100, &mut log); // pulses at 50, 150
        feed(&mut w, 200, 10, 4500, 1000, 100, &mut log);
        assert_eq!(log.len(), 1);
        assert_eq!((log[0].0, log[0].1, log[0].2), (Reason::LevelEnd, 200, 2));
        assert_eq!(w.level(), Some(0.45));
    }

    #[test]
    fn gaps_are_masked_not_bridged() {
        let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
        let mut seen = None;
        w.on_sample(&sample(0, 3000, 0), |_| {});
        w.on_sample(&sample(1, 3000, 0), |_| {});
        w.on_gap(3);
        w.on_sample(&sample(5, 3500, flags::IMPULSE_ACTIVE), |_| {});
        w.on_sample(&sample(6, 3000, 0), |_| {});
        w.finish(|v| {
            seen = Some((
                v.missing.to_vec(),
                v.pulse_starts.to_vec(),
                v.input[2].is_nan(),
                v.dt_s,
            ))
        });
        let (missing, starts, nan, dt) = seen.unwrap();
        assert_eq!(missing, vec![false, false, true, true, true, false, false]);
        assert_eq!(starts, vec![5]);
        assert!(nan);
        assert!((dt - 1e-3).abs() < 1e-12);
    }

    #[test]
    fn unannounced_index_jump_is_masked_not_bridged() {
        // The sampler's queue overflowed: samples 2..=4 and their gap notice never arrived.
        let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
        let mut seen = None;
        w.on_sample(&sample(0, 3000, 0), |_| {});
        w.on_sample(&sample(1, 3000, flags::IMPULSE_ACTIVE), |_| {});
        let o = w.on_sample(&sample(5, 3000, 0), |_| {});
        assert_eq!(o.unannounced_lost, 3);
        w.on_sample(&sample(6, 3000, 0), |_| {});
        w.finish(|v| seen = Some((v.missing.to_vec(), v.pulse_starts.to_vec(), v.dt_s)));
        let (missing, starts, dt) = seen.unwrap();
        assert_eq!(missing, vec![false, false, true, true, true, false, false]);
        assert_eq!(starts, vec![1]);
        assert!((dt - 1e-3).abs() < 1e-12);
    }

    #[test]
    fn announced_gap_is_not_counted_twice() {
        let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
        w.on_sample(&sample(0, 3000, 0), |_| {});
        w.on_gap(3);
        let o = w.on_sample(&sample(4, 3000, 0), |_| {});
        assert_eq!(o.unannounced_lost, 0);
        assert_eq!(w.len(), 5);
    }

    #[test]
    fn index_going_back_closes_the_window_like_a_segment() {
        let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
        let mut log = Vec::new();
        feed(&mut w, 100, 100, 3000, 50, 1000, &mut log);
        assert!(log.is_empty());
        let mut reasons = Vec::new();
        w.on_sample(&sample(0, 3000, 0), |v| reasons.push(v.reason));
        assert_eq!(reasons, vec![Reason::Segment]);
        assert_eq!(w.len(), 1, "the new segment starts a fresh window");
    }

    #[test]
    fn full_window_restarts_without_allocating() {
        let mut w = Window::new(64, 4, 0.005, OutputChannel::Thrust);
        let cap = w.input.capacity();
        let mut log = Vec::new();
        let mut overflowed = 0;
        for i in 0..200 {
            let o = w.on_sample(&sample(i, 3000, 0), |v| log.push(v.reason));
            overflowed += u32::from(o.overflowed);
        }
        assert!(log.is_empty());
        assert_eq!(overflowed, 3);
        assert!(w.len() <= 64);
        assert_eq!(w.input.capacity(), cap);
    }

    #[test]
    fn segment_identifies_complete_window_then_waits_for_a_level() {
        let mut w = Window::new(10_000, 1, 0.005, OutputChannel::Thrust);
        let mut log = Vec::new();
        feed(&mut w, 0, 100, 3000, 50, 1000, &mut log);
        let mut n = 0;
        w.on_segment(|v| {
            assert_eq!(v.reason, Reason::Segment);
            n += 1
        });
        assert_eq!(n, 1);
        assert_eq!(w.level(), None);
        // a pulse sample first after the reset is not referred to any level
        let o = w.on_sample(&sample(0, 3500, flags::IMPULSE_ACTIVE), |_| {});
        assert!(!o.pulse);
    }

    #[test]
    fn missing_measurement_is_masked() {
        let mut w = Window::new(100, 1, 0.005, OutputChannel::Thrust);
        let mut s = sample(0, 3000, 0);
        w.on_sample(&s, |_| {});
        s.index = 1;
        s.thrust_n = f32::NAN;
        w.on_sample(&s, |_| {});
        assert_eq!(w.missing, vec![false, true]);
    }
}
