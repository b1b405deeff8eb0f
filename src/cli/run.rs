//! `propid run` (not written yet).

use super::CliError;

/// Arguments of `propid run`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `propid run`.
pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::Usage("propid run is not implemented yet".into()))
}
