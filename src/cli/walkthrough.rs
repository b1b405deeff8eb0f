//! `propid walkthrough [--out DIR]`: reproduces the ERA derivation the project grew from on a
//! simulated noisy mass–spring–damper and writes SVG plots, a Markdown page tying them
//! together (`walkthrough.md`) and the identified against the true `m, d, k`
//! (`walkthrough.json`). The mathematics is in [`derivation`].

mod derivation;
mod page;
mod plot;

use std::fmt::Write as _;
use std::path::PathBuf;

use super::CliError;
use derivation::{Derivation, Setup};
use propid_numerics::{IdentError, SvdError};

/// Why the walkthrough could not be derived or drawn (`propid walkthrough` exits 4).
#[derive(Debug, thiserror::Error)]
pub enum WalkthroughError {
    /// The simulated set-up is out of range.
    #[error("{0}")]
    Setup(&'static str),
    /// The exact full-order model does not exist.
    #[error("H_1 is singular: no exact full-order model")]
    SingularH1,
    /// The SVD of the Hankel matrix failed.
    #[error("SVD of H_1: {0}")]
    Svd(#[source] SvdError),
    /// The noise distribution refused its standard deviation.
    #[error("noise: {0}")]
    Noise(#[source] rand_distr::NormalError),
    /// The identification core refused its set-up.
    #[error(transparent)]
    Core(IdentError),
    /// ERA failed on the measured Markov parameters.
    #[error("ERA: {0}")]
    Era(#[source] IdentError),
    /// The core's report does not hold a consistent `(A, B, C, D)`.
    #[error("the ERA report has inconsistent matrix sizes")]
    InconsistentReport,
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
    let d = Derivation::run(setup)?;
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
