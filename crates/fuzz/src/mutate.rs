//! Mutations of a seed slice: byte-level (bit flips, interesting bytes, inserts, deletes,
//! duplicates, splices, truncation), text-level (numeric fields replaced by edge values, lines
//! deleted, duplicated or swapped) and frame-level (a TSP/1 frame's body changed and its CRC and
//! COBS made valid again, so the payload parsers and the sample placement see it).

use propid_wire::protocol::{cobs, crc::crc16_mcrf4xx};
use rand::rngs::StdRng;
use rand::Rng;

/// Bytes a parser treats specially.
const BYTES: &[u8] = b"\0\xff\n\r,;\t*#-+.eE0 \"";

/// Numbers at the edges of what a reader meets.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-320",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "-9223372036854775809",
    "0.000000001",
    "1e9",
    "2047",
    "65535",
    "0x10",
    "1,5",
    "9999999999999999999999999999999",
    ".",
    "-",
    "e5",
    "1e",
    "+",
];

/// A slice of `seed` (text: its first line and a run of lines; binary: any run of bytes), at
/// most `max` bytes.
pub fn slice(rng: &mut StdRng, seed: &[u8], max: usize) -> Vec<u8> {
    if seed.len() <= max {
        return seed.to_vec();
    }
    if is_text(seed) {
        let head_end = seed.iter().position(|&b| b == b'\n').map_or(0, |i| i + 1);
        let head = &seed[..head_end.min(max / 2)];
        let room = max - head.len();
        let mut a = rng.gen_range(head_end..seed.len());
        while a > head_end && seed[a - 1] != b'\n' {
            a -= 1;
        }
        let mut out = head.to_vec();
        out.extend_from_slice(&seed[a..(a + room).min(seed.len())]);
        out
    } else {
        let a = rng.gen_range(0..seed.len() - max);
        seed[a..a + max].to_vec()
    }
}

fn is_text(b: &[u8]) -> bool {
    b.iter()
        .take(512)
        .all(|&c| c == b'\n' || c == b'\r' || c == b'\t' || (32..127).contains(&c) || c >= 0x80)
}

/// Applies 1..=6 random mutations to `buf`, drawing splices from `other`.
pub fn mutate(rng: &mut StdRng, buf: &mut Vec<u8>, other: &[u8]) {
    for _ in 0..rng.gen_range(1..=6) {
        match rng.gen_range(0..13) {
            0 | 1 => flip_bit(rng, buf),
            2 => set_byte(rng, buf),
            3 => insert(rng, buf),
            4 => delete(rng, buf),
            5 => duplicate(rng, buf),
            6 => splice(rng, buf, other),
            7 => truncate(rng, buf),
            8 | 9 => number(rng, buf),
            10 => lines(rng, buf),
            _ => frame(rng, buf),
        }
    }
}

fn flip_bit(rng: &mut StdRng, buf: &mut [u8]) {
    if !buf.is_empty() {
        let i = rng.gen_range(0..buf.len());
        buf[i] ^= 1 << rng.gen_range(0..8);
    }
}

fn set_byte(rng: &mut StdRng, buf: &mut [u8]) {
    if !buf.is_empty() {
        let i = rng.gen_range(0..buf.len());
        buf[i] = if rng.gen_bool(0.5) {
            BYTES[rng.gen_range(0..BYTES.len())]
        } else {
            rng.gen()
        };
    }
}

fn insert(rng: &mut StdRng, buf: &mut Vec<u8>) {
    let at = rng.gen_range(0..=buf.len());
    let n = rng.gen_range(1..=16);
    let bytes: Vec<u8> = (0..n)
        .map(|_| BYTES[rng.gen_range(0..BYTES.len())])
        .collect();
    buf.splice(at..at, bytes);
}

fn delete(rng: &mut StdRng, buf: &mut Vec<u8>) {
    if !buf.is_empty() {
        let a = rng.gen_range(0..buf.len());
        let b = (a + rng.gen_range(1..=64)).min(buf.len());
        buf.drain(a..b);
    }
}

fn duplicate(rng: &mut StdRng, buf: &mut Vec<u8>) {
    if !buf.is_empty() && buf.len() < 1 << 20 {
        let a = rng.gen_range(0..buf.len());
        let b = (a + rng.gen_range(1..=256)).min(buf.len());
        let chunk = buf[a..b].to_vec();
        let at = rng.gen_range(0..=buf.len());
        buf.splice(at..at, chunk);
    }
}

