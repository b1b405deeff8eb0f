//! The text of a CSV file from its bytes, in the encodings stand software on a PC writes:
//! UTF-8 (with or without a BOM), UTF-16 with a BOM (Excel's "Unicode text", tab separated),
//! and Windows-1252 (a Windows export or Excel's "CSV" save, where `µ` is the byte `B5` and `·`
//! the byte `B7`). Read as UTF-8 with replacement, a Windows-1252 `ESC signal (µs)` became
//! `ESC signal (�s)`, a column no table knows; a UTF-16 file's NUL bytes looked binary.
//!
//! **Rule** ([`decode`]). A UTF-16 byte order mark (`FF FE` little-endian, `FE FF` big-endian)
//! decides UTF-16; otherwise bytes that are valid UTF-8 are UTF-8; otherwise the file is
//! Windows-1252 (every byte is a character: ASCII as it is, `80`–`9F` the code page's own table,
//! `A0`–`FF` as in Latin-1). A file that is neither is not rejected here: every byte decodes
//! to something, and the CSV reader says what it cannot read.

use std::borrow::Cow;

/// The encoding a text was decoded from (`source.csv.encoding` when it is not UTF-8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Encoding {
    /// UTF-8, with or without a BOM.
    #[serde(rename = "utf-8")]
    Utf8,
    /// UTF-16, little-endian, with a BOM.
    #[serde(rename = "utf-16le")]
    Utf16Le,
    /// UTF-16, big-endian, with a BOM.
    #[serde(rename = "utf-16be")]
    Utf16Be,
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

/// The UTF-16 encoding `bytes` announce by their byte order mark, if they do.
pub fn utf16_mark(bytes: &[u8]) -> Option<Encoding> {
    match bytes {
        [0xFF, 0xFE, ..] => Some(Encoding::Utf16Le),
        [0xFE, 0xFF, ..] => Some(Encoding::Utf16Be),
        _ => None,
    }
}

/// The text of `bytes` and the encoding it was read in (module doc). UTF-8 is borrowed.
pub fn decode(bytes: &[u8]) -> (Cow<'_, str>, Encoding) {
    let utf16 = |be: bool| {
        let units = bytes[2..].chunks_exact(2).map(|p| {
            let pair = [p[0], p[1]];
            if be {
                u16::from_be_bytes(pair)
            } else {
                u16::from_le_bytes(pair)
            }
        });
        char::decode_utf16(units)
            .map(|c| c.unwrap_or('\u{fffd}'))
            .collect::<String>()
    };
    match utf16_mark(bytes) {
        Some(e) => (Cow::Owned(utf16(e == Encoding::Utf16Be)), e),
        None => match std::str::from_utf8(bytes) {
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
        },
    }
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
}
