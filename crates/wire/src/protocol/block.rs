//! Splitting a byte stream at the `0x00` delimiters of docs/PROTOCOL.md §2 into COBS blocks, in one
//! fixed buffer of 254 bytes (the longest legal block): the one splitter of both directions
//! (the host's [`Decoder`](super::Decoder), the device's command reader).
//!
//! Bytes are appended until a delimiter; the block is then handed out (mutable, so that it can
//! be COBS-decoded in place) and the buffer starts afresh. More than 254 bytes before a
//! delimiter are not even stored: the block is reported as [`Block::Oversize`]. Bytes after the
//! last delimiter wait for the next push.

use super::encode::MAX_ENCODED;

/// What lay between two delimiters.
#[derive(Debug, PartialEq, Eq)]
pub enum Block<'a> {
    /// Nothing (two `0x00` in a row): ignored by the protocol.
    Empty,
    /// More than 254 bytes: dropped.
    Oversize,
    /// A candidate frame (still COBS-encoded), at most 254 bytes.
    Data(&'a mut [u8]),
}

/// Fixed-buffer splitter (see the [module documentation](self)). Never allocates.
#[derive(Debug, Clone)]
pub struct BlockSplitter {
    buf: [u8; MAX_ENCODED],
    len: usize,
    overflow: bool,
}

impl Default for BlockSplitter {
    fn default() -> Self {
        Self::new()
    }
}

impl BlockSplitter {
    /// An empty splitter.
    pub fn new() -> Self {
        Self {
            buf: [0; MAX_ENCODED],
            len: 0,
            overflow: false,
        }
    }

    /// Bytes of an unfinished block waiting for their delimiter.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Forget an unfinished block.
    pub fn reset(&mut self) {
        self.len = 0;
        self.overflow = false;
    }

    /// Feed `bytes`; `on_block` gets every block completed by a delimiter, in order.
    pub fn push(&mut self, bytes: &[u8], mut on_block: impl FnMut(Block<'_>)) {
        let mut rest = bytes;
        while let Some(i) = find_zero(rest) {
            self.append(&rest[..i]);
            rest = &rest[i + 1..];
            on_block(self.take());
        }
        self.append(rest);
    }

    /// Feed bytes up to the first delimiter: the block it completes (then the bytes after it
    /// are returned), or `None` when `bytes` holds no delimiter (all of it was appended).
    pub fn push_until_block<'b>(&mut self, bytes: &'b [u8]) -> Option<(Block<'_>, &'b [u8])> {
        match find_zero(bytes) {
            Some(i) => {
                self.append(&bytes[..i]);
                Some((self.take(), &bytes[i + 1..]))
            }
            None => {
                self.append(bytes);
                None
            }
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

    /// A delimiter arrived: the buffered block, and the buffer starts afresh.
    fn take(&mut self) -> Block<'_> {
        let (len, overflow) = (self.len, self.overflow);
        self.reset();
        if overflow {
            Block::Oversize
        } else if len == 0 {
            Block::Empty
        } else {
            Block::Data(&mut self.buf[..len])
        }
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

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn blocks_empty_and_oversize_are_told_apart_across_pushes() {
        let mut s = BlockSplitter::new();
        let mut got = Vec::new();
        let mut on = |b: Block<'_>| {
            got.push(match b {
                Block::Empty => "empty".to_string(),
                Block::Oversize => "oversize".to_string(),
                Block::Data(d) => format!("{d:?}"),
            })
        };
        s.push(&[1, 2], &mut on);
        s.push(&[3, 0, 0], &mut on);
        s.push(&[7u8; 300], &mut on);
        s.push(&[0, 9], &mut on);
        assert_eq!(got, ["[1, 2, 3]", "empty", "oversize"]);
        assert_eq!(s.pending(), 1);
    }
}
