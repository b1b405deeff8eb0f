//! `propid identify` (not written yet).

use super::CliError;

/// Arguments of `propid identify`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `propid identify`.
pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::Usage(
        "propid identify is not implemented yet".into(),
    ))
}
