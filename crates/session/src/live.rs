//! The lines only the live web page gets (`propid run|replay|demo --http`): what the page draws
//! that the stdout lines do not carry. Published to the HTTP clients only
//! ([`Publisher::publish_live`](super::publish::Publisher::publish_live)), so stdout, the file
//! and the socket publish exactly what they did; built only when an HTTP sink is open.
//!
//! - `{"type":"samples", "t_s", "throttle", "thrust_N", "torque_Nm", "rpm", "voltage_V",
//!   "current_A", "pulses"}`
//!   ([`SamplesLine`]): the samples of about the last 100 ms of device time, thinned to at most
//!   one every [`KEEP_EVERY_US`] (a sample inside a pulse is always kept, so every pulse is
//!   drawn), and the device times of the pulse starts among them.
//! - `{"type":"response", ...}` ([`ResponseLine`]): the latest window's measured pulse
//!   responses per unit throttle (the mean over its pulses and their standard deviation per
//!   lag) and the model's response to the same unit pulse.
//! - `{"type":"stabilization", "t_s", "operating_point", "level", <identify --json's
//!   stabilization>}` ([`StabilizationLine`]): the latest window's stabilization diagram and
//!   singular values.
//! - `{"type":"live_stats", <the fields of the final stats line>}`: the counters so far,
//!   about twice a second.
//! - `{"type":"schedule", "models"}` after every model: the gain schedule so far (the final
//!   schedule line has the same shape).

use serde::Serialize;

use super::item::{flags, SampleItem};
use propid_numerics::nullable;
use propid_numerics::pulses::PulseEnsemble;
use propid_numerics::stabilization::Stabilization;
use propid_numerics::StateSpace;

/// Keep at most one sample per this many µs of device time (250 per second), besides the
/// samples inside a pulse.
pub const KEEP_EVERY_US: u64 = 4_000;

/// A `samples` line is due when its first sample is this old, µs of device time.
pub const SAMPLES_LINE_US: u64 = 100_000;

/// Longest pulse response drawn, lags.
pub const MAX_LAGS: usize = 1_024;

/// A `"samples"` line.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SamplesLine {
    /// Device time of each sample (unwrapped), s.
    pub t_s: Vec<f64>,
    /// Throttle, fraction 0..1.
    pub throttle: Vec<f64>,
    /// Thrust, N (`null` when not valid).
    #[serde(rename = "thrust_N", with = "nullable::vec")]
    pub thrust_n: Vec<f64>,
    /// Torque, N·m.
    #[serde(rename = "torque_Nm", with = "nullable::vec")]
    pub torque_nm: Vec<f64>,
    /// Rotor speed, rev/min.
    #[serde(with = "nullable::vec")]
    pub rpm: Vec<f64>,
    /// Supply voltage, V (`null` when the stand does not send it).
    #[serde(rename = "voltage_V", with = "nullable::vec")]
    pub voltage_v: Vec<f64>,
    /// Current, A (`null` when the stand does not send it).
    #[serde(rename = "current_A", with = "nullable::vec")]
    pub current_a: Vec<f64>,
    /// Device times of the pulse starts among these samples, s.
    pub pulses: Vec<f64>,
}

/// Thins the sample stream into [`SamplesLine`]s (the worker's, with an HTTP sink only).
#[derive(Debug, Default)]
pub struct SampleDigest {
    line: SamplesLine,
    first_us: Option<u64>,
    next_keep_us: u64,
}

impl SampleDigest {
    /// Takes one sample (`pulse_start`: the window saw a pulse start at it); returns the line
    /// when [`SAMPLES_LINE_US`] of device time have gathered.
    pub fn push(&mut self, s: &SampleItem, pulse_start: bool) -> Option<SamplesLine> {
        let t_s = s.t_us as f64 / 1e6;
        if pulse_start {
            self.line.pulses.push(t_s);
        }
        if s.t_us < self.next_keep_us && !s.has(flags::IMPULSE_ACTIVE) && !pulse_start {
            return None;
        }
        self.next_keep_us = s.t_us + KEEP_EVERY_US;
        let first = *self.first_us.get_or_insert(s.t_us);
        let l = &mut self.line;
        l.t_s.push(t_s);
        l.throttle.push(s.throttle());
        l.thrust_n.push(short(s.thrust_n));
        l.torque_nm.push(short(s.torque_nm));
        l.rpm.push(short(s.rpm));
        l.voltage_v.push(short(s.voltage_v));
        l.current_a.push(short(s.current_a));
        if s.t_us.saturating_sub(first) >= SAMPLES_LINE_US || s.t_us < first {
            return self.take();
        }
        None
    }

    /// The samples gathered and not yet published, if any.
    pub fn take(&mut self) -> Option<SamplesLine> {
        self.first_us = None;
        if self.line.t_s.is_empty() {
            return None;
        }
        Some(std::mem::take(&mut self.line))
    }
}

/// The `f64` that prints as the `f32` does (`1.1` rather than `1.100000023841858`): the
/// digits the device sent, not the float's binary tail.
fn short(x: f32) -> f64 {
    if !x.is_finite() {
        return f64::NAN;
    }
    x.to_string().parse().unwrap_or(f64::NAN)
}

