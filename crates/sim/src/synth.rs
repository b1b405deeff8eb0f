//! Synthetic experiments for the diagnosis tests and the detection table: random plants, a
//! random hidden effect, and a pulse experiment over several operating points, generated
//! in-process with the simulated plant ([`crate::plant::Plant`], no pty).
//!
//! The experiment (sample period 2 ms): five operating points (throttle 0.50, 0.35, 0.65, 0.42,
//! 0.58), each held for 3 s; after 0.3 s of settling, pulses every 0.3 s, 10 samples (20 ms)
//! wide, with amplitudes cycling through +0.05, −0.05, +0.10, −0.10. 7 500 samples in all.

use propid_numerics::EffectName;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use crate::effects::{
    AsymmetricDynamics, BaselineDrift, DeadTime, EffectsConfig, ExtraMode, PeriodicDisturbance,
    Saturation, SaturationSignal, StaticNonlinearity, StiffnessNonlinearity, SupplySag,
};
use crate::plant::{Plant, PlantConfig, PlantError};

/// Sample period of the synthetic experiments, seconds.
pub const DT_S: f64 = 0.002;
/// Operating points of the experiment, throttle.
pub const LEVELS: [f64; 5] = [0.5, 0.35, 0.65, 0.42, 0.58];
/// Pulse amplitudes, cycled.
pub const AMPLITUDES: [f64; 4] = [0.05, -0.05, 0.1, -0.1];

/// The throttle sequence of the experiment (see the module doc).
pub fn throttle_plan() -> Vec<f64> {
    throttle_plan_at(DT_S)
}

/// [`throttle_plan`] sampled every `dt_s` seconds (pulses `round(0.02 / dt_s)` samples wide).
pub fn throttle_plan_at(dt_s: f64) -> Vec<f64> {
    let per_level = (3.0 / dt_s).round() as usize;
    let settle = (0.3 / dt_s).round() as usize;
    let spacing = (0.3 / dt_s).round() as usize;
    let width = ((0.02 / dt_s).round() as usize).max(1);
    let mut u = Vec::with_capacity(per_level * LEVELS.len());
    for &level in &LEVELS {
        for k in 0..per_level {
            let mut x = level;
            if k >= settle && (k - settle) % spacing < width && k + spacing < per_level {
                x += AMPLITUDES[((k - settle) / spacing) % AMPLITUDES.len()];
            }
            u.push(x);
        }
    }
    u
}

/// Signals measured in a synthetic experiment.
#[derive(Debug, Clone)]
pub struct Measured {
    /// Throttle commanded.
    pub u: Vec<f64>,
    /// Thrust measured, N.
    pub y: Vec<f64>,
    /// Supply voltage measured, V.
    pub voltage: Vec<f64>,
}

/// Runs the plant through `plan` (settled at the first throttle) with noise seed `seed`.
pub fn run(cfg: &PlantConfig, plan: &[f64], seed: u64) -> Result<Measured, PlantError> {
    let mut plant = Plant::new(cfg, DT_S, seed)?;
    plant.settle(plan.first().copied().unwrap_or(0.0));
    let mut out = Measured {
        u: Vec::with_capacity(plan.len()),
        y: Vec::with_capacity(plan.len()),
        voltage: Vec::with_capacity(plan.len()),
    };
    for &u in plan {
        let m = plant.step(u);
        out.u.push(u);
        out.y.push(m.thrust_n);
        out.voltage.push(m.voltage_v);
    }
    Ok(out)
}

/// A random plant: `fn` 5..15 Hz, `ζ` 0.3..0.9 (underdamped) or 1.2..2.0 (overdamped, every
/// other seed), gain 8..16 N per unit throttle, noise 0.01..0.02 N RMS, 1 mN quantum.
pub fn random_plant(rng: &mut StdRng, overdamped: bool) -> PlantConfig {
    PlantConfig {
        fn_hz: rng.gen_range(5.0..15.0),
        zeta: if overdamped {
            rng.gen_range(1.2..2.0)
        } else {
            rng.gen_range(0.3..0.9)
        },
        gain_n_per_throttle: rng.gen_range(8.0..16.0),
        noise_rms_n: rng.gen_range(0.01..0.02),
        quantum_n: 0.001,
        ..PlantConfig::default()
    }
}

