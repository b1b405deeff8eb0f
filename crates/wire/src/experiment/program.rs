//! The set-point program of the kinds other than pulses (`staircase`, `ramp`, `chirp`): a
//! timed list of SET_THROTTLE commands, generated from the configuration alone.
//!
//! - **staircase**: the levels sorted up, then back down (the top once), each a step
//!   (`ramp_ms` 0) held `hold_ms`.
//! - **ramp**: a step (with the configured `ramp_ms`) to the lowest level, held `settle_ms`;
//!   the up leg to the highest at `ramp_rate_per_s` (one SET_THROTTLE whose device ramp lasts
//!   `(hi − lo)/rate`, split into pieces of at most [`MAX_RAMP_PIECE_MS`]); `hold_ms` at the
//!   top; the down leg back; `hold_ms` at the bottom.
//! - **chirp**: to the level (`ramp_ms`), held `settle_ms`; then every [`CHIRP_STEP_MS`] a
//!   SET_THROTTLE to `u(t) = level + A·sin φ(t)`, ramped over the step (the device draws
//!   the sine piecewise linearly), with the logarithmic (exponential) sweep of Farina (2000,
//!   *Simultaneous measurement of impulse response and distortion with a swept-sine
//!   technique*): `f(t) = f₀·(f₁/f₀)^(t/T)`, `φ(t) = 2π f₀ T/ln(f₁/f₀)·((f₁/f₀)^(t/T) − 1)`,
//!   equal time per octave; then `settle_ms` at the level.
//!
//! Times are from the program's start (the ARM's ACK); the plan sends set-point `i` at its
//! time or, when the previous one is still unacknowledged, at that ACK.

use super::config::{ExperimentConfig, Kind};

/// The chirp's command period, ms: the device ramps between consecutive points.
pub const CHIRP_STEP_MS: u64 = 10;
/// Longest device ramp of one ramp piece, ms (SET_THROTTLE's `ramp_ms` is 16-bit).
pub const MAX_RAMP_PIECE_MS: u64 = 60_000;

/// One SET_THROTTLE of the program.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setpoint {
    /// When to send it, ms from the program's start.
    pub at_ms: u64,
    /// Throttle fraction.
    pub level: f64,
    /// The device's ramp to it, ms.
    pub ramp_ms: u16,
    /// A level the plan announces (`LevelReached`): a staircase's or ramp's hold, a chirp's
    /// level; not a chirp's points nor a ramp's pieces.
    pub announce: bool,
}

/// The program of `cfg`'s kind and its end (ms from the start: the last hold over). Empty for
/// `pulses`.
pub fn program(cfg: &ExperimentConfig) -> (Vec<Setpoint>, u64) {
    let mut p = Vec::new();
    let mut t = 0u64;
    let put = |p: &mut Vec<Setpoint>, at_ms: u64, level: f64, ramp_ms: u64, announce: bool| {
        p.push(Setpoint {
            at_ms,
            level,
            ramp_ms: ramp_ms.min(u16::MAX as u64) as u16,
            announce,
        })
    };
    let mut sorted = cfg.levels.clone();
    sorted.sort_by(f64::total_cmp);
    match cfg.kind {
        Kind::Pulses => return (p, 0),
        Kind::Staircase => {
            let down = sorted.iter().rev().skip(1).copied();
            let order: Vec<f64> = sorted.iter().copied().chain(down).collect();
            for l in order {
                put(&mut p, t, l, 0, true);
                t += cfg.hold_ms as u64;
            }
        }
        Kind::Ramp => {
            let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
            put(&mut p, t, lo, cfg.ramp_ms as u64, true);
            t += cfg.ramp_ms as u64 + cfg.settle_ms as u64;
            for (from, to) in [(lo, hi), (hi, lo)] {
                let leg_ms = ((to - from).abs() / cfg.ramp_rate_per_s * 1000.0).round() as u64;
                let pieces = leg_ms.div_ceil(MAX_RAMP_PIECE_MS).max(1);
                for k in 1..=pieces {
                    let piece = leg_ms * k / pieces - leg_ms * (k - 1) / pieces;
                    let level = from + (to - from) * k as f64 / pieces as f64;
                    put(&mut p, t, level, piece, k == pieces);
                    t += piece;
                }
                t += cfg.hold_ms as u64;
            }
        }
        Kind::Chirp => {
            let level = cfg.levels[0];
            put(&mut p, t, level, cfg.ramp_ms as u64, true);
            t += cfg.ramp_ms as u64 + cfg.settle_ms as u64;
            let n = (cfg.chirp_s * 1000.0 / CHIRP_STEP_MS as f64).round() as u64;
            for k in 1..=n {
                let ts = (k * CHIRP_STEP_MS) as f64 / 1000.0;
                let u = level + cfg.chirp_amplitude * chirp_phase(cfg, ts).sin();
                put(&mut p, t + k * CHIRP_STEP_MS, u, CHIRP_STEP_MS, false);
            }
            t += (n + 1) * CHIRP_STEP_MS;
            put(&mut p, t, level, CHIRP_STEP_MS, false);
            t += cfg.settle_ms as u64;
        }
    }
    (p, t)
}

