//! Why a frame was dropped: one variant per counted kind (see
//! [`DropCounts`](super::decoder::DropCounts)).

use super::cobs::CobsError;

/// A frame between two `0x00` delimiters that could not be decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The bytes are not valid COBS.
    #[error("COBS error: {0}")]
    Cobs(CobsError),
    /// The CRC over the body does not match.
    #[error("CRC mismatch: frame says {received:#06x}, computed {computed:#06x}")]
    Crc {
        /// CRC carried by the frame.
        received: u16,
        /// CRC computed over the body.
        computed: u16,
    },
    /// `ver` is not 1.
    #[error("unsupported protocol version {0}")]
    BadVersion(u8),
    /// The decoded body is shorter than 6 bytes (ver, type, seq, crc).
    #[error("frame of {0} bytes is shorter than 6")]
    ShortFrame(usize),
    /// The payload is shorter than its type's minimum.
    #[error("payload of type {msg_type:#04x} has {len} bytes, needs {min}")]
    ShortPayload {
        /// Message type.
        msg_type: u8,
        /// Payload length received.
        len: usize,
        /// Minimum for the type.
        min: usize,
    },
    /// More than 254 encoded bytes between two delimiters.
    #[error("frame longer than 254 encoded bytes")]
    Oversize,
    /// A type code this version does not know.
    #[error("unknown message type {0:#04x}")]
    UnknownType(u8),
}
