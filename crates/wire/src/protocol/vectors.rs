//! The test vectors of docs/PROTOCOL.md §5, byte for byte, in both directions.

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

#[test]
fn sample_vector() {
    let msg = Message::Sample(Sample {
        sample_index: 123_456,
        t_us: 4_000_000_123,
        throttle: 1500,
        flags: SampleFlags(0x003F),
        thrust_n: 4.25,
        torque_nm: 0.061,
        rpm: 12000.0,
        voltage_v: 16.80,
        current_a: 12.34,
    });
    check(
        0x1234,
        msg,
        "08 01 42 34 12 40 e2 01 08 7b 28 6b ee dc 05 3f 01 01 07 88 40 23 db 79
         3d 0e 80 3b 46 66 66 86 41 a4 70 45 41 07 39 00",
    );
}

#[test]
fn arm_vector() {
    check(
        7,
        Message::Arm(Arm::new(500)),
        "04 01 02 07 09 f4 01 41 52 4d 21 dd 96 00",
    );
}

#[test]
fn set_throttle_vector() {
    let msg = Message::SetThrottle(SetThrottle {
        level: 3500,
        ramp_ms: 0,
    });
    check(8, msg, "04 01 04 08 03 ac 0d 01 03 6b 79 00");
}

#[test]
fn impulse_vector() {
    let msg = Message::Impulse(Impulse {
        level: 6000,
        width_us: 20_000,
    });
    check(9, msg, "04 01 05 09 05 70 17 20 4e 01 03 18 b6 00");
}

#[test]
fn stop_vector() {
    check(10, Message::Stop, "04 01 06 0a 03 33 34 00");
}

#[test]
fn ack_vector() {
    let msg = Message::Ack(Ack {
        cmd_seq: 9,
        cmd_type: msg_type::IMPULSE,
        result: AckResult::Ok,
        ack_flags: 0,
        t_us: 4_000_010_000,
    });
    check(
        0x1235,
        msg,
        "06 01 43 35 12 09 02 05 01 07 10 4f 6b ee 29 35 00",
    );
}

#[test]
fn every_message_round_trips() {
    let msgs = [
        Message::Hello(Hello {
            proto_minor: 2,
            esc_protocol: EscProtocol::DShot300,
            fw_version: 0x0102,
            boot_id: 0xDEAD_BEEF,
            t_us: 99,
            sample_rate_hz: 1000,
            channels: 0x1F,
            motor_poles: 14,
            caps: 0x0F,
            name: Hello::name_field("sim-stand"),
        }),
        Message::Event(Event {
            code: EventCode::TxOverrun,
            arg: 3,
            t_us: 1,
            sample_index: 77,
        }),
        Message::Log(Log::new(3, "boot ok")),
        Message::Log(Log::new(0, &"x".repeat(200))),
        Message::HelloReq,
        Message::Disarm,
        Message::Heartbeat,
        Message::SetRate(SetRate {
            sample_rate_hz: 2000,
        }),
        Message::Tare,
    ];
    for (i, m) in msgs.iter().enumerate() {
        let wire = encoded(i as u16, m);
        assert!(wire.len() <= MAX_FRAME_LEN);
        assert_eq!(
            decode_one(&wire),
            Frame {
                seq: i as u16,
                msg: *m
            }
        );
    }
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
