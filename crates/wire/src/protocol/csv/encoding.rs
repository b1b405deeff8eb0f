//! The text of a CSV file from its bytes, in the encodings stand software on a PC writes:
//! UTF-8 (with or without a BOM), UTF-16 (Excel's "Unicode text", tab separated; with a BOM or
//! without one), UTF-32, and Windows-1252 (a Windows export or Excel's "CSV" save, where `µ` is
//! the byte `B5` and `·` the byte `B7`). Read as UTF-8 with replacement, a Windows-1252 `ESC
//! signal (µs)` became `ESC signal (�s)`, a column no table knows; a UTF-16 file's NUL bytes
//! looked binary.
//!
//! **Rule** ([`wide`], [`decode`]). A byte order mark decides UTF-32 (`FF FE 00 00`
//! little-endian, `00 00 FE FF` big-endian) or UTF-16 (`FF FE`, `FE FF`). Without one, the NUL
//! bytes of a text of mostly ASCII characters decide ([`wide`]): every 4-byte unit of the
//! first [`SNIFF`] bytes a character below U+10000 written `xx xx 00 00` (or `00 00 xx xx`) is
//! UTF-32; no 2-byte unit `00 00` and at least three in four written `xx 00` (or `00 xx`) is
//! UTF-16 — UTF-8 and Windows-1252 text never holds a NUL byte, a binary TSP/1 recording never
//! two in a row (COBS). Otherwise bytes that are valid UTF-8 are UTF-8; otherwise the file is
//! Windows-1252 (every byte is a character: ASCII as it is, `80`–`9F` the code page's own
//! table, `A0`–`FF` as in Latin-1). A file that is neither is not rejected here: every byte
//! decodes to something, and the CSV reader says what it cannot read.

use std::borrow::Cow;

/// The encoding a text was decoded from (`source.csv.encoding` when it is not UTF-8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Encoding {
    /// UTF-8, with or without a BOM.
    #[serde(rename = "utf-8")]
    Utf8,
    /// UTF-16, little-endian, with a BOM or without one.
    #[serde(rename = "utf-16le")]
    Utf16Le,
    /// UTF-16, big-endian, with a BOM or without one.
    #[serde(rename = "utf-16be")]
    Utf16Be,
    /// UTF-32, little-endian, with a BOM or without one.
    #[serde(rename = "utf-32le")]
    Utf32Le,
    /// UTF-32, big-endian, with a BOM or without one.
    #[serde(rename = "utf-32be")]
    Utf32Be,
    /// Windows-1252.
    #[serde(rename = "windows-1252")]
    Windows1252,
}

/// Windows-1252's characters for the bytes `80`–`9F` (`�` where the code page has none).
const CP1252_80: [char; 32] = [
    '€', '\u{fffd}', '‚', 'ƒ', '„', '…', '†', '‡', 'ˆ', '‰', 'Š', '‹', 'Œ', '\u{fffd}', 'Ž',
    '\u{fffd}', '\u{fffd}', '‘', '’', '“', '”', '•', '–', '—', '˜', '™', 'š', '›', 'œ', '\u{fffd}',
    'ž', 'Ÿ',
];

/// Bytes looked at by [`wide`] for a text without a byte order mark.
pub const SNIFF: usize = 4096;

impl Encoding {
    /// Bytes per code unit of UTF-16 and UTF-32 (`None` for the byte encodings).
    fn unit(self) -> Option<usize> {
        match self {
            Encoding::Utf16Le | Encoding::Utf16Be => Some(2),
            Encoding::Utf32Le | Encoding::Utf32Be => Some(4),
            Encoding::Utf8 | Encoding::Windows1252 => None,
        }
    }

    fn big_endian(self) -> bool {
        matches!(self, Encoding::Utf16Be | Encoding::Utf32Be)
    }
}

/// The UTF-16 or UTF-32 encoding of `bytes` and the length of its byte order mark (0 without
/// one), by the rule of the [module documentation](self); `None` for a byte encoding.
pub fn wide(bytes: &[u8]) -> Option<(Encoding, usize)> {
    match bytes {
        [0xFF, 0xFE, 0, 0, ..] => return Some((Encoding::Utf32Le, 4)),
        [0, 0, 0xFE, 0xFF, ..] => return Some((Encoding::Utf32Be, 4)),
        [0xFF, 0xFE, ..] => return Some((Encoding::Utf16Le, 2)),
        [0xFE, 0xFF, ..] => return Some((Encoding::Utf16Be, 2)),
        _ => {}
    }
    let head = &bytes[..bytes.len().min(SNIFF)];
    let quads: Vec<&[u8]> = head.chunks_exact(4).collect();
    let all = |f: fn(&[u8]) -> bool| !quads.is_empty() && quads.iter().all(|q| f(q));
    if all(|q| q[2..] == [0, 0] && q[..2] != [0, 0]) {
        return Some((Encoding::Utf32Le, 0));
    }
    if all(|q| q[..2] == [0, 0] && q[2..] != [0, 0]) {
        return Some((Encoding::Utf32Be, 0));
    }
    let pairs = head.chunks_exact(2);
    let n = pairs.len();
    if n < 2 || pairs.clone().any(|p| p == [0, 0]) {
        return None;
    }
    let high_nul = |i: usize| pairs.clone().filter(|p| p[i] == 0).count() * 4 >= n * 3;
    if high_nul(1) {
        Some((Encoding::Utf16Le, 0))
    } else if high_nul(0) {
        Some((Encoding::Utf16Be, 0))
    } else {
        None
    }
}