/// Switches on effect `name` in `cfg` with random parameters (ranges in the source, documented
/// in `docs/diagnose.md`).
pub fn hide_effect(cfg: &mut PlantConfig, name: EffectName, rng: &mut StdRng) {
    let mut e = EffectsConfig::default();
    match name {
        EffectName::DeadTime => {
            e.dead_time = Some(DeadTime {
                delay_s: rng.gen_range(0.01..0.05),
            })
        }
        EffectName::StaticNonlinearity => {
            let exponent = if rng.gen_bool(0.5) {
                rng.gen_range(1.5..2.5)
            } else {
                rng.gen_range(0.5..0.7)
            };
            e.static_nonlinearity = Some(StaticNonlinearity { exponent });
        }
        EffectName::ExtraMode => {
            let lo = (3.0 * cfg.fn_hz).max(25.0);
            e.extra_mode = Some(ExtraMode {
                fn_hz: rng.gen_range(lo..80.0),
                zeta: rng.gen_range(0.02..0.08),
                gain: 1.0,
            });
        }
        EffectName::BaselineDrift => {
            let r: f64 = rng.gen_range(0.01..0.03);
            e.baseline_drift = Some(BaselineDrift {
                rate_per_s: if rng.gen_bool(0.5) { r } else { -r },
            });
        }
        EffectName::PeriodicDisturbance => {
            e.periodic_disturbance = Some(PeriodicDisturbance {
                freq_hz: rng.gen_range(20.0..90.0),
                amplitude: rng.gen_range(0.03..0.1),
                phase_rad: rng.gen_range(0.0..std::f64::consts::TAU),
            });
        }
        EffectName::SupplySag => {
            cfg.discharge_v_per_s = 0.1;
            e.supply_sag = Some(SupplySag {
                gain_per_volt: rng.gen_range(0.03..0.1),
            });
        }
        EffectName::Saturation => {
            e.saturation = Some(Saturation {
                level: rng.gen_range(0.6..0.7),
                signal: SaturationSignal::Throttle,
            });
        }
        EffectName::AsymmetricDynamics => {
            // Spin-down slower (drag only) or, every other draw, faster (active braking), by a
            // ratio of 1.6..2.5, around a geometric mean time scale of 0.8..1.25.
            let ratio: f64 = rng.gen_range(1.6..2.5);
            let ratio = if rng.gen_bool(0.5) {
                ratio
            } else {
                1.0 / ratio
            };
            let mean: f64 = rng.gen_range(0.8..1.25);
            e.asymmetric_dynamics = Some(AsymmetricDynamics {
                up_scale: mean / ratio.sqrt(),
                down_scale: mean * ratio.sqrt(),
            });
        }
        EffectName::StiffnessNonlinearity => {
            // ε T_r² (the relative stiffening at the reference thrust T_r = K/2): 0.08..0.25
            // hardening, or −0.06..−0.03 softening (the core keeps a steady state up to the
            // top of the experiment).
            let s = if rng.gen_bool(0.5) {
                rng.gen_range(0.08..0.25)
            } else {
                rng.gen_range(-0.06..-0.03)
            };
            let t_ref = cfg.reference_thrust_n();
            e.stiffness_nonlinearity = Some(StiffnessNonlinearity {
                k3_per_k1: s / (t_ref * t_ref),
            });
        }
        // Effects of the stand baseline only: this 2nd-order plant has no sensor per channel
        // nor a rotor whose lag follows its speed; nothing is hidden.
        EffectName::SensorLag | EffectName::SpeedDependentTau => {}
    }
    cfg.effects = e;
}

/// Case `i` of effect `name` (`None`: a clean plant): a seeded random plant (overdamped for odd
/// `i`) with the effect hidden, and its measured signals. The seed follows the length of the
/// effect's published name (`"clean"` for none).
pub fn case(name: Option<EffectName>, i: u64) -> Result<(PlantConfig, Measured), PlantError> {
    let len = name.map_or("clean", EffectName::as_str).len();
    let seed = 0x5eed_0000 + i * 7919 + len as u64 * 104_729;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut cfg = random_plant(&mut rng, i % 2 == 1);
    if let Some(name) = name {
        hide_effect(&mut cfg, name, &mut rng);
    }
    let m = run(&cfg, &throttle_plan(), seed ^ 0xabcdef)?;
    Ok((cfg, m))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_has_pulses_of_every_amplitude_at_every_level() {
        let u = throttle_plan();
        assert_eq!(u.len(), 7500);
        for (i, &level) in LEVELS.iter().enumerate() {
            let seg = &u[i * 1500..(i + 1) * 1500];
            for a in AMPLITUDES {
                assert!(
                    seg.iter().any(|&x| (x - level - a).abs() < 1e-12),
                    "level {level} amp {a}"
                );
            }
        }
    }
}
