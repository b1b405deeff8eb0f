//! `propid walkthrough` (not written yet).

use super::CliError;

/// Arguments of `propid walkthrough`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `propid walkthrough`.
pub fn run(_args: Args) -> Result<(), CliError> {
    Err(CliError::Usage(
        "propid walkthrough is not implemented yet".into(),
    ))
}
