//! `propid walkthrough [--out DIR]`: reproduces the ERA derivation the project grew from on a
//! simulated noisy mass–spring–damper and writes SVG plots, a Markdown page tying them
//! together (`walkthrough.md`) and the identified against the true `m, d, k`
//! (`walkthrough.json`). The mathematics is in [`derivation`].

mod derivation;
mod page;
mod plot;

use std::path::PathBuf;

use super::CliError;
use derivation::{Derivation, Setup};

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
    let d = Derivation::run(setup).map_err(CliError::Identification)?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::io(format!("creating {}", args.out.display()), e))?;
    let files = page::plots(&d, &args.out).map_err(CliError::Identification)?;
    page::write(&d, &args.out, &files)?;
    let s = &d.setup;
    let msd = &d.report.mass_spring_damper;
    println!(
        "walkthrough written to {} ({} files)",
        args.out.display(),
        files.len() + 2
    );
    println!(
        "            true        identified (ERA, order {})",
        d.report.order
    );
    println!("m (kg)      {:<10.5}  {:.5}", s.m, msd.m);
    println!("d (N s/m)   {:<10.5}  {:.5}", s.d, msd.d);
    println!("k (N/m)     {:<10.5}  {:.5}", s.k, msd.k);
    Ok(())
}