/// The text of `bytes` and the encoding it was read in (module doc). UTF-8 is borrowed.
pub fn decode(bytes: &[u8]) -> (Cow<'_, str>, Encoding) {
    if let Some((e, mark)) = wide(bytes) {
        return (Cow::Owned(decode_wide(&bytes[mark..], e)), e);
    }
    match std::str::from_utf8(bytes) {
        Ok(text) => (Cow::Borrowed(text), Encoding::Utf8),
        Err(_) => {
            let text = bytes
                .iter()
                .map(|&b| match b {
                    0x80..=0x9F => CP1252_80[usize::from(b - 0x80)],
                    _ => char::from(b),
                })
                .collect();
            (Cow::Owned(text), Encoding::Windows1252)
        }
    }
}

/// UTF-16 or UTF-32 code units (after the mark) as text: an incomplete last unit is dropped,
/// a lone surrogate or a value that is no character replaced by `�`.
fn decode_wide(bytes: &[u8], e: Encoding) -> String {
    let be = e.big_endian();
    if e.unit() == Some(4) {
        return bytes
            .chunks_exact(4)
            .map(|q| {
                let q = [q[0], q[1], q[2], q[3]];
                let v = if be {
                    u32::from_be_bytes(q)
                } else {
                    u32::from_le_bytes(q)
                };
                char::from_u32(v).unwrap_or('\u{fffd}')
            })
            .collect();
    }
    let units = bytes.chunks_exact(2).map(|p| {
        let pair = [p[0], p[1]];
        if be {
            u16::from_be_bytes(pair)
        } else {
            u16::from_le_bytes(pair)
        }
    });
    char::decode_utf16(units)
        .map(|c| c.unwrap_or('\u{fffd}'))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_encoding_gives_the_same_text() {
        let text = "Time (s),ESC signal (µs),Torque (N·m)\r\n0.01,1500,0.02\r\n";
        let (t, e) = decode(text.as_bytes());
        assert_eq!((t.as_ref(), e), (text, Encoding::Utf8));
        assert!(matches!(t, Cow::Borrowed(_)));
        let cp1252: Vec<u8> = text
            .chars()
            .map(|c| match c {
                'µ' => 0xB5,
                '·' => 0xB7,
                c => c as u8,
            })
            .collect();
        assert_eq!(
            decode(&cp1252),
            (Cow::Owned(text.into()), Encoding::Windows1252)
        );
        let mut le = vec![0xFF, 0xFE];
        let mut be = vec![0xFE, 0xFF];
        for u in text.encode_utf16() {
            le.extend(u.to_le_bytes());
            be.extend(u.to_be_bytes());
        }
        assert_eq!(decode(&le), (Cow::Owned(text.into()), Encoding::Utf16Le));
        assert_eq!(decode(&be), (Cow::Owned(text.into()), Encoding::Utf16Be));
        // Windows-1252's own characters in 80..9F (a bullet as the torque's dot)
        assert_eq!(decode(b"N\x95m\xff").0, "N•mÿ");
        // an odd trailing byte of a UTF-16 file is dropped, a lone surrogate replaced
        assert_eq!(
            decode(&[0xFF, 0xFE, 0x41, 0x00, 0x00, 0xD8, 0x42]).0,
            "A\u{fffd}"
        );
    }

    /// `text` in UTF-16 or UTF-32, little- or big-endian, with a BOM or not.
    fn wide_bytes(text: &str, unit: usize, be: bool, bom: bool) -> Vec<u8> {
        let mut out = Vec::new();
        let chars = bom.then_some('\u{feff}').into_iter().chain(text.chars());
        for c in chars {
            if unit == 4 {
                let v = c as u32;
                out.extend(if be { v.to_be_bytes() } else { v.to_le_bytes() });
            } else {
                let mut buf = [0u16; 2];
                for u in c.encode_utf16(&mut buf) {
                    out.extend(if be { u.to_be_bytes() } else { u.to_le_bytes() });
                }
            }
        }
        out
    }

    #[test]
    fn utf16_without_a_bom_and_utf32_are_read_and_named() {
        let text = "Time (s)\tESC signal (µs)\tTorque (N·m)\r\n0.01\t1500\t0.02\r\n";
        for (unit, be, e) in [
            (2, false, Encoding::Utf16Le),
            (2, true, Encoding::Utf16Be),
            (4, false, Encoding::Utf32Le),
            (4, true, Encoding::Utf32Be),
        ] {
            for bom in [false, true] {
                let bytes = wide_bytes(text, unit, be, bom);
                let mark = if bom { unit } else { 0 };
                assert_eq!(wide(&bytes), Some((e, mark)), "{e:?} bom {bom}");
                assert_eq!(decode(&bytes), (Cow::Owned(text.into()), e), "{e:?}");
            }
        }
        // A character outside the BMP in UTF-16 (a surrogate pair) among ASCII: still UTF-16.
        let bytes = wide_bytes("t_s,thrust_N 🚁\n0.1,2.5\n", 2, false, false);
        assert_eq!(wide(&bytes), Some((Encoding::Utf16Le, 0)));
        // Neither UTF-8, Windows-1252 nor a TSP/1 recording (no two NULs in a row) is wide.
        assert_eq!(wide(b"t_s,thrust_N\n0.1,2.5\n"), None);
        assert_eq!(wide(b"N\x95m\xff"), None);
        assert_eq!(
            wide(&[0x03, 0x01, 0x02, 0x00, 0x04, 0x05, 0x06, 0x00]),
            None
        );
        // too short to tell
        assert_eq!(wide(b"1\0"), None);
    }
}
