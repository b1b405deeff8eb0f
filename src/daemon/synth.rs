//! Synthetic TSP/1 device streams with exactly known content, for tests and benchmarks.
//!
//! [`synth_stream`] writes what a stand running the default experiment would send: a HELLO,
//! then per operating point a ramp (RAMP_ACTIVE), a settle time and one-sample pulses of
//! alternating sign and two amplitudes (IMPULSE_ACTIVE, EVENT IMPULSE_START/END), all sampled
//! from a known 2nd-order plant, optionally with noise. Faults are injected at exact places so
//! tests can assert the daemon's counters exactly: dropped samples (index jumps), bit flips in
//! chosen SAMPLE frames, garbage bursts, a device clock that starts just before its wrap.
//!
//! **Plant.** Thrust `y` responds to throttle `u` (fraction) through
//! `y_k = a1 y_{k−1} + a2 y_{k−2} + b (u_{k−1} + u_{k−2})` with the poles
//! `z = exp(s·dt)`, `s = −ζω ± jω√(1−ζ²)`, `ω = 2π fn`: `a1 = 2 Re z`, `a2 = −|z|²`, and
//! `b = g (1 − a1 − a2) / 2` so that the DC gain is `g` N per unit throttle.

use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::protocol::encode_frame;
use crate::protocol::message::{
    EscProtocol, Event, EventCode, Frame, Hello, Message, Sample, SampleFlags,
};
use crate::protocol::MAX_FRAME_LEN;

/// What to synthesise.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthConfig {
    /// Sample rate, Hz.
    pub rate_hz: u32,
    /// Operating points, throttle fraction.
    pub levels: Vec<f64>,
    /// Pulses per operating point.
    pub pulses_per_level: u32,
    /// Pulse amplitudes (alternating sign: +a0, −a0, +a1, −a1, …).
    pub amplitudes: Vec<f64>,
    /// Samples from one pulse to the next.
    pub spacing: u32,
    /// Samples of settling after a ramp before the first pulse.
    pub settle: u32,
    /// Samples of ramp between levels.
    pub ramp: u32,
    /// Plant natural frequency, Hz.
    pub fn_hz: f64,
    /// Plant damping ratio (< 1).
    pub zeta: f64,
    /// Plant DC gain, N per unit throttle.
    pub gain: f64,
    /// Thrust noise standard deviation, N.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// Device clock of the first sample, µs (near `u32::MAX` to test the wrap).
    pub t0_us: u32,
    /// Boot id in the HELLO.
    pub boot_id: u32,
    /// Sample indices (0-based, as the device counts) never sent: device-side drops.
    pub drop_samples: Vec<u32>,
    /// Sample indices whose SAMPLE frame gets one bit flipped (in its CRC, never to 0x00).
    pub flip_samples: Vec<u32>,
    /// Sample indices before which a garbage burst (text then 0x00) is inserted.
    pub garbage_before: Vec<u32>,
}

impl Default for SynthConfig {
    fn default() -> Self {
        SynthConfig {
            rate_hz: 1000,
            levels: vec![0.3, 0.45, 0.6],
            pulses_per_level: 8,
            amplitudes: vec![0.05, 0.1],
            spacing: 150,
            settle: 300,
            ramp: 50,
            fn_hz: 25.0,
            zeta: 0.5,
            gain: 8.0,
            noise: 0.0,
            seed: 1,
            t0_us: 1_000,
            boot_id: 0xB007_0001,
            drop_samples: Vec::new(),
            flip_samples: Vec::new(),
            garbage_before: Vec::new(),
        }
    }
}

/// One sample of the schedule: throttle (raw) and flags.
#[derive(Debug, Clone, Copy)]
struct Step {
    raw: u16,
    flags: u16,
    pulse_start: bool,
    pulse_end: bool,
}

