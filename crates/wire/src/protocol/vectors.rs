//! The registry's test: every message's vector (docs/PROTOCOL.md §5 where it gives one) byte
//! for byte in both directions and as its CSV line; then the decoder's drop counting.

use super::message::*;
use super::*;

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect()
}

fn encoded(seq: u16, msg: &Message) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(seq, msg, &mut out);
    out[..n].to_vec()
}

fn decode_one(wire: &[u8]) -> Frame {
    let mut dec = Decoder::new();
    let mut frames = Vec::new();
    dec.push(wire, |f| frames.push(f));
    assert_eq!(frames.len(), 1, "stats: {:?}", dec.stats());
    assert_eq!(dec.stats().dropped.total(), 0);
    frames[0]
}

fn check(seq: u16, msg: Message, wire_hex: &str) {
    let wire = hex(wire_hex);
    assert_eq!(encoded(seq, &msg), wire, "encode {msg:?}");
    assert_eq!(decode_one(&wire), Frame { seq, msg }, "decode {wire_hex}");
}

/// Every registered message: its type code and name unique, its vector encoded and decoded
/// byte for byte, its payload's minimum length enforced, and its CSV line written (and read
/// back where the dialect reads it) as the vector says.
#[test]
fn every_registered_message_round_trips_its_vector() {
    let vectors = message::vectors();
    let mut codes = std::collections::BTreeSet::new();
    let mut names = std::collections::BTreeSet::new();
    for v in &vectors {
        let (t, name) = (v.msg.msg_type(), v.msg.name());
        assert!(codes.insert(t), "type code {t:#04x} registered twice");
        assert!(names.insert(name), "name {name} registered twice");
        assert_eq!(type_name(t), Some(name));
        check(v.seq, v.msg, v.wire);

        let mut pl = [0u8; payload::MAX_PAYLOAD];
        let n = v.msg.write_payload(&mut pl);
        let min = min_payload_len(t).unwrap();
        assert!(n >= min, "{name}: vector payload shorter than its minimum");
        if min > 0 {
            assert_eq!(
                Message::parse(t, &pl[..min - 1]),
                Err(DecodeError::ShortPayload {
                    msg_type: t,
                    len: min - 1,
                    min
                })
            );
        }
        assert_eq!(Message::parse(t, &pl[..n]), Ok(v.msg), "{name}");
        check_csv(v);
    }
}

/// The vector's CSV line: a command line written and read back, or a device line written and
/// (HELLO, EVENT) read back; a message without one has no form either way.
fn check_csv(v: &Vector<Message>) {
    use csv::{device_line, encode_csv_command, parse_comment, parse_csv_command, CommentFact};
    let name = v.msg.name();
    let mut buf = [0u8; csv::MAX_CSV_COMMAND];
    let command = encode_csv_command(&v.msg, &mut buf).map(|n| buf[..n].to_vec());
    let device = device_line(&v.msg);
    let Some(line) = v.csv else {
        assert!(
            command.is_err() && device.is_none(),
            "{name} has a CSV form"
        );
        return;
    };
    let with_nl = format!("{line}\n");
    match csv_command_form(v.msg.msg_type()) {
        CsvCommandForm::None => {
            assert_eq!(device.as_deref(), Some(with_nl.as_str()), "{name}");
            let fact = line.strip_prefix('#').and_then(parse_comment);
            let again = match fact {
                Some(CommentFact::Hello(h)) => device_line(&Message::Hello(h)),
                Some(CommentFact::Event(e)) => device_line(&Message::Event(e)),
                None => return,
            };
            assert_eq!(again.as_deref(), Some(with_nl.as_str()), "{name} read back");
        }
        form => {
            assert_eq!(device, None, "{name}");
            assert_eq!(command.as_deref(), Ok(with_nl.as_bytes()), "{name}");
            let back = parse_csv_command(line).unwrap();
            assert_eq!(csv::CsvCommandKind::of(&back).keyword(), form.keyword());
            if let CsvCommandForm::Reads(kw) = form {
                assert_eq!(back, v.msg, "{name}");
                assert_eq!(csv_reader(kw), Some(v.msg.msg_type()), "{kw} read by two");
            }
        }
    }
}

/// The messages whose vectors are not all their cases: a LOG of the longest text.
#[test]
fn longest_log_round_trips() {
    let m = Message::Log(Log::new(0, &"x".repeat(200)));
    let wire = encoded(3, &m);
    assert!(wire.len() <= MAX_FRAME_LEN);
    assert_eq!(decode_one(&wire), Frame { seq: 3, msg: m });
}

