//! The sans-IO frame decoder: bytes in, frames out, every drop counted by kind.
//!
//! The decoder keeps one fixed buffer of 254 bytes (the longest legal COBS block) and no other
//! state than counters, so it never allocates. Bytes are appended until a `0x00` delimiter; the
//! block is then COBS-decoded in place and checked, in this order:
//!
//! 1. more than 254 bytes before the delimiter → `oversize` (the excess is not even stored);
//! 2. nothing before the delimiter → an empty frame, ignored (`empty_frames`);
//! 3. invalid COBS → `cobs_error`;
//! 4. decoded body shorter than 6 bytes → `short_frame`;
//! 5. CRC-16/MCRF4XX mismatch → `crc_error` (checked before `ver`: a damaged `ver` byte is a
//!    CRC error, only an intact frame of another version counts as `bad_version`);
//! 6. `ver != 1` → `bad_version`;
//! 7. unknown `type` → `unknown_type`;
//! 8. payload shorter than the type's minimum → `short_payload`.
//!
//! Whatever happens, decoding restarts after the delimiter, so the frame after a bad one is
//! never lost. Bytes after the last delimiter wait in the buffer for the next [`Decoder::push`].

use serde::{Deserialize, Serialize};

use super::block::{Block, BlockSplitter};
use super::cobs;
use super::crc::crc16_mcrf4xx;
use super::encode::MAX_ENCODED;
use super::error::DecodeError;
use super::message::{Frame, Message};
use super::VERSION;

/// Dropped frames, one counter per kind. Serialised as the daemon's `frames_dropped` object.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DropCounts {
    /// Invalid COBS.
    pub cobs_error: u64,
    /// CRC mismatch.
    pub crc_error: u64,
    /// Intact frame with `ver != 1`.
    pub bad_version: u64,
    /// Body shorter than 6 bytes.
    pub short_frame: u64,
    /// Payload shorter than its type's minimum.
    pub short_payload: u64,
    /// More than 254 encoded bytes between delimiters.
    pub oversize: u64,
    /// Unknown message type.
    pub unknown_type: u64,
}

impl DropCounts {
    /// Count one drop of the kind of `e`.
    pub fn count(&mut self, e: &DecodeError) {
        let c = match e {
            DecodeError::Cobs(_) => &mut self.cobs_error,
            DecodeError::Crc { .. } => &mut self.crc_error,
            DecodeError::BadVersion(_) => &mut self.bad_version,
            DecodeError::ShortFrame(_) => &mut self.short_frame,
            DecodeError::ShortPayload { .. } => &mut self.short_payload,
            DecodeError::Oversize => &mut self.oversize,
            DecodeError::UnknownType(_) => &mut self.unknown_type,
        };
        *c += 1;
    }

    /// All drops together.
    pub fn total(&self) -> u64 {
        self.cobs_error
            + self.crc_error
            + self.bad_version
            + self.short_frame
            + self.short_payload
            + self.oversize
            + self.unknown_type
    }
}

/// Decoder counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DecodeStats {
    /// Frames decoded and handed out.
    pub frames_ok: u64,
    /// Empty frames (two delimiters in a row), ignored as the protocol says.
    pub empty_frames: u64,
    /// Bytes pushed.
    pub bytes: u64,
    /// Dropped frames by kind.
    pub dropped: DropCounts,
}

/// A frame whose integrity holds (valid COBS, at least 6 bytes, CRC correct): its `ver`,
/// `type` and `seq` can be trusted, its version and payload are not checked yet. The device
/// side answers such a frame even when it refuses it (docs/PROTOCOL.md §4: VERSION, UNKNOWN_TYPE,
/// BAD_LENGTH); an unchecked block has nobody to answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawFrame<'a> {
    /// Protocol version byte.
    pub ver: u8,
    /// Message type byte.
    pub msg_type: u8,
    /// Sequence number.
    pub seq: u16,
    /// Payload (between `seq` and the CRC).
    pub payload: &'a [u8],
}

impl RawFrame<'_> {
    /// Checks 6–8 of the [module documentation](self): version, type, payload length.
    pub fn decode(&self) -> Result<Frame, DecodeError> {
        if self.ver != VERSION {
            return Err(DecodeError::BadVersion(self.ver));
        }
        let msg = Message::parse(self.msg_type, self.payload)?;
        Ok(Frame { seq: self.seq, msg })
    }
}

/// Checks 1 and 3–5 of the [module documentation](self) on one COBS block (without its
/// delimiter), decoding it in place: size, COBS, length, CRC. The one integrity check of TSP/1
/// frames, host and device side.
pub fn check_block(block: &mut [u8]) -> Result<RawFrame<'_>, DecodeError> {
    if block.len() > MAX_ENCODED {
        return Err(DecodeError::Oversize);
    }
    let n = cobs::decode_in_place(block).map_err(DecodeError::Cobs)?;
    let body = &block[..n];
    if n < 6 {
        return Err(DecodeError::ShortFrame(n));
    }
    let received = u16::from_le_bytes([body[n - 2], body[n - 1]]);
    let computed = crc16_mcrf4xx(&body[..n - 2]);
    if received != computed {
        return Err(DecodeError::Crc { received, computed });
    }
    Ok(RawFrame {
        ver: body[0],
        msg_type: body[1],
        seq: u16::from_le_bytes([body[2], body[3]]),
        payload: &body[4..n - 2],
    })
}

