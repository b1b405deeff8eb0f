//! What the firmware measures, behind a small trait: the plant model of
//! [`plant`](super::plant) (with its effects) in normal use, exact stand-ins in tests.

use super::plant::{Measurement, Plant, PlantConfig};
use super::SimError;

/// A stand whose throttle is held for one sample period at a time.
///
/// `step(u)` is called at the start of a sample period with the throttle held during it and
/// returns what the sensors read *at that instant*, before `u` acts (the plant has no
/// feed-through). The firmware calls it at the boundary between periods `k−1` and `k` with
/// `u_k`, so the reading is the end-of-period measurement of sample `k−1` (docs/PROTOCOL.md §3).
pub trait Dynamics: Send {
    /// Holds `throttle` (0..1) for the next period; returns the reading at its start.
    fn step(&mut self, throttle: f64) -> Measurement;

    /// Changes the sample period (SET_RATE; only while disarmed).
    fn set_sample_period(&mut self, dt_s: f64) -> Result<(), SimError>;
}

/// The plant model with its configuration and seed, rebuilt when the sample rate changes.
#[derive(Debug, Clone)]
pub struct PlantDynamics {
    plant: Plant,
    seed: u64,
}

impl PlantDynamics {
    /// A plant at rest sampled every `dt_s` seconds.
    pub fn new(cfg: &PlantConfig, dt_s: f64, seed: u64) -> Result<Self, SimError> {
        let plant = Plant::new(cfg, dt_s, seed)?;
        Ok(PlantDynamics { plant, seed })
    }

    /// The plant.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }
}

impl Dynamics for PlantDynamics {
    fn step(&mut self, throttle: f64) -> Measurement {
        self.plant.step(throttle)
    }

    fn set_sample_period(&mut self, dt_s: f64) -> Result<(), SimError> {
        let cfg = self.plant.config().clone();
        self.seed = self.seed.wrapping_add(1);
        self.plant = Plant::new(&cfg, dt_s, self.seed)?;
        Ok(())
    }
}

/// An exact, memoryless stand-in for tests: thrust = `gain` × the throttle of the previous
/// period (what a plant with `C B = gain`, `A = 0` would read), other channels fixed.
#[derive(Debug, Clone, Copy)]
pub struct EchoStand {
    /// Thrust per unit throttle, N.
    pub gain: f64,
    last: f64,
}

impl EchoStand {
    /// An echo stand with `gain` N per unit throttle.
    pub fn new(gain: f64) -> Self {
        EchoStand { gain, last: 0.0 }
    }
}

impl Dynamics for EchoStand {
    fn step(&mut self, throttle: f64) -> Measurement {
        let thrust = self.gain * self.last;
        self.last = throttle;
        Measurement {
            thrust_n: thrust,
            torque_nm: 0.01 * thrust,
            rpm: 1000.0 * thrust,
            voltage_v: 16.0,
            current_a: 1.0,
            adc_saturated: false,
        }
    }

    fn set_sample_period(&mut self, _dt_s: f64) -> Result<(), SimError> {
        Ok(())
    }
}
