//! # propid — identify a motor + propeller on a thrust stand
//!
//! propid turns test-stand data into the linear models a flight-controller designer needs
//! (natural frequency, damping, time constants, DC gain around an operating point), and says
//! when a 2nd-order model is not enough and why.
//!
//! The crate is layered, pure core first, thin shell last:
//! - [`core`]: the identification core: Markov parameters from pulse experiments, the
//!   Eigensystem Realization Algorithm (Juang & Pappa 1985), accuracy indicators, fixed-size
//!   workspaces. No I/O.
//! - [`protocol`]: the TSP/1 wire format (COBS frames with CRC, CSV fallback), sans-IO.
//! - [`record`]: the uniformly sampled record that readers produce and the core consumes.
//! - [`ingest`]: files into records (TSP/1 recordings, CSV exports of commercial stands).
//! - [`sim`]: the simulated stand (plant, firmware state machine, pseudo-terminal).
//! - [`daemon`]: sources, sampler and worker threads, publishing, shutdown.
//! - [`diagnose`]: what the 2nd-order simulation gets wrong, and why.
//! - [`cli`]: the subcommands of the `propid` binary.

pub mod cli;
pub mod core;
pub mod daemon;
pub mod diagnose;
pub mod experiment;
pub mod ingest;
pub mod protocol;
pub mod record;
pub mod sim;
