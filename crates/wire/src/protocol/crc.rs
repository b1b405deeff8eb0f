//! CRC-16/MCRF4XX, the frame check of TSP/1 (docs/PROTOCOL.md §2).
//!
//! Parameters (Rocksoft model): width 16, poly `0x1021` processed reflected (`0x8408`),
//! init `0xFFFF`, refin = refout = true, xorout `0x0000`; check("123456789") = `0x6F91`.
//! This is the CRC that MAVLink calls X.25 "accumulate" before its final xor.
//!
//! Implemented with tables built at compile time. Byte-wise:
//! `crc' = (crc >> 8) ^ T₀[(crc ^ b) & 0xFF]`, `T₀[i]` the 8-fold reflected shift of `i`.
//! Four bytes at a time ("slicing-by-4", Intel 2006): with `x = crc ^ (b₀ | b₁ << 8)` (the
//! 16-bit register is shifted out entirely after two bytes),
//! `crc' = T₃[x & 0xFF] ^ T₂[x >> 8] ^ T₁[b₂] ^ T₀[b₃]`, where `Tₖ[i] = (Tₖ₋₁[i] >> 8) ^
//! T₀[Tₖ₋₁[i] & 0xFF]` is the effect of byte `i` followed by `k` zero bytes.

/// Initial register value.
pub const CRC_INIT: u16 = 0xFFFF;

const POLY_REFLECTED: u16 = 0x8408;

const fn make_table() -> [u16; 256] {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = i as u16;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ POLY_REFLECTED
            } else {
                crc >> 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
}

const fn make_tables() -> [[u16; 256]; 4] {
    let mut t = [make_table(); 4];
    let mut k = 1;
    while k < 4 {
        let mut i = 0;
        while i < 256 {
            let prev = t[k - 1][i];
            t[k][i] = (prev >> 8) ^ t[0][(prev & 0xFF) as usize];
            i += 1;
        }
        k += 1;
    }
    t
}

static TABLES: [[u16; 256]; 4] = make_tables();

/// Continue a CRC-16/MCRF4XX computation from register value `crc` over `data`.
pub fn crc16_update(mut crc: u16, data: &[u8]) -> u16 {
    let [t0, t1, t2, t3] = &TABLES;
    let mut words = data.chunks_exact(4);
    for w in &mut words {
        let x = crc ^ u16::from_le_bytes([w[0], w[1]]);
        crc =
            t3[(x & 0xFF) as usize] ^ t2[(x >> 8) as usize] ^ t1[w[2] as usize] ^ t0[w[3] as usize];
    }
    for &b in words.remainder() {
        crc = (crc >> 8) ^ t0[((crc ^ b as u16) & 0xFF) as usize];
    }
    crc
}

/// CRC-16/MCRF4XX of `data`.
pub fn crc16_mcrf4xx(data: &[u8]) -> u16 {
    crc16_update(CRC_INIT, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit-by-bit reference, straight from the definition.
    fn reference(data: &[u8]) -> u16 {
        let mut crc = CRC_INIT;
        for &b in data {
            crc ^= b as u16;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ POLY_REFLECTED
                } else {
                    crc >> 1
                };
            }
        }
        crc
    }

    #[test]
    fn check_value_matches_protocol_vector() {
        assert_eq!(crc16_mcrf4xx(b"123456789"), 0x6F91);
    }

    #[test]
    fn empty_input_is_init() {
        assert_eq!(crc16_mcrf4xx(&[]), 0xFFFF);
    }

    #[test]
    fn table_matches_bitwise_reference() {
        let data: Vec<u8> = (0..=255u8).chain((0..=255u8).rev()).collect();
        for n in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 38, 100, 253, 512] {
            assert_eq!(crc16_mcrf4xx(&data[..n]), reference(&data[..n]), "n = {n}");
        }
    }

    #[test]
    fn update_is_incremental() {
        let whole = crc16_mcrf4xx(b"123456789");
        let split = crc16_update(crc16_update(CRC_INIT, b"1234"), b"56789");
        assert_eq!(whole, split);
    }
}
