//! The sampler's hot path allocates nothing: decoding frames (good and bad) with [`Decoder`],
//! encoding commands with `encode_frame`, and the CSV line decoder on data rows. A counting
//! global allocator counts this thread's allocations.

use crate::counting_alloc;

use counting_alloc::allocations;

use propid_wire::protocol::csv::{CsvDecoder, CsvItem};
use propid_wire::protocol::message::{Log, Sample, SampleFlags};
use propid_wire::protocol::{encode_frame, Decoder, Impulse, Message, MAX_FRAME_LEN};

#[test]
fn decoding_and_encoding_allocate_nothing() {
    let mut stream = Vec::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    for i in 0..200u32 {
        let s = Sample {
            sample_index: i,
            t_us: 1000 * i,
            throttle: 4000,
            flags: SampleFlags(0x3F),
            thrust_n: 1.0,
            ..Sample::default()
        };
        let n = encode_frame(i as u16, &Message::Sample(s), &mut buf);
        stream.extend_from_slice(&buf[..n]);
        if i % 50 == 0 {
            stream.extend_from_slice(b"garbage \x01\x02\x00"); // a drop
            let n = encode_frame(0, &Message::Log(Log::new(1, "log")), &mut buf);
            stream.extend_from_slice(&buf[..n]);
        }
    }
    let mut dec = Decoder::new();
    let (n_alloc, frames) = allocations(|| {
        let mut frames = 0u32;
        for chunk in stream.chunks(37) {
            dec.push(chunk, |_| frames += 1);
        }
        let mut out = [0u8; MAX_FRAME_LEN];
        for seq in 0..100u16 {
            let imp = Message::Impulse(Impulse {
                level: 5000,
                width_us: 1000,
            });
            assert!(encode_frame(seq, &imp, &mut out) > 0);
        }
        frames
    });
    assert_eq!(n_alloc, 0);
    assert_eq!(frames, 204);
    assert_eq!(dec.stats().dropped.total(), 4);
}

#[test]
fn csv_rows_allocate_nothing_after_the_header() {
    let mut dec = CsvDecoder::default();
    dec.push(b"t_us,idx,throttle,thrust_N\n", |_| {});
    let rows: String = (0..100)
        .map(|i| format!("{},{},3500,{}.5\n", 1000 * i, i, i))
        .collect();
    let (n_alloc, count) = allocations(|| {
        let mut count = 0;
        dec.push(rows.as_bytes(), |it| {
            if let CsvItem::Row(_) = it {
                count += 1
            }
        });
        count
    });
    assert_eq!(n_alloc, 0);
    assert_eq!(count, 100);
}