/// Decode one COBS block (without its delimiter, at most 254 bytes) in place into a frame.
/// The checks and their order are those of the [module documentation](self).
pub fn decode_block(block: &mut [u8]) -> Result<Frame, DecodeError> {
    check_block(block)?.decode()
}

/// Fixed-buffer TSP/1 frame decoder (see the [module documentation](self)).
///
/// ```
/// use propid_wire::protocol::{encode_frame, Decoder, Message, MAX_FRAME_LEN};
/// let mut wire = [0u8; MAX_FRAME_LEN];
/// let n = encode_frame(10, &Message::Stop, &mut wire);
/// let mut dec = Decoder::new();
/// let mut got = Vec::new();
/// dec.push(b"boot banner\r\n\0", |f| got.push(f)); // counted, dropped
/// dec.push(&wire[..n], |f| got.push(f));
/// assert_eq!(got.len(), 1);
/// assert_eq!(got[0].msg, Message::Stop);
/// assert_eq!(dec.stats().dropped.total(), 1);
/// ```
#[derive(Debug, Clone, Default)]
pub struct Decoder {
    blocks: BlockSplitter,
    stats: DecodeStats,
}

impl Decoder {
    /// A decoder with an empty buffer and zero counters.
    pub fn new() -> Self {
        Self::default()
    }

    /// The counters so far.
    pub fn stats(&self) -> &DecodeStats {
        &self.stats
    }

    /// Bytes of an unfinished frame waiting for their delimiter.
    pub fn pending(&self) -> usize {
        self.blocks.pending()
    }

    /// Forget an unfinished frame (for instance after a reconnect); counters are kept.
    pub fn reset(&mut self) {
        self.blocks.reset();
    }

    /// Feed `bytes`; `on_frame` is called for every valid frame, in order. Drops are counted.
    pub fn push(&mut self, bytes: &[u8], mut on_frame: impl FnMut(Frame)) {
        self.push_results(bytes, |r| {
            if let Ok(f) = r {
                on_frame(f)
            }
        });
    }

    /// Feed `bytes`; `on_result` gets every valid frame and every dropped one (as its error),
    /// in order. Empty frames are not reported. Counters are updated either way.
    pub fn push_results(
        &mut self,
        bytes: &[u8],
        mut on_result: impl FnMut(Result<Frame, DecodeError>),
    ) {
        self.stats.bytes += bytes.len() as u64;
        let stats = &mut self.stats;
        self.blocks.push(bytes, |b| {
            if let Some(r) = decode(b, stats) {
                on_result(r);
            }
        });
    }

    /// Iterate over the frames in `bytes` (drops counted, not yielded).
    ///
    /// ```
    /// # use propid_wire::protocol::Decoder;
    /// let mut dec = Decoder::new();
    /// for frame in dec.frames(&[0x03, 0x33, 0x34, 0x00]) {
    ///     println!("{frame:?}");
    /// }
    /// ```
    pub fn frames<'a>(&'a mut self, bytes: &'a [u8]) -> Frames<'a> {
        self.stats.bytes += bytes.len() as u64;
        Frames {
            dec: self,
            rest: bytes,
        }
    }
}

/// One block decoded and counted (`None` for an empty one).
fn decode(block: Block<'_>, stats: &mut DecodeStats) -> Option<Result<Frame, DecodeError>> {
    let r = match block {
        Block::Empty => {
            stats.empty_frames += 1;
            return None;
        }
        Block::Oversize => Err(DecodeError::Oversize),
        Block::Data(d) => decode_block(d),
    };
    match &r {
        Ok(_) => stats.frames_ok += 1,
        Err(e) => stats.dropped.count(e),
    }
    Some(r)
}

/// Iterator over the frames of one chunk, see [`Decoder::frames`].
#[derive(Debug)]
pub struct Frames<'a> {
    dec: &'a mut Decoder,
    rest: &'a [u8],
}

impl Iterator for Frames<'_> {
    type Item = Frame;

    fn next(&mut self) -> Option<Frame> {
        let Decoder { blocks, stats } = &mut *self.dec;
        while let Some((block, rest)) = blocks.push_until_block(self.rest) {
            self.rest = rest;
            if let Some(Ok(f)) = decode(block, stats) {
                return Some(f);
            }
        }
        self.rest = &[];
        None
    }
}

impl Drop for Frames<'_> {
    /// The rest of the chunk still goes through the decoder, so the stream stays in step;
    /// frames the caller did not take are counted in `frames_ok` but discarded. Iterate to the
    /// end (or use [`Decoder::push`]) to get them all.
    fn drop(&mut self) {
        for _ in self.by_ref() {}
    }
}