/// A `"response"` line: the latest window's pulse responses and the model's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ResponseLine {
    /// Device time of the window's last sample, s (the model line's `t_s`).
    pub t_s: f64,
    /// The window's operating point, fraction.
    pub operating_point: f64,
    /// The operating point's number.
    pub level: u32,
    /// Sample period, s: lag `k` is at `k · dt_s` after the pulse start.
    pub dt_s: f64,
    /// Width of the unit pulse both responses answer, samples.
    pub width: usize,
    /// Pulses averaged.
    pub pulses: usize,
    /// Mean over the pulses of `(y[start + k] − baseline) / amplitude`, per lag.
    #[serde(with = "nullable::vec")]
    pub mean: Vec<f64>,
    /// Their standard deviation per lag (`null` with fewer than two pulses measured there).
    #[serde(with = "nullable::vec")]
    pub spread: Vec<f64>,
    /// The model's response to the same pulse (amplitude 1, `width` samples), from rest.
    #[serde(with = "nullable::vec")]
    pub model: Vec<f64>,
}

/// A `"stabilization"` line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StabilizationLine {
    /// Device time of the window's last sample, s.
    pub t_s: f64,
    /// The window's operating point, fraction.
    pub operating_point: f64,
    /// The operating point's number.
    pub level: u32,
    /// The diagram (the shape of `identify --json`'s `"stabilization"`).
    #[serde(flatten)]
    pub diagram: Stabilization,
}

/// The measured pulse responses of the ensemble's kept pulses, over `lags` lags, per unit
/// throttle: for pulse `i` at `start` with amplitude `a` and baseline `b` (the ensemble's own
/// pulses and baselines: the identification's, not a second pulse finder),
/// `r_i[k] = (y[start + k] − b) / a`, missing samples left out; then the mean and the standard
/// deviation over the pulses at each lag, and the model's response to the same unit pulse.
pub fn response(
    ens: &PulseEnsemble,
    y: &[f64],
    missing: &[bool],
    lags: usize,
    model: Option<&StateSpace>,
    dt_s: f64,
) -> ResponseLine {
    let lags = lags.min(MAX_LAGS);
    let (mut sum, mut sq, mut n) = (vec![0.0; lags], vec![0.0; lags], vec![0usize; lags]);
    let mut width = 0;
    let mut pulses = 0;
    for (i, p) in ens.pulses().iter().enumerate() {
        if !p.kept || p.amplitude == 0.0 {
            continue;
        }
        let base = ens.baseline(i).first().copied().unwrap_or(f64::NAN);
        pulses += 1;
        if width == 0 {
            width = p.width.max(1);
        }
        for k in 0..lags {
            let j = p.start + k;
            if j >= y.len() || missing.get(j).copied().unwrap_or(false) {
                continue;
            }
            let r = (y[j] - base) / p.amplitude;
            if r.is_finite() {
                sum[k] += r;
                sq[k] += r * r;
                n[k] += 1;
            }
        }
    }
    let mean: Vec<f64> = (0..lags)
        .map(|k| {
            if n[k] > 0 {
                sum[k] / n[k] as f64
            } else {
                f64::NAN
            }
        })
        .collect();
    let spread = (0..lags)
        .map(|k| {
            if n[k] < 2 {
                return f64::NAN;
            }
            let m = mean[k];
            ((sq[k] - n[k] as f64 * m * m) / (n[k] - 1) as f64)
                .max(0.0)
                .sqrt()
        })
        .collect();
    let width = width.max(1);
    let model = model
        .and_then(|ss| {
            if ss.inputs() != 1 || ss.outputs() != 1 {
                return None;
            }
            let u: Vec<f64> = (0..lags)
                .map(|k| if k < width { 1.0 } else { 0.0 })
                .collect();
            let mut out = vec![0.0; lags];
            ss.simulate(&u, &mut out).ok().map(|()| out)
        })
        .unwrap_or_default();
    ResponseLine {
        t_s: f64::NAN,
        operating_point: f64::NAN,
        level: 0,
        dt_s,
        width,
        pulses,
        mean,
        spread,
        model,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    fn sample(index: u64, t_us: u64, flags: u16) -> SampleItem {
        SampleItem {
            index,
            t_us,
            throttle_raw: 3_000,
            flags,
            thrust_n: 1.5,
            torque_nm: f32::NAN,
            rpm: 9_000.0,
            voltage_v: 15.9,
            current_a: f32::NAN,
            received: Instant::now(),
        }
    }

    /// 1 kHz samples are thinned to one per 4 ms, a pulse's samples are all kept, and a line
    /// comes out every 100 ms of device time with the pulse start in it.
    #[test]
    fn the_digest_thins_keeps_pulses_and_cuts_lines() {
        let mut d = SampleDigest::default();
        let mut lines = Vec::new();
        for i in 0..250u64 {
            let f = if (50..52).contains(&i) {
                flags::IMPULSE_ACTIVE
            } else {
                0
            };
            if let Some(l) = d.push(&sample(i, i * 1_000, f), i == 50) {
                lines.push(l);
            }
        }
        assert_eq!(lines.len(), 2);
        let first = &lines[0];
        assert!(first.t_s.len() < 30, "{}", first.t_s.len());
        assert!(first.t_s.contains(&0.05) && first.t_s.contains(&0.051));
        assert_eq!(first.pulses, vec![0.05]);
        let text = serde_json::to_string(first).unwrap();
        assert!(text.contains(r#""torque_Nm":[null"#), "{text}");
        assert!(text.contains(r#""voltage_V":[15.9,"#), "{text}");
        assert!(text.contains(r#""current_A":[null"#), "{text}");
        assert!(d.take().is_some());
        assert!(d.take().is_none());
    }
}
