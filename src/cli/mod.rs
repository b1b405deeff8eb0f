//! The subcommands of the `propid` binary. Each module holds its clap `Args` and a `run`
//! function; errors from every layer are mapped to a [`CliError`], which `main` turns into a
//! message on stderr and an exit code.

pub mod demo;
pub mod diagnose;
pub mod identify;
pub mod load;
pub mod replay;
pub mod run;
pub mod sim;
pub mod walkthrough;

/// What went wrong, by the class of cause the user has to act on. Each class has its own exit
/// code (see [`CliError::exit_code`]).
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The command line is wrong (exit 2).
    #[error("{0}")]
    Usage(String),
    /// An input file or stream is unreadable or has bad content (exit 3).
    #[error("{0}")]
    Input(String),
    /// The data does not support an identification (exit 4).
    #[error("{0}")]
    Identification(String),
    /// The configuration is refused (exit 5).
    #[error("{0}")]
    Config(String),
    /// The stand (serial link, device) failed (exit 6).
    #[error("{0}")]
    Device(String),
    /// Reading or writing a file failed (exit 7).
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The OS error.
        source: std::io::Error,
    },
}

impl CliError {
    /// The process exit code for this error.
    pub fn exit_code(&self) -> i32 {
        match self {
            CliError::Usage(_) => 2,
            CliError::Input(_) => 3,
            CliError::Identification(_) => 4,
            CliError::Config(_) => 5,
            CliError::Device(_) => 6,
            CliError::Io { .. } => 7,
        }
    }

    /// An I/O error with what was being done.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        CliError::Io {
            context: context.into(),
            source,
        }
    }
}
