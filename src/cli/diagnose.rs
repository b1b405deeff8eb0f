//! `propid diagnose` (not written yet).

use super::CliError;

/// Arguments of `propid diagnose`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `propid diagnose`.
pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::Usage(
        "propid diagnose is not implemented yet".into(),
    ))
}
