//! # propid-wire — the bench link without I/O
//!
//! Everything between the bytes a stand sends and the samples the identification consumes,
//! as pure state machines (bytes in, frames or samples out, a counter for every kind of drop):
//! - [`protocol`]: TSP/1 (COBS frames with CRC, messages, the fixed-buffer decoder and the
//!   encoder) and the one CSV dialect of docs/PROTOCOL.md §6 (data lines, comments, commands);
//! - [`stream`]: the device clock unwrapped, every sample placed at its index (gaps, duplicates,
//!   segments, events) and assembled into a [`record::Record`];
//! - [`record`]: the uniformly sampled record that readers produce and the core consumes;
//! - [`experiment`]: the host-side experiment plan (handshake, arm, levels, pulses).
//!
//! No file, port, thread or clock is touched here: the daemon and the simulated stand drive
//! these with bytes and times of their own.

pub mod experiment;
pub mod protocol;
pub mod record;
pub mod stream;
