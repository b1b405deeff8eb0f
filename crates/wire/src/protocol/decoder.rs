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

use super::cobs;
use super::crc::crc16_mcrf4xx;
use super::encode::MAX_ENCODED;
use super::error::DecodeError;
use super::message::Frame;
use super::payload;
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

/// Decode one COBS block (without its delimiter, at most 254 bytes) in place into a frame.
/// The checks and their order are those of the [module documentation](self).
pub fn decode_block(block: &mut [u8]) -> Result<Frame, DecodeError> {
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
    if body[0] != VERSION {
        return Err(DecodeError::BadVersion(body[0]));
    }
    let seq = u16::from_le_bytes([body[2], body[3]]);
    let msg = payload::parse(body[1], &body[4..n - 2])?;
    Ok(Frame { seq, msg })
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
#[derive(Debug, Clone)]
pub struct Decoder {
    buf: [u8; MAX_ENCODED],
    len: usize,
    overflow: bool,
    stats: DecodeStats,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder with an empty buffer and zero counters.
    pub fn new() -> Self {
        Self {
            buf: [0; MAX_ENCODED],
            len: 0,
            overflow: false,
            stats: DecodeStats::default(),
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> &DecodeStats {
        &self.stats
    }

    /// Bytes of an unfinished frame waiting for their delimiter.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Forget an unfinished frame (for instance after a reconnect); counters are kept.
    pub fn reset(&mut self) {
        self.len = 0;
        self.overflow = false;
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
        let mut rest = bytes;
        while let Some(i) = find_zero(rest) {
            self.append(&rest[..i]);
            rest = &rest[i + 1..];
            if let Some(r) = self.finish() {
                on_result(r);
            }
        }
        self.append(rest);
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

    fn append(&mut self, chunk: &[u8]) {
        if self.overflow || chunk.is_empty() {
            return;
        }
        let end = self.len + chunk.len();
        if end > MAX_ENCODED {
            self.overflow = true;
        } else {
            self.buf[self.len..end].copy_from_slice(chunk);
            self.len = end;
        }
    }

    /// A delimiter arrived: decode what is buffered and start afresh.
    fn finish(&mut self) -> Option<Result<Frame, DecodeError>> {
        let r = if self.overflow {
            Some(Err(DecodeError::Oversize))
        } else if self.len == 0 {
            self.stats.empty_frames += 1;
            None
        } else {
            Some(decode_block(&mut self.buf[..self.len]))
        };
        self.reset();
        match &r {
            Some(Ok(_)) => self.stats.frames_ok += 1,
            Some(Err(e)) => self.stats.dropped.count(e),
            None => {}
        }
        r
    }
}

/// Position of the first `0x00`, eight bytes at a time: a word `v` holds a zero byte iff
/// `(v − 0x01…01) & !v & 0x80…80 ≠ 0`, and the lowest set bit of that mask marks the first one
/// (little-endian; borrows only propagate upwards from a zero byte, so lower bytes are exact).
fn find_zero(s: &[u8]) -> Option<usize> {
    const LO: u64 = 0x0101_0101_0101_0101;
    const HI: u64 = 0x8080_8080_8080_8080;
    let mut words = s.chunks_exact(8);
    let mut base = 0;
    for w in &mut words {
        let v = u64::from_le_bytes([w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]]);
        let m = v.wrapping_sub(LO) & !v & HI;
        if m != 0 {
            return Some(base + (m.trailing_zeros() / 8) as usize);
        }
        base += 8;
    }
    words
        .remainder()
        .iter()
        .position(|&b| b == 0)
        .map(|i| base + i)
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
        while let Some(i) = find_zero(self.rest) {
            self.dec.append(&self.rest[..i]);
            self.rest = &self.rest[i + 1..];
            if let Some(Ok(f)) = self.dec.finish() {
                return Some(f);
            }
        }
        self.dec.append(self.rest);
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

#[cfg(test)]
mod tests {
    use super::find_zero;

    #[test]
    fn find_zero_matches_a_plain_search() {
        let mut v: Vec<u8> = (0..64).map(|i| 1 + (i * 37 % 255) as u8).collect();
        v[5] = 0x80; // high bits and 0x01 bytes around a zero must not confuse the word test
        v[6] = 0x01;
        assert_eq!(find_zero(&v), None);
        for z in 0..v.len() {
            let mut w = v.clone();
            w[z] = 0;
            if z + 3 < w.len() {
                w[z + 3] = 0;
            }
            for start in 0..4.min(w.len()) {
                let s = &w[start..];
                assert_eq!(
                    find_zero(s),
                    s.iter().position(|&b| b == 0),
                    "z={z} start={start}"
                );
            }
        }
    }
}
