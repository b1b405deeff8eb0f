//! `propid replay` (not written yet).

use super::CliError;

/// Arguments of `propid replay`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `propid replay`.
pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::Usage(
        "propid replay is not implemented yet".into(),
    ))
}
