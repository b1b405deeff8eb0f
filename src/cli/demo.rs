//! `propid demo` (not written yet).

use super::CliError;

/// Arguments of `propid demo`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `propid demo`.
pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::Usage("propid demo is not implemented yet".into()))
}
