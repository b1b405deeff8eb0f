//! TSP/1, the thrust-stand serial protocol (`docs/PROTOCOL.md`), sans-IO.
//!
//! - [`crc`]: CRC-16/MCRF4XX; [`cobs`]: byte stuffing;
//! - [`message`]: every message of both directions as typed `Copy` structs, each in one file
//!   with its type code, layout, CSV form and vector ([`WireMessage`]), registered in one list
//!   that makes [`Message`]; [`Frame`]; [`payload`]: the little-endian layout primitives;
//! - [`encode`]: [`encode_frame`] into a caller buffer (no allocation);
//! - [`block`]: the stream split at every `0x00` into COBS blocks (one fixed buffer);
//! - [`decoder`]: [`check_block`], the one integrity check of a frame (COBS, length, CRC),
//!   and [`Decoder`], a fixed-buffer decoder with [`DecodeStats`] (one counter per kind of
//!   drop), resynchronising at every `0x00`;
//! - [`csv`]: the text fallback of §6, the one CSV dialect (lines, checksum, header names,
//!   rows, the bench's `#` lines, commands); [`detect`]: binary or CSV from the first bytes.
//!
//! Nothing here does I/O: callers push the bytes they read and write the bytes they are given,
//! so the serial source, the recording replay, the simulated stand and the tests share one code
//! path.

pub mod block;
pub mod cobs;
pub mod crc;
pub mod csv;
pub mod decoder;
pub mod detect;
pub mod encode;
pub mod error;
pub mod message;
pub mod payload;

/// The alias and unit table of the CSV dialect, under its former path.
pub use csv::columns as csv_columns;
/// The CSV commands, under their former path.
pub use csv::command as csv_command;

#[cfg(test)]
mod vectors;

pub use decoder::{check_block, decode_block, DecodeStats, Decoder, DropCounts, Frames, RawFrame};
pub use encode::{encode_frame, encode_raw, try_encode_frame, EncodeError, MAX_FRAME_LEN};
pub use error::DecodeError;
pub use message::{
    Ack, AckResult, Arm, EscProtocol, Event, EventCode, Frame, Hello, Impulse, Log, Message,
    Sample, SampleFlags, SetRate, SetThrottle, WireMessage,
};

/// Protocol major version carried in every frame (`ver`).
pub const VERSION: u8 = 1;
