//! The simulated thrust stand.
//!
//! The stand's firmware side of TSP/1 (`docs/PROTOCOL.md`) runs here against a simulated
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
//! - [`plant_pipe`]: the plant alone, one step per line, for the reference firmware running in
//!   an emulator (`propid sim --plant-pipe`, `firmware/harness`).
//! - [`config::SimConfig`]: `config/sim.toml`, validated with the key and value named on refusal.
//!
//! Smaller pieces: [`rx`] classifies host frames (so refused ones can still be ACKed with their
//! seq), [`csv`] is the text dialect (`protocol = "csv"`), [`dedup`] the device's memory of its
//! last 8 commands, [`pace`] the monotonic clock, and the command semantics live in `execute`.
//! The [`plant`] and its [`effects`] are the diagnose part's model of the motor + propeller.

pub mod calibrate;
pub mod config;
pub mod csv;
pub mod dedup;
pub mod delay_line;
pub mod dynamics;
pub mod effects;
mod execute;
pub mod faults;
pub mod firmware;
pub mod pace;
pub mod plant;
pub mod plant_pipe;
pub mod pty;
pub mod record;
pub mod rx;
pub mod stand_cases;
pub mod synth;
pub mod truth;
pub mod walkthrough;

#[cfg(test)]
mod experiment_tests;

pub use config::{ConfigError, SimConfig};
pub use plant::PlantError;
pub use pty::PtyError;
pub use record::ExperimentError;

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
    Plant(#[from] PlantError),
    /// The pseudo-terminal could not be created or used.
    #[error("pseudo-terminal: {0}")]
    Pty(#[from] PtyError),
    /// Reading or writing a file or the terminal failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The host-side experiment of a recording cannot run (protocol, length or plan refused).
    #[error("experiment: {0}")]
    Experiment(#[from] ExperimentError),
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

#[cfg(test)]
mod tests {
    use std::error::Error as _;

    use super::*;
    use crate::config::WireProtocol;
    use crate::dynamics::PlantDynamics;
    use crate::plant::PlantConfig;

    /// Each refusal keeps the message it had when the causes were strings, and carries the
    /// typed cause.
    #[test]
    fn errors_keep_their_messages_and_carry_typed_causes() {
        let mut sink = Vec::new();
        let mut cfg = SimConfig::default();
        cfg.stand.protocol = WireProtocol::Csv;
        let e = record::record(&cfg, 1.0, &mut sink).unwrap_err();
        assert!(matches!(e, SimError::Experiment(ExperimentError::NotTsp)));
        assert_eq!(
            e.to_string(),
            "experiment: record mode runs the TSP/1 experiment plan: set stand.protocol = \"tsp\""
        );
        let e = record::record(&SimConfig::default(), -1.0, &mut sink).unwrap_err();
        assert_eq!(
            e.to_string(),
            "experiment: --seconds -1: must be in (0, 86400]"
        );
        let mut cfg = SimConfig::default();
        cfg.experiment.levels.clear();
        let e = record::record(&cfg, 1.0, &mut sink).unwrap_err();
        let SimError::Experiment(ExperimentError::Plan(plan)) = &e else {
            panic!("{e:?}")
        };
        assert_eq!(plan.key, "levels.len()");
        assert_eq!(e.to_string(), format!("experiment: {plan}"));

        let plant = PlantConfig {
            fn_hz: f64::NAN,
            ..PlantConfig::default()
        };
        let Err(e) = PlantDynamics::new(&plant, 1e-3, 0) else {
            panic!("a NaN fn_hz is refused")
        };
        let cause = e.source().and_then(|s| s.downcast_ref::<PlantError>());
        assert!(
            matches!(
                cause,
                Some(PlantError::InvalidParameter {
                    key: "plant.fn_hz",
                    ..
                })
            ),
            "{e:?}"
        );
        assert_eq!(
            e.to_string(),
            "plant model: plant parameter `plant.fn_hz` = NaN is invalid: must be > 0 and below \
             the Nyquist frequency"
        );

        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("not-a-link");
        std::fs::write(&file, "").unwrap();
        let e = pty::point_link(&file, dir.path()).unwrap_err();
        assert!(matches!(&e, SimError::Pty(PtyError::LinkNotSymlink(p)) if *p == file));
        assert_eq!(
            e.to_string(),
            format!(
                "pseudo-terminal: --link {}: exists and is not a symlink",
                file.display()
            )
        );

        let e = SimConfig::from_toml_str("[stand]\nsample_rate_hz = \"fast\"\n", "t").unwrap_err();
        let cause = e.source().and_then(|s| s.downcast_ref::<toml::de::Error>());
        assert_eq!(e.to_string(), format!("t: {}", cause.unwrap()));
    }
}
