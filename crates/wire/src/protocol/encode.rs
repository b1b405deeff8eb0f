//! Frame encoder (docs/PROTOCOL.md §2), both directions, no allocation:
//! `wire = COBS(ver type seq payload crc) 0x00`, CRC-16/MCRF4XX over `ver..payload`, all
//! little-endian. The body is assembled on the stack, then COBS-encoded into the caller's buffer.

use super::cobs;
use super::crc::crc16_mcrf4xx;
use super::message::Message;
use super::payload::MAX_PAYLOAD;
use super::VERSION;

/// Largest body (`ver..crc`), bytes.
pub const MAX_BODY: usize = 253;
/// Largest COBS-encoded body, bytes (without the delimiter).
pub const MAX_ENCODED: usize = 254;
/// Largest wire frame including the trailing `0x00`: a buffer of this size always suffices.
pub const MAX_FRAME_LEN: usize = MAX_ENCODED + 1;

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    /// The output buffer is shorter than the frame needs.
    #[error("output buffer of {have} bytes, frame needs {need}")]
    BufferTooSmall {
        /// Bytes available.
        have: usize,
        /// Bytes needed.
        need: usize,
    },
    /// A raw payload longer than 247 bytes.
    #[error("payload of {0} bytes exceeds 247")]
    PayloadTooLong(usize),
}

/// Encode `msg` with link sequence number `seq` into `out`, delimiter included; returns the
/// number of bytes written. `out` of [`MAX_FRAME_LEN`] bytes always suffices; if `out` is too
/// small nothing is written and 0 is returned (use [`try_encode_frame`] to get the reason).
pub fn encode_frame(seq: u16, msg: &Message, out: &mut [u8]) -> usize {
    try_encode_frame(seq, msg, out).unwrap_or(0)
}

/// As [`encode_frame`], with a typed error when `out` is too small.
pub fn try_encode_frame(seq: u16, msg: &Message, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut pl = [0u8; MAX_PAYLOAD];
    let n = msg.write_payload(&mut pl);
    encode_raw(VERSION, msg.msg_type(), seq, &pl[..n], out)
}

/// Encode an arbitrary body (any `ver`, any `type`, any payload up to 247 bytes) into a wire
/// frame with a correct CRC. For fault injection and tests; normal senders use [`encode_frame`].
pub fn encode_raw(
    ver: u8,
    msg_type: u8,
    seq: u16,
    payload: &[u8],
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    if payload.len() > MAX_PAYLOAD {
        return Err(EncodeError::PayloadTooLong(payload.len()));
    }
    let mut body = [0u8; MAX_BODY];
    let n = 4 + payload.len();
    body[0] = ver;
    body[1] = msg_type;
    body[2..4].copy_from_slice(&seq.to_le_bytes());
    body[4..n].copy_from_slice(payload);
    let crc = crc16_mcrf4xx(&body[..n]);
    body[n..n + 2].copy_from_slice(&crc.to_le_bytes());
    let body = &body[..n + 2];
    let need = cobs::max_encoded_len(body.len()) + 1;
    if out.len() < need {
        return Err(EncodeError::BufferTooSmall {
            have: out.len(),
            need,
        });
    }
    let len = cobs::encode(body, out).map_err(|_| EncodeError::BufferTooSmall {
        have: out.len(),
        need,
    })?;
    out[len] = 0;
    Ok(len + 1)
}