/// The throttle schedule of the experiment, one entry per sample.
fn schedule(cfg: &SynthConfig) -> Vec<Step> {
    let raw = |x: f64| (x * 10_000.0).round().clamp(0.0, 10_000.0) as u16;
    let mut out = Vec::new();
    let mut prev = 0.0;
    for &level in &cfg.levels {
        for i in 0..cfg.ramp {
            let x = prev + (level - prev) * f64::from(i + 1) / f64::from(cfg.ramp);
            out.push(Step {
                raw: raw(x),
                flags: SampleFlags::RAMP_ACTIVE.bits(),
                pulse_start: false,
                pulse_end: false,
            });
        }
        let plain = Step {
            raw: raw(level),
            flags: 0,
            pulse_start: false,
            pulse_end: false,
        };
        out.extend(std::iter::repeat(plain).take(cfg.settle as usize));
        for j in 0..cfg.pulses_per_level {
            let a = cfg.amplitudes[(j as usize / 2) % cfg.amplitudes.len()];
            let a = if j % 2 == 0 { a } else { -a };
            out.push(Step {
                raw: raw(level + a),
                flags: SampleFlags::IMPULSE_ACTIVE.bits(),
                pulse_start: true,
                pulse_end: false,
            });
            let mut after = plain;
            after.pulse_end = true;
            out.push(after);
            out.extend(std::iter::repeat(plain).take(cfg.spacing.saturating_sub(2) as usize));
        }
        prev = level;
    }
    out
}

/// The plant's recursion coefficients `(a1, a2, b)` (see the module docs).
fn plant(cfg: &SynthConfig) -> (f64, f64, f64) {
    let dt = 1.0 / f64::from(cfg.rate_hz);
    let w = 2.0 * std::f64::consts::PI * cfg.fn_hz;
    let re = (-cfg.zeta * w * dt).exp();
    let wd = w * (1.0 - cfg.zeta * cfg.zeta).max(0.0).sqrt();
    let a1 = 2.0 * re * (wd * dt).cos();
    let a2 = -re * re;
    (a1, a2, cfg.gain * (1.0 - a1 - a2) / 2.0)
}

/// Appends one encoded frame.
fn push_frame(out: &mut Vec<u8>, seq: &mut u16, msg: &Message) {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(*seq, msg, &mut buf);
    *seq = seq.wrapping_add(1);
    out.extend_from_slice(&buf[..n]);
}

/// The HELLO this device sends.
pub fn hello(cfg: &SynthConfig, t_us: u32) -> Message {
    Message::Hello(Hello {
        proto_minor: 0,
        esc_protocol: EscProtocol::from_u8(3),
        fw_version: 1,
        boot_id: cfg.boot_id,
        t_us,
        sample_rate_hz: cfg.rate_hz.min(u32::from(u16::MAX)) as u16,
        channels: 0b1,
        motor_poles: 14,
        caps: 0b1111,
        name: Hello::name_field("synth"),
    })
}

/// What the stream holds, for exact assertions.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SynthFacts {
    /// SAMPLE frames the device produced (including dropped and corrupted ones).
    pub samples_taken: u64,
    /// SAMPLE frames written intact.
    pub samples_sent: u64,
    /// Frames written intact (all types).
    pub frames_intact: u64,
    /// Frames corrupted by a bit flip.
    pub frames_flipped: u64,
    /// Garbage bursts inserted.
    pub garbage_bursts: u64,
}