fn splice(rng: &mut StdRng, buf: &mut Vec<u8>, other: &[u8]) {
    if other.is_empty() {
        return;
    }
    let a = rng.gen_range(0..other.len());
    let b = (a + rng.gen_range(1..=512)).min(other.len());
    let at = rng.gen_range(0..=buf.len());
    let end = (at + rng.gen_range(0..=64)).min(buf.len());
    buf.splice(at..end, other[a..b].iter().copied());
}

fn truncate(rng: &mut StdRng, buf: &mut Vec<u8>) {
    if !buf.is_empty() {
        let n = rng.gen_range(0..buf.len());
        buf.truncate(n);
    }
}

/// Replaces the number around a random position with an edge value.
fn number(rng: &mut StdRng, buf: &mut Vec<u8>) {
    if buf.is_empty() {
        return;
    }
    let num = |c: u8| c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'+' | b'e' | b'E');
    let start = rng.gen_range(0..buf.len());
    let Some(i) = (start..buf.len()).find(|&i| buf[i].is_ascii_digit()) else {
        return;
    };
    let mut a = i;
    while a > 0 && num(buf[a - 1]) {
        a -= 1;
    }
    let mut b = i;
    while b < buf.len() && num(buf[b]) {
        b += 1;
    }
    let v = NUMBERS[rng.gen_range(0..NUMBERS.len())];
    buf.splice(a..b, v.bytes());
}

/// Deletes, duplicates or swaps whole lines.
fn lines(rng: &mut StdRng, buf: &mut Vec<u8>) {
    let mut ls: Vec<Vec<u8>> = buf.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
    if ls.len() < 2 {
        return;
    }
    let i = rng.gen_range(0..ls.len());
    let j = rng.gen_range(0..ls.len());
    match rng.gen_range(0..3) {
        0 => {
            ls.remove(i);
        }
        1 => {
            let l = ls[i].clone();
            for _ in 0..rng.gen_range(1..=50) {
                ls.insert(j.min(ls.len()), l.clone());
            }
        }
        _ => ls.swap(i, j),
    }
    *buf = ls.join(&b'\n');
}

/// Changes the body of one valid TSP/1 frame and makes its CRC and COBS valid again.
fn frame(rng: &mut StdRng, buf: &mut Vec<u8>) {
    let ends: Vec<usize> = buf
        .iter()
        .enumerate()
        .filter(|(_, &b)| b == 0)
        .map(|(i, _)| i)
        .collect();
    if ends.len() < 2 {
        return;
    }
    let k = rng.gen_range(1..ends.len());
    let (a, b) = (ends[k - 1] + 1, ends[k]);
    let mut body = [0u8; 512];
    let Ok(n) = cobs::decode(&buf[a..b], &mut body) else {
        return;
    };
    if n < 6 {
        return;
    }
    let mut body = body[..n - 2].to_vec();
    for _ in 0..rng.gen_range(1..=3) {
        match rng.gen_range(0..4) {
            0 => {
                let i = rng.gen_range(0..body.len());
                body[i] = rng.gen();
            }
            1 => {
                // an edge value into a 16- or 32-bit field
                let i = rng.gen_range(0..body.len());
                let v: [u8; 4] = *[[0xff; 4], [0; 4], [0xff, 0xff, 0xff, 0x7f], [0, 0, 0, 0x80]]
                    .get(rng.gen_range(0..4))
                    .unwrap_or(&[0; 4]);
                for (d, s) in body[i..].iter_mut().zip(v) {
                    *d = s;
                }
            }
            2 if body.len() > 4 => {
                let n = rng.gen_range(4..body.len());
                body.truncate(n);
            }
            _ => body.extend((0..rng.gen_range(1..8)).map(|_| rng.gen::<u8>())),
        }
    }
    body.truncate(250);
    let crc = crc16_mcrf4xx(&body);
    body.extend_from_slice(&crc.to_le_bytes());
    let mut enc = [0u8; 600];
    if let Ok(m) = cobs::encode(&body, &mut enc) {
        buf.splice(a..b, enc[..m].iter().copied());
    }
}