#[test]
fn trailing_payload_bytes_are_ignored() {
    let mut wire = [0u8; MAX_FRAME_LEN];
    let n = encode_raw(
        1,
        msg_type::SET_THROTTLE,
        5,
        &[0xac, 0x0d, 0, 0, 9, 9],
        &mut wire,
    )
    .unwrap();
    let f = decode_one(&wire[..n]);
    assert_eq!(
        f.msg,
        Message::SetThrottle(SetThrottle {
            level: 3500,
            ramp_ms: 0
        })
    );
}

#[test]
fn encode_into_small_buffer_writes_nothing() {
    let mut small = [0xAAu8; 4];
    assert_eq!(encode_frame(1, &Message::Stop, &mut small), 0);
    assert_eq!(small, [0xAA; 4]);
    assert!(matches!(
        try_encode_frame(1, &Message::Stop, &mut small),
        Err(EncodeError::BufferTooSmall { .. })
    ));
}

#[test]
fn every_drop_kind_is_counted_and_the_next_frame_survives() {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let mut stream = Vec::new();
    let stop = encoded(1, &Message::Stop);
    // cobs_error: a group running past the end.
    stream.extend_from_slice(&[0x05, 0x11, 0x00]);
    stream.extend_from_slice(&stop);
    // crc_error: flip a payload bit of a valid frame.
    let mut bad = encoded(2, &Message::SetRate(SetRate { sample_rate_hz: 5 }));
    bad[5] ^= 0x04;
    stream.extend_from_slice(&bad);
    stream.extend_from_slice(&stop);
    // bad_version.
    let n = encode_raw(2, msg_type::STOP, 3, &[], &mut buf).unwrap();
    stream.extend_from_slice(&buf[..n]);
    stream.extend_from_slice(&stop);
    // short_frame: valid COBS of a 2-byte body. (Stray text is mostly a COBS error instead.)
    stream.extend_from_slice(&[0x03, b'h', b'i', 0x00]);
    stream.extend_from_slice(&stop);
    // short_payload: SAMPLE with 4 bytes.
    let n = encode_raw(1, msg_type::SAMPLE, 4, &[1, 2, 3, 4], &mut buf).unwrap();
    stream.extend_from_slice(&buf[..n]);
    stream.extend_from_slice(&stop);
    // oversize: 300 non-zero bytes.
    stream.extend_from_slice(&[0x41; 300]);
    stream.push(0);
    stream.extend_from_slice(&stop);
    // unknown_type.
    let n = encode_raw(1, 0x7E, 5, &[], &mut buf).unwrap();
    stream.extend_from_slice(&buf[..n]);
    stream.extend_from_slice(&stop);
    // empty frames.
    stream.extend_from_slice(&[0, 0]);

    let mut dec = Decoder::new();
    let mut frames = 0;
    let mut errors = Vec::new();
    dec.push_results(&stream, |r| match r {
        Ok(f) => {
            assert_eq!(f.msg, Message::Stop);
            frames += 1
        }
        Err(e) => errors.push(e),
    });
    let s = dec.stats();
    assert_eq!(frames, 7);
    assert_eq!(s.frames_ok, 7);
    assert_eq!(s.empty_frames, 2);
    assert_eq!(errors.len(), 7);
    let d = s.dropped;
    assert_eq!(
        [
            d.cobs_error,
            d.crc_error,
            d.bad_version,
            d.short_frame,
            d.short_payload,
            d.oversize,
            d.unknown_type
        ],
        [1; 7]
    );
    assert_eq!(s.bytes, stream.len() as u64);
}

#[test]
fn iterator_and_callback_agree() {
    let mut stream = Vec::new();
    for i in 0..5u16 {
        stream.extend_from_slice(&encoded(i, &Message::Heartbeat));
    }
    let mut a = Decoder::new();
    let mut via_push = Vec::new();
    a.push(&stream[..7], |f| via_push.push(f));
    a.push(&stream[7..], |f| via_push.push(f));
    let mut b = Decoder::new();
    let mut via_iter: Vec<Frame> = b.frames(&stream[..7]).collect();
    via_iter.extend(b.frames(&stream[7..]));
    assert_eq!(via_push, via_iter);
    assert_eq!(a.stats(), b.stats());
}

#[test]
fn stats_serialise_with_public_field_names() {
    let v = serde_json::to_value(DecodeStats::default()).unwrap();
    for k in [
        "cobs_error",
        "crc_error",
        "bad_version",
        "short_frame",
        "short_payload",
        "oversize",
        "unknown_type",
    ] {
        assert_eq!(v["dropped"][k], 0, "{k}");
    }
    assert_eq!(v["frames_ok"], 0);
}