/// Writes the device's byte stream for `cfg` and what it holds.
pub fn synth_stream(cfg: &SynthConfig) -> (Vec<u8>, SynthFacts) {
    let steps = schedule(cfg);
    let (a1, a2, b) = plant(cfg);
    let dt_us = 1_000_000.0 / f64::from(cfg.rate_hz);
    let mut rng = rand::rngs::StdRng::seed_from_u64(cfg.seed);
    let normal = Normal::new(0.0, cfg.noise.max(0.0)).unwrap_or(Normal::new(0.0, 0.0).unwrap());
    let mut out = Vec::with_capacity(steps.len() * 40);
    let mut facts = SynthFacts::default();
    let mut seq = 0u16;
    push_frame(&mut out, &mut seq, &hello(cfg, cfg.t0_us));
    facts.frames_intact += 1;
    let (mut y1, mut y2, mut u1, mut u2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (k, st) in steps.iter().enumerate() {
        let idx = k as u32;
        let t_us = cfg
            .t0_us
            .wrapping_add((f64::from(idx) * dt_us).round() as u32);
        let u = f64::from(st.raw) / 10_000.0;
        let y = a1 * y1 + a2 * y2 + b * (u1 + u2);
        (y2, y1, u2, u1) = (y1, y, u1, u);
        facts.samples_taken += 1;
        if cfg.garbage_before.contains(&idx) {
            out.extend_from_slice(b"boot banner v1.2\r\n\x00");
            facts.garbage_bursts += 1;
        }
        if cfg.drop_samples.contains(&idx) {
            continue;
        }
        let noise = if cfg.noise > 0.0 {
            normal.sample(&mut rng)
        } else {
            0.0
        };
        if st.pulse_start {
            let ev = Message::Event(Event {
                code: EventCode::ImpulseStart,
                arg: 0,
                t_us,
                sample_index: idx,
            });
            push_frame(&mut out, &mut seq, &ev);
            facts.frames_intact += 1;
        }
        let flags = SampleFlags::ARMED.bits() | SampleFlags::THRUST_VALID.bits() | st.flags;
        let msg = Message::Sample(Sample {
            sample_index: idx,
            t_us,
            throttle: st.raw,
            flags: SampleFlags(flags | SampleFlags::THRUST_FRESH.bits()),
            thrust_n: (y + noise) as f32,
            torque_nm: f32::NAN,
            rpm: f32::NAN,
            voltage_v: 16.8,
            current_a: f32::NAN,
        });
        let start = out.len();
        push_frame(&mut out, &mut seq, &msg);
        if cfg.flip_samples.contains(&idx) {
            // The CRC's last byte sits just before the delimiter; flip a bit that cannot
            // turn it into 0x00 (a delimiter), so exactly this frame is lost.
            let pos = out.len() - 2;
            let bit = if out[pos] == 0x01 { 0x02 } else { 0x01 };
            out[pos] ^= bit;
            debug_assert!(out[start..out.len() - 1].iter().all(|&b| b != 0));
            facts.frames_flipped += 1;
        } else {
            facts.samples_sent += 1;
            facts.frames_intact += 1;
        }
        if st.pulse_end {
            let ev = Message::Event(Event {
                code: EventCode::ImpulseEnd,
                arg: 0,
                t_us,
                sample_index: idx,
            });
            push_frame(&mut out, &mut seq, &ev);
            facts.frames_intact += 1;
        }
    }
    (out, facts)
}

/// Decodes a stream into frames (for tests of the synthesiser itself).
pub fn frames_of(bytes: &[u8]) -> Vec<Frame> {
    let mut d = crate::protocol::Decoder::new();
    let mut v = Vec::new();
    d.push(bytes, |f| v.push(f));
    v
}

/// The true plant as `(fn_hz, zeta, dc_gain)`.
pub fn truth(cfg: &SynthConfig) -> (f64, f64, f64) {
    (cfg.fn_hz, cfg.zeta, cfg.gain)
}

/// Benchmarks: a stream of `seconds` at `rate_hz` of the default plan.
pub fn long_config(rate_hz: u32, seconds: f64) -> SynthConfig {
    let base = SynthConfig {
        rate_hz,
        ..SynthConfig::default()
    };
    let per_level = base.ramp + base.settle + base.pulses_per_level * base.spacing;
    let levels_needed = ((seconds * f64::from(rate_hz)) / f64::from(per_level)).ceil() as usize;
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    SynthConfig {
        levels: (0..levels_needed.max(1))
            .map(|_| rng.gen_range(0.25..0.7))
            .collect(),
        noise: 0.01,
        ..base
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clean_stream_decodes_to_the_expected_frames() {
        let cfg = SynthConfig::default();
        let (bytes, facts) = synth_stream(&cfg);
        let frames = frames_of(&bytes);
        assert_eq!(frames.len() as u64, facts.frames_intact);
        let samples = frames
            .iter()
            .filter(|f| matches!(f.msg, Message::Sample(_)))
            .count() as u64;
        assert_eq!(samples, facts.samples_taken);
        let per_level = u64::from(cfg.ramp + cfg.settle + cfg.pulses_per_level * cfg.spacing);
        assert_eq!(facts.samples_taken, per_level * 3);
    }

    #[test]
    fn plant_has_the_stated_dc_gain() {
        let cfg = SynthConfig::default();
        let (a1, a2, b) = plant(&cfg);
        assert!((2.0 * b / (1.0 - a1 - a2) - cfg.gain).abs() < 1e-12);
    }

    #[test]
    fn faults_are_placed_exactly() {
        let cfg = SynthConfig {
            drop_samples: vec![10, 11, 500],
            flip_samples: vec![20, 700, 701],
            garbage_before: vec![30, 900],
            ..SynthConfig::default()
        };
        let (bytes, facts) = synth_stream(&cfg);
        assert_eq!(facts.frames_flipped, 3);
        assert_eq!(facts.garbage_bursts, 2);
        let mut d = crate::protocol::Decoder::new();
        let mut n = 0u64;
        d.push(&bytes, |_| n += 1);
        assert_eq!(n, facts.frames_intact);
        assert_eq!(d.stats().dropped.total(), 5);
        assert_eq!(facts.samples_sent, facts.samples_taken - 6);
    }
}
