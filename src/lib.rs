//! # propid — identify a motor + propeller on a thrust stand
//!
//! propid turns test-stand data into the linear models a flight-controller designer needs
//! (natural frequency, damping, time constants, DC gain around an operating point), and says
//! when a 2nd-order model is not enough and why.
//!
//! This is the application crate, the thin shell over three pure ones (the workspace's crate
//! graph is the architecture; `docs/ARCHITECTURE.md`):
//! - `propid-numerics`: the identification core (Markov parameters, Hankel operators, SVDs,
//!   ERA, OKID, model order, segmentation of a record). No I/O.
//! - `propid-wire`: the bench link without I/O (TSP/1, the CSV dialect, sample placement, the
//!   record, the experiment plan).
//! - `propid-sim`: the simulated stand and the test-case generators.
//!
//! Here, on top of them:
//! - [`ingest`]: files into records (TSP/1 recordings, CSV exports of commercial stands).
//! - [`daemon`]: sources, sampler and worker threads, publishing, shutdown.
//! - [`diagnose`]: what the 2nd-order simulation gets wrong, and why.
//! - [`input`]: reading an input file within a bound (1 GiB).
//! - [`plot`]: SVG figures more than one report draws (the stabilization diagram).
//! - [`cli`]: the subcommands of the `propid` binary.

pub mod cli;
pub mod daemon;
pub mod input;
pub use propid_report::plot;
