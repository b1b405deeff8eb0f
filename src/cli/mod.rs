//! The subcommands of the `propid` binary. Each module holds its clap `Args` and a `run`
//! function; errors from every layer arrive as a [`CliError`] holding the layer's typed error,
//! which `main` turns into a message on stderr and an exit code ([`CliError::exit_code`]).

pub mod demo;
pub mod diagnose;
pub mod fleet;
pub mod identify;
pub mod kinds_report;
pub mod model_file;
pub mod read;
pub mod replay;
pub mod run;
pub mod sim;
pub mod stand_log;
pub mod stdout;
pub mod walkthrough;

pub use propid_report::columns_read;
/// The one file loader, by its old name.
pub use read as load;

use crate::daemon::source::SourceError;
use crate::daemon::{ConfigError, DaemonError};
use load::{LoadError, NoSteps};
use propid_diagnose::DiagnoseError;
use propid_numerics::identify::AnyError;
use propid_sim::SimError;
use walkthrough::WalkthroughError;

/// What went wrong: one variant per typed cause, each in the class of cause the user has to act
/// on ([`ExitClass`]), which gives the exit code. The messages are the layers' own, with the
/// context the command adds.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The command line is wrong.
    #[error(transparent)]
    Usage(#[from] UsageError),
    /// A file could not be read as the command asked (unreadable: [`CliError::Io`]).
    #[error(transparent)]
    Load(#[from] LoadError),
    /// A recording to replay could not be opened.
    #[error(transparent)]
    Recording(SourceError),
    /// A result could not be written as JSON.
    #[error(transparent)]
    Json(serde_json::Error),
    /// The diagnosis could not be written as JSON.
    #[error("JSON: {0}")]
    DiagnosisJson(#[source] serde_json::Error),
    /// The identification refused the data.
    #[error(transparent)]
    Identify(#[from] AnyError),
    /// A file without an input column is too short to find steps in.
    /// The model (printed) failed the quality checks of `propid_numerics::quality`.
    #[error(
        "the identified model fails the quality checks ({flaws}): it is not the plant's model \
         (printed for inspection with \"quality\")"
    )]
    ModelRejected {
        /// The checks it failed, by name.
        flaws: String,
    },
    #[error("{file}: too short to find steps in")]
    StepsTooShort {
        /// The file as given.
        file: String,
    },
    /// A file without an input column has no step to build the input from.
    #[error("{file}: no input column and no step found in the response ({hint})")]
    NoInput {
        /// The file as given.
        file: String,
        /// Why no step was found.
        cause: NoSteps,
        /// What the user can do.
        hint: &'static str,
    },
    /// The diagnosis refused the data (bad input, or no identification).
    #[error(transparent)]
    Diagnose(#[from] DiagnoseError),
    /// The stand model could not be fitted on a log (`diagnose --sim-config`).
    #[error("stand model: {0}")]
    StandModel(#[from] propid_numerics::stand_model::fit::StandModelError),
    /// The walkthrough could not be derived or drawn.
    #[error(transparent)]
    Walkthrough(#[from] WalkthroughError),
    /// The daemon's configuration was refused.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The simulated stand's configuration was refused.
    #[error(transparent)]
    SimConfig(#[from] propid_sim::ConfigError),
    /// The simulated stand failed (configuration, pseudo-terminal or I/O).
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The in-process simulated stand of `propid demo` could not start.
    #[error("simulated stand: {0}")]
    SimulatedStand(#[source] SimError),
    /// The stand's serial port could not be opened.
    #[error(transparent)]
    Serial(SourceError),
    /// The daemon stopped with an error.
    #[error("{}", daemon_message(.0))]
    Daemon(#[from] DaemonError),
    /// Writing to stdout failed (a closed pipe: [`CliError::is_closed_pipe`], the quiet end).
    #[error("write error: {0}")]
    Stdout(#[source] std::io::Error),
    /// A model file is refused: another schema, changed after it was written, or invalid.
    #[error("model file refused: {0}")]
    Model(#[source] propid_model::ModelError),
    /// DATA lacks a channel the model needs (its input, an output, the supply voltage).
    #[error("{file}: lacks what the model needs: {detail}")]
    ModelData {
        /// The data file as given.
        file: String,
        /// What is missing.
        detail: String,
    },
    /// Reading or writing a file failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The OS error.
        source: std::io::Error,
    },
}

/// The class of a cause: what the user has to act on, and the exit code (docs/cli.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExitClass {
    /// The command line is wrong (exit 2).
    Usage = 2,
    /// An input file or stream is unreadable or has bad content (exit 3).
    Input = 3,
    /// The data does not support an identification (exit 4).
    Identification = 4,
    /// The configuration is refused (exit 5).
    Config = 5,
    /// The stand (serial link, device) failed (exit 6).
    Device = 6,
    /// Reading or writing a file failed (exit 7).
    Io = 7,
    /// The experiment plan ended on a fault (device reset, watchdog trip, refused command):
    /// the daemon stopped by itself (exit 8).
    PlanFault = 8,
    /// A model file is refused: another schema, tampered with, or invalid (exit 9).
    ModelFile = 9,
    /// The data lack a channel the model needs, or are sampled at another rate (exit 10).
    ModelData = 10,
}

/// A wrong command line, by option.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UsageError {
    /// `diagnose` with more than one `--output`.
    #[error("diagnose takes one --output")]
    OneOutput,
    /// `--estimation-fraction` outside 0.3..0.9.
    #[error("--estimation-fraction {0} is outside 0.3..0.9")]
    EstimationFraction(f64),
    /// `--seconds` not a positive number.
    #[error("--seconds {0}: must be > 0")]
    Seconds(f64),
    /// `--faults-for` not a positive number.
    #[error("--faults-for {0}: must be > 0")]
    FaultsFor(f64),
    /// `--record` without `--seconds`.
    #[error("--record needs --seconds S")]
    RecordNeedsSeconds,
    /// `--record-max-bytes` neither 0 nor in range.
    #[error("--record-max-bytes {0}: 0 (no limit) or 65536..=1125899906842624 bytes")]
    RecordMaxBytes(u64),
}

impl CliError {
    /// The class of the cause.
    pub fn class(&self) -> ExitClass {
        match self {
            CliError::Usage(_) | CliError::Load(load::LoadError::Option(_)) => ExitClass::Usage,
            CliError::Load(_)
            | CliError::Recording(_)
            | CliError::Json(_)
            | CliError::DiagnosisJson(_) => ExitClass::Input,
            CliError::Diagnose(e) if diagnose::is_input_error(e) => ExitClass::Input,
            CliError::Identify(_)
            | CliError::StepsTooShort { .. }
            | CliError::ModelRejected { .. }
            | CliError::NoInput { .. }
            | CliError::Diagnose(_)
            | CliError::StandModel(_)
            | CliError::Walkthrough(_) => ExitClass::Identification,
            CliError::Config(_) | CliError::SimConfig(_) => ExitClass::Config,
            CliError::Sim(e) => match e {
                SimError::Config(_) | SimError::Plant(_) | SimError::Experiment(_) => {
                    ExitClass::Config
                }
                SimError::Pty(_) => ExitClass::Device,
                SimError::Io { .. } => ExitClass::Io,
            },
            CliError::SimulatedStand(_) | CliError::Serial(_) => ExitClass::Device,
            CliError::Daemon(e) => match e {
                DaemonError::Config(_) => ExitClass::Config,
                DaemonError::Source(_) | DaemonError::LinkFailed { .. } => ExitClass::Device,
                DaemonError::Identify(_) => ExitClass::Identification,
                DaemonError::PlanHalted => ExitClass::PlanFault,
                DaemonError::Io { .. }
                | DaemonError::Output { .. }
                | DaemonError::Serialize(_)
                | DaemonError::Signal(_)
                | DaemonError::ThreadPanicked { .. } => ExitClass::Io,
            },
            CliError::Io { .. } | CliError::Stdout(_) => ExitClass::Io,
            CliError::Model(_) => ExitClass::ModelFile,
            CliError::ModelData { .. } => ExitClass::ModelData,
        }
    }

    /// Whether this is stdout closed by its reader (EPIPE): `main` ends quietly with exit 0.
    pub fn is_closed_pipe(&self) -> bool {
        match self {
            CliError::Stdout(e) => stdout::is_closed_pipe(e),
            _ => false,
        }
    }

    /// The process exit code for this error.
    pub fn exit_code(&self) -> i32 {
        self.class() as i32
    }

    /// An I/O error with what was being done.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        CliError::Io {
            context: context.into(),
            source,
        }
    }
}

/// A daemon error as `propid` reports it: a failed identification set-up by the core's message,
/// a bug (serialisation, signal handler, panicked thread) prefixed with `propid: `, the rest by
/// the daemon's own message.
fn daemon_message(e: &DaemonError) -> String {
    match e {
        DaemonError::Identify(e) => e.to_string(),
        DaemonError::Serialize(_) | DaemonError::Signal(_) | DaemonError::ThreadPanicked { .. } => {
            format!("propid: {e}")
        }
        _ => e.to_string(),
    }
}

/// Parses `--http ADDR` ([`crate::daemon::config::http_address`]).
pub fn http_arg(text: &str) -> Result<std::net::SocketAddr, String> {
    crate::daemon::config::http_address(text).ok_or_else(|| {
        format!("{text:?}: a port (8080, :8080: 127.0.0.1) or an address (0.0.0.0:8080)")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Messages and exit codes as they were when the causes were strings.
    #[test]
    fn messages_and_exit_codes_are_kept() {
        let cases: Vec<(CliError, &str, i32)> = vec![
            (
                UsageError::Seconds(-1.0).into(),
                "--seconds -1: must be > 0",
                2,
            ),
            (
                LoadError::Empty {
                    file: "a.csv".into(),
                }
                .into(),
                "a.csv: the file is empty",
                3,
            ),
            (
                CliError::NoInput {
                    file: "a.csv".into(),
                    cause: NoSteps::TooShort,
                    hint: "give --input NAME",
                },
                "a.csv: no input column and no step found in the response (give --input NAME)",
                4,
            ),
            (
                DaemonError::Identify(propid_numerics::IdentError::NoPulse).into(),
                "no pulse found in the input (need short throttle pulses on top of a constant level)",
                4,
            ),
            (
                DaemonError::LinkFailed {
                    link: "/dev/ttyACM0".into(),
                }
                .into(),
                "link failed: /dev/ttyACM0 stopped acknowledging commands",
                6,
            ),
            (
                DaemonError::ThreadPanicked { thread: "worker" }.into(),
                "propid: internal error: the worker thread panicked",
                7,
            ),
            (
                DaemonError::io("bind socket /tmp/s", std::io::Error::other("busy")).into(),
                "bind socket /tmp/s: busy",
                7,
            ),
            (
                SimError::Pty(propid_sim::PtyError::NotOpened).into(),
                "pseudo-terminal: the simulator did not open a pty",
                6,
            ),
            (
                SimError::Plant(propid_sim::PlantError::InvalidParameter {
                    key: "plant.zeta",
                    value: 0.0,
                    reason: "must be in (0, 20]",
                })
                .into(),
                "plant model: plant parameter `plant.zeta` = 0 is invalid: must be in (0, 20]",
                5,
            ),
            (
                CliError::SimulatedStand(SimError::Pty(propid_sim::PtyError::NotOpened)),
                "simulated stand: pseudo-terminal: the simulator did not open a pty",
                6,
            ),
        ];
        for (e, message, code) in cases {
            assert_eq!((e.to_string().as_str(), e.exit_code()), (message, code));
        }
    }
}