/// The log sweep's phase at `t_s` seconds into it (module doc), rad.
pub fn chirp_phase(cfg: &ExperimentConfig, t_s: f64) -> f64 {
    let (f0, f1, t) = (cfg.chirp_f0_hz, cfg.chirp_f1_hz, cfg.chirp_s);
    let r = (f1 / f0).ln();
    std::f64::consts::TAU * f0 * t / r * ((r * t_s / t).exp() - 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(kind: Kind) -> ExperimentConfig {
        ExperimentConfig {
            kind,
            ..ExperimentConfig::default()
        }
    }

    #[test]
    fn a_staircase_goes_up_then_down_each_level_held() {
        let c = ExperimentConfig {
            levels: vec![0.6, 0.3, 0.45],
            ..cfg(Kind::Staircase)
        };
        let (p, end) = program(&c);
        let levels: Vec<f64> = p.iter().map(|s| s.level).collect();
        assert_eq!(levels, vec![0.3, 0.45, 0.6, 0.45, 0.3]);
        let at: Vec<u64> = p.iter().map(|s| s.at_ms).collect();
        assert_eq!(at, vec![0, 2000, 4000, 6000, 8000]);
        assert_eq!(end, 10_000);
        assert!(p.iter().all(|s| s.ramp_ms == 0 && s.announce));
    }

    #[test]
    fn a_ramp_runs_both_legs_at_the_rate() {
        let c = ExperimentConfig {
            levels: vec![0.2, 0.8],
            ramp_rate_per_s: 0.1,
            hold_ms: 1000,
            ..cfg(Kind::Ramp)
        };
        let (p, end) = program(&c);
        // to 0.2 (500 ms ramp + 500 settle), up over 6 s, hold 1 s, down over 6 s, hold 1 s
        assert_eq!(p.len(), 3);
        assert_eq!((p[1].at_ms, p[1].level, p[1].ramp_ms), (1000, 0.8, 6000));
        assert_eq!((p[2].at_ms, p[2].ramp_ms), (8000, 6000));
        assert!((p[2].level - 0.2).abs() < 1e-12);
        assert_eq!(end, 15_000);
        // a slow leg is cut into pieces the 16-bit ramp can hold
        let c = ExperimentConfig {
            ramp_rate_per_s: 0.005,
            ..c
        };
        let (p, _) = program(&c);
        let up = &p[1..3];
        assert_eq!(p.len(), 5, "{p:?}");
        assert!((up[1].level - 0.8).abs() < 1e-12);
        assert_eq!(up.iter().map(|s| s.ramp_ms as u64).sum::<u64>(), 120_000);
        assert!((up[0].level - 0.5).abs() < 1e-12 && !up[0].announce && up[1].announce);
    }

    #[test]
    fn a_chirp_sweeps_log_about_its_level_within_its_amplitude() {
        let c = ExperimentConfig {
            levels: vec![0.5],
            chirp_f0_hz: 1.0,
            chirp_f1_hz: 16.0,
            chirp_s: 8.0,
            chirp_amplitude: 0.1,
            ..cfg(Kind::Chirp)
        };
        let (p, end) = program(&c);
        assert_eq!(p.len(), 1 + 800 + 1);
        assert!(p.iter().all(|s| (s.level - 0.5).abs() <= 0.1 + 1e-12));
        assert!(p[1..].iter().all(|s| s.ramp_ms == CHIRP_STEP_MS as u16));
        assert_eq!(end, 1000 + 8010 + 500);
        // equal time per octave: the instantaneous frequency dφ/dt/2π doubles every 2 s
        let f = |t: f64| {
            (chirp_phase(&c, t + 1e-6) - chirp_phase(&c, t)) / 1e-6 / std::f64::consts::TAU
        };
        for (t, want) in [(0.0, 1.0), (2.0, 2.0), (4.0, 4.0), (8.0, 16.0)] {
            assert!((f(t) - want).abs() < 1e-3 * want, "f({t}) = {}", f(t));
        }
    }

    /// A device that acknowledges every command at once: the staircase's SET_THROTTLEs go out
    /// at their times, holds announced, then the ramp down and DISARM.
    #[test]
    fn the_plan_sends_a_staircase_at_its_times_then_disarms() {
        use super::super::{Experiment, Notice, Output, Phase};
        use crate::protocol::{Ack, AckResult, Frame, Hello, Message};
        let c = ExperimentConfig {
            levels: vec![0.3, 0.5],
            hold_ms: 1000,
            ..cfg(Kind::Staircase)
        };
        let mut p = Experiment::new(c, 0).unwrap();
        let ack = |seq: u16, cmd_type: u8| Frame {
            seq: 0,
            msg: Message::Ack(Ack {
                cmd_seq: seq,
                cmd_type,
                result: AckResult::Ok,
                ack_flags: 0,
                t_us: 0,
            }),
        };
        let hello = Frame {
            seq: 0,
            msg: Message::Hello(Hello {
                proto_minor: 0,
                esc_protocol: crate::protocol::EscProtocol::None,
                fw_version: 1,
                boot_id: 7,
                t_us: 0,
                sample_rate_hz: 1000,
                channels: 1,
                motor_poles: 0,
                caps: 0,
                name: Hello::name_field("t"),
            }),
        };
        p.start(0);
        p.on_frame(&hello, 0);
        let (mut sets, mut reached) = (Vec::new(), Vec::new());
        let mut t = 0u64;
        while !p.is_over() && t < 10_000_000 {
            p.poll(t);
            while let Some(o) = p.next_output() {
                match o {
                    Output::Send { seq, msg } => {
                        if let Message::SetThrottle(s) = msg {
                            sets.push((t / 1000, s.level));
                        }
                        if msg.name() != "HEARTBEAT" {
                            p.on_frame(&ack(seq, msg.msg_type()), t);
                        }
                    }
                    Output::Notice(Notice::LevelReached { level, .. }) => reached.push(level),
                    Output::Notice(_) => {}
                }
            }
            t += 1000;
        }
        assert_eq!(p.phase(), Phase::Done);
        assert_eq!(sets, vec![(0, 3000), (1000, 5000), (2000, 3000), (3000, 0)]);
        assert_eq!(reached, vec![0.3, 0.5, 0.3]);
    }

    #[test]
    fn pulses_have_no_program() {
        assert!(program(&cfg(Kind::Pulses)).0.is_empty());
    }
}
