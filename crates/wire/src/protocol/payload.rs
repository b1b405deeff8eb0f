//! The primitives of every TSP/1 payload layout (docs/PROTOCOL.md §3, §4): little-endian
//! integers and IEEE-754 binary32 floats at fixed offsets, read by [`u16_at`], [`u32_at`],
//! [`f32_at`] and written by [`Writer`]. Each message's own layout is its
//! [`WireMessage`](super::message::WireMessage) implementation.

/// Largest payload that fits a 253-byte body: 253 − 4 (ver, type, seq) − 2 (crc).
pub const MAX_PAYLOAD: usize = 247;

/// The `u16` at offset `o` (the caller checked the length).
pub fn u16_at(p: &[u8], o: usize) -> u16 {
    u16::from_le_bytes([p[o], p[o + 1]])
}

/// The `u32` at offset `o` (the caller checked the length).
pub fn u32_at(p: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([p[o], p[o + 1], p[o + 2], p[o + 3]])
}

/// The `f32` at offset `o` (the caller checked the length).
pub fn f32_at(p: &[u8], o: usize) -> f32 {
    f32::from_bits(u32_at(p, o))
}

/// A little-endian writer over a payload buffer of [`MAX_PAYLOAD`] bytes (every message fits:
/// the longest, LOG, is 1 + 200 bytes).
pub struct Writer<'a> {
    out: &'a mut [u8; MAX_PAYLOAD],
    n: usize,
}

impl<'a> Writer<'a> {
    /// A writer at the start of `out`.
    pub fn new(out: &'a mut [u8; MAX_PAYLOAD]) -> Self {
        Self { out, n: 0 }
    }
    /// Bytes written so far.
    pub fn len(&self) -> usize {
        self.n
    }
    /// True when nothing was written.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
    /// Raw bytes.
    pub fn bytes(&mut self, b: &[u8]) {
        self.out[self.n..self.n + b.len()].copy_from_slice(b);
        self.n += b.len();
    }
    /// One byte.
    pub fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    /// A little-endian `u16`.
    pub fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    /// A little-endian `u32`.
    pub fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    /// A little-endian binary32.
    pub fn f32(&mut self, v: f32) {
        self.bytes(&v.to_le_bytes());
    }
}
