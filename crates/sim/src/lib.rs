//! The simulated thrust stand.
//!
//! The stand's firmware side of TSP/1 (`../shared/PROTOCOL.md`) runs here against a simulated
//! motor + propeller, so that the daemon, its tests and `propid demo` exercise exactly the code
//! they would run against hardware. The layers, pure first:
//!
//! - [`firmware::Firmware`]: the device as a sans-IO state machine. Command bytes go in with the
//!   time they arrived, [`Firmware::advance`](firmware::Firmware::advance) runs the device clock
//!   (one SAMPLE per sample period, periodic HELLO, the watchdog), device frames come out.
//! - [`dynamics::Dynamics`]: what the firmware measures; the plant model (and its effects) behind
//!   a small trait so that the firmware's tests can use an exact, noise-free stand-in.
//! - [`faults::FaultInjector`]: bit flips, garbage bursts, dropped samples, stalls and hang-ups,
//!   applied to whole output frames so that every injected fault is counted exactly.
//! - [`pty`]: the runner that paces the firmware to its sample rate on a pseudo-terminal, in its
//!   own process (`propid sim`) or on a thread ([`pty::SimHandle`]).
//! - [`record`]: firmware + host experiment plan in a loop on a simulated clock, writing a
//!   recording faster than real time (`propid sim --record`).
//! - [`config::SimConfig`]: `config/sim.toml`, validated with the key and value named on refusal.
//!
//! Smaller pieces: [`rx`] classifies host frames (so refused ones can still be ACKed with their
//! seq), [`csv`] is the text dialect (`protocol = "csv"`), [`dedup`] the device's memory of its
//! last 8 commands, [`pace`] the monotonic clock, and the command semantics live in `execute`.
//! The [`plant`] and its [`effects`] are the diagnose part's model of the motor + propeller.

pub mod config;
pub mod csv;
pub mod dedup;
pub mod dynamics;
pub mod effects;
mod execute;
pub mod faults;
pub mod firmware;
pub mod pace;
pub mod plant;
pub mod pty;
pub mod record;
pub mod rx;
pub mod synth;

#[cfg(test)]
mod experiment_tests;

pub use config::{ConfigError, SimConfig};

/// The boot id of boot number `boot` of a stand seeded with `seed`: random-looking, different
/// for every boot, the same for the same seed (so runs are reproducible).
pub fn boot_id(seed: u64, boot: u64) -> u32 {
    use rand::{Rng, SeedableRng};
    let mut rng =
        rand::rngs::StdRng::seed_from_u64(seed ^ boot.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    rng.gen::<u32>() | 1
}

/// What can go wrong in the simulated stand.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The configuration was refused.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The plant model refused its parameters.
    #[error("plant model: {0}")]
    Plant(String),
    /// The pseudo-terminal could not be created or used.
    #[error("pseudo-terminal: {0}")]
    Pty(String),
    /// Reading or writing a file or the terminal failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The host-side experiment refused its configuration.
    #[error("experiment: {0}")]
    Experiment(String),
}

impl SimError {
    /// An I/O error with what was being done.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        SimError::Io {
            context: context.into(),
            source,
        }
    }
}
