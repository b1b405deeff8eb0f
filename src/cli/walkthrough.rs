//! `propid walkthrough [--out DIR]`: reproduces the ERA derivation the project grew from on a
//! simulated noisy mass–spring–damper and writes SVG plots, a Markdown page tying them
//! together (`walkthrough.md`) and the identified against the true `m, d, k`
//! (`walkthrough.json`). The mathematics is in [`propid_sim::walkthrough`].

mod page;
mod plot;

use std::fmt::Write as _;
use std::path::PathBuf;

use super::CliError;
use propid_sim::walkthrough::{Derivation, Setup, WalkthroughError as DerivationError};

/// Why the walkthrough could not be derived or drawn (`propid walkthrough` exits 4).
#[derive(Debug, thiserror::Error)]
pub enum WalkthroughError {
    /// The derivation failed ([`propid_sim::walkthrough`]).
    #[error(transparent)]
    Derivation(#[from] DerivationError),
    /// No singular value to draw.
    #[error("no singular values to plot")]
    NoSingularValues,
    /// Drawing an SVG failed.
    #[error("plot: {0}")]
    Plot(#[source] plotters::drawing::DrawingAreaErrorKind<std::io::Error>),
}

/// Arguments of `propid walkthrough`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Directory for the page and the plots (created if missing).
    #[arg(long, default_value = "walkthrough")]
    pub out: PathBuf,
    /// Seed of the simulated measurement noise.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
}

/// Runs `propid walkthrough`.
pub fn run(args: Args) -> Result<(), CliError> {
    let setup = Setup {
        seed: args.seed,
        ..Setup::default()
    };
    let d = Derivation::run(setup).map_err(WalkthroughError::from)?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::io(format!("creating {}", args.out.display()), e))?;
    let files = page::plots(&d, &args.out)?;
    page::write(&d, &args.out, &files)?;
    let s = &d.setup;
    let msd = &d.report.mass_spring_damper;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "walkthrough written to {} ({} files)",
        args.out.display(),
        files.len() + 2
    );
    let _ = writeln!(
        t,
        "            true        identified (ERA, order {})",
        d.report.order
    );
    let _ = writeln!(t, "m (kg)      {:<10.5}  {:.5}", s.m, msd.m);
    let _ = writeln!(t, "d (N s/m)   {:<10.5}  {:.5}", s.d, msd.d);
    let _ = writeln!(t, "k (N/m)     {:<10.5}  {:.5}", s.k, msd.k);
    super::stdout::write(&t)
}
