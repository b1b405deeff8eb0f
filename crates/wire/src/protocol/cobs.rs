//! Consistent Overhead Byte Stuffing (Cheshire & Baker, IEEE/ACM ToN 7(2), 1999).
//!
//! COBS removes every `0x00` from a block so that `0x00` can delimit frames on the wire
//! (docs/PROTOCOL.md §2). The encoded block is a sequence of groups `code, data[code-1]`: each group
//! stands for `code-1` non-zero bytes followed by one implicit zero, except a group with
//! `code = 0xFF` (254 data bytes, no zero) and the last group (the implicit zero is dropped).
//! Overhead: at most one byte per 254 bytes of input, at least one byte (see [`max_encoded_len`]).
//!
//! Neither function allocates; decoding also works in place ([`decode_in_place`]), which is what
//! the frame decoder uses on its fixed buffer.

/// Why a block is not valid COBS.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum CobsError {
    /// A group code of `0x00` inside the block (it can only be a delimiter).
    #[error("zero byte inside a COBS block at offset {0}")]
    ZeroInBlock(usize),
    /// A group announces more bytes than the block holds.
    #[error("COBS group at offset {0} runs past the end of the block")]
    Truncated(usize),
    /// The output buffer is too small.
    #[error("COBS output buffer too small")]
    OutputTooSmall,
}

/// Largest encoded length for `n` input bytes: `n + max(1, ceil(n / 254))`.
pub const fn max_encoded_len(n: usize) -> usize {
    let groups = n.div_ceil(254);
    n + if groups == 0 { 1 } else { groups }
}

/// Encode `src` into `dst` (no delimiter is written). Returns the encoded length.
pub fn encode(src: &[u8], dst: &mut [u8]) -> Result<usize, CobsError> {
    if dst.len() < max_encoded_len(src.len()) {
        return Err(CobsError::OutputTooSmall);
    }
    let mut code_at = 0;
    let mut w = 1;
    let mut code: u8 = 1;
    for (i, &b) in src.iter().enumerate() {
        if b == 0 {
            dst[code_at] = code;
            code_at = w;
            w += 1;
            code = 1;
        } else {
            dst[w] = b;
            w += 1;
            code += 1;
            // A full group of 254 data bytes closes without an implicit zero; open a new group
            // only if more input follows (no useless trailing 0x01).
            if code == 0xFF && i + 1 < src.len() {
                dst[code_at] = code;
                code_at = w;
                w += 1;
                code = 1;
            }
        }
    }
    dst[code_at] = code;
    Ok(w)
}

/// Decode the COBS block `buf` in place; the decoded bytes are `buf[..n]` with `n` returned.
/// `buf` must not contain the `0x00` delimiter.
pub fn decode_in_place(buf: &mut [u8]) -> Result<usize, CobsError> {
    let len = buf.len();
    let mut r = 0;
    let mut w = 0;
    while r < len {
        let code = buf[r];
        if code == 0 {
            return Err(CobsError::ZeroInBlock(r));
        }
        let n = code as usize - 1;
        if r + 1 + n > len {
            return Err(CobsError::Truncated(r));
        }
        buf.copy_within(r + 1..r + 1 + n, w);
        w += n;
        r += 1 + n;
        if code != 0xFF && r < len {
            buf[w] = 0;
            w += 1;
        }
    }
    Ok(w)
}

/// Decode the COBS block `src` into `dst`. Returns the decoded length.
pub fn decode(src: &[u8], dst: &mut [u8]) -> Result<usize, CobsError> {
    if dst.len() < src.len() {
        return Err(CobsError::OutputTooSmall);
    }
    dst[..src.len()].copy_from_slice(src);
    decode_in_place(&mut dst[..src.len()])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn enc(src: &[u8]) -> Vec<u8> {
        let mut out = vec![0u8; max_encoded_len(src.len())];
        let n = encode(src, &mut out).unwrap();
        out.truncate(n);
        out
    }

    fn dec(src: &[u8]) -> Result<Vec<u8>, CobsError> {
        let mut buf = src.to_vec();
        let n = decode_in_place(&mut buf)?;
        buf.truncate(n);
        Ok(buf)
    }

    #[test]
    fn protocol_vector_encode_and_decode() {
        assert_eq!(
            enc(&[0x11, 0x22, 0x00, 0x33]),
            [0x03, 0x11, 0x22, 0x02, 0x33]
        );
        assert_eq!(
            dec(&[0x03, 0x11, 0x22, 0x02, 0x33]).unwrap(),
            [0x11, 0x22, 0x00, 0x33]
        );
    }

    #[test]
    fn textbook_vectors() {
        let cases: [(&[u8], &[u8]); 5] = [
            (&[], &[0x01]),
            (&[0x00], &[0x01, 0x01]),
            (&[0x00, 0x00], &[0x01, 0x01, 0x01]),
            (&[0x11, 0x00], &[0x02, 0x11, 0x01]),
            (&[0x11, 0x22, 0x33, 0x44], &[0x05, 0x11, 0x22, 0x33, 0x44]),
        ];
        for (raw, coded) in cases {
            assert_eq!(enc(raw), coded, "encode {raw:02x?}");
            assert_eq!(dec(coded).unwrap(), raw, "decode {coded:02x?}");
        }
    }

    #[test]
    fn long_runs_round_trip_without_zeros() {
        for n in [253, 254, 255, 508, 600] {
            let raw: Vec<u8> = (0..n).map(|i| (i % 255 + 1) as u8).collect();
            let coded = enc(&raw);
            assert!(!coded.contains(&0));
            assert!(coded.len() <= max_encoded_len(n));
            assert_eq!(dec(&coded).unwrap(), raw, "n = {n}");
        }
        // A 253-byte body, the largest TSP/1 body, encodes to at most 254 bytes.
        assert_eq!(max_encoded_len(253), 254);
    }

    #[test]
    fn malformed_blocks_are_errors() {
        assert_eq!(dec(&[0x05, 0x11, 0x22]), Err(CobsError::Truncated(0)));
        assert_eq!(
            dec(&[0x02, 0x11, 0x00, 0x01]),
            Err(CobsError::ZeroInBlock(2))
        );
        let mut small = [0u8; 2];
        assert_eq!(
            encode(&[1, 2, 3], &mut small),
            Err(CobsError::OutputTooSmall)
        );
        assert_eq!(
            decode(&[1, 1, 1], &mut small),
            Err(CobsError::OutputTooSmall)
        );
    }
}
