//! The simulated stand's integration tests, one binary: the pty runner and recordings.

mod sim_pty;
mod sim_record;
