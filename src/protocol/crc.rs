//! CRC-16/MCRF4XX, the frame check of TSP/1 (PROTOCOL.md §2).
//!
//! Parameters (Rocksoft model): width 16, poly `0x1021` processed reflected (`0x8408`),
//! init `0xFFFF`, refin = refout = true, xorout `0x0000`; check("123456789") = `0x6F91`.
//! This is the CRC that MAVLink calls X.25 "accumulate" before its final xor.
//!
//! Implemented byte-wise with a 256-entry table built at compile time:
//! `crc' = (crc >> 8) ^ T[(crc ^ b) & 0xFF]`, with `T[i]` the 8-fold reflected shift of `i`.

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

static TABLE: [u16; 256] = make_table();

/// Continue a CRC-16/MCRF4XX computation from register value `crc` over `data`.
pub fn crc16_update(mut crc: u16, data: &[u8]) -> u16 {
    for &b in data {
        crc = (crc >> 8) ^ TABLE[((crc ^ b as u16) & 0xFF) as usize];
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
        for n in [0, 1, 2, 7, 100, 512] {
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
