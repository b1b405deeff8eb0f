//! `propid sim` (not written yet).

use super::CliError;

/// Arguments of `propid sim`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `propid sim`.
pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::Usage("propid sim is not implemented yet".into()))
}
