//! Decoder throughput (issue 3: "decoder throughput" in README) and recording ingest speed
//! (the replay target: one hour of 1 kHz recording in under 2 s).
//!
//! Run: `cargo bench --bench decoder`. Criterion reports bytes/s for the decoder groups and
//! elements (samples)/s for the ingest group.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use propid_ingest::read_record;
use propid_wire::protocol::message::{Hello, Sample, SampleFlags};
use propid_wire::protocol::{encode_frame, Decoder, EscProtocol, Message, MAX_FRAME_LEN};

/// A recording of `n` SAMPLE frames at 1 kHz with a HELLO every 1000 samples.
fn recording(n: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity(n as usize * 40);
    let mut buf = [0u8; MAX_FRAME_LEN];
    let mut seq = 0u16;
    for i in 0..n {
        if i % 1000 == 0 {
            let h = Hello {
                proto_minor: 0,
                esc_protocol: EscProtocol::DShot600,
                fw_version: 1,
                boot_id: 42,
                t_us: 1000 * i,
                sample_rate_hz: 1000,
                channels: 0x1F,
                motor_poles: 14,
                caps: 0xF,
                name: Hello::name_field("bench"),
            };
            let k = encode_frame(seq, &Message::Hello(h), &mut buf);
            out.extend_from_slice(&buf[..k]);
            seq = seq.wrapping_add(1);
        }
        let s = Sample {
            sample_index: i,
            t_us: 1000u32.wrapping_mul(i),
            throttle: 3000 + (i % 100) as u16,
            flags: SampleFlags(0x3F | 1 << 10),
            thrust_n: 2.0 + (i % 17) as f32 * 0.01,
            torque_nm: 0.03,
            rpm: 15000.0,
            voltage_v: 16.4,
            current_a: 8.0,
        };
        let k = encode_frame(seq, &Message::Sample(s), &mut buf);
        out.extend_from_slice(&buf[..k]);
        seq = seq.wrapping_add(1);
    }
    out
}

fn decoder(c: &mut Criterion) {
    let bytes = recording(100_000);
    let frames = 100_000 + 100;
    let mut g = c.benchmark_group("decoder");
    for chunk in [1usize, 64, 4096, bytes.len()] {
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_with_input(
            BenchmarkId::new("bytes_chunk", chunk),
            &chunk,
            |b, &chunk| {
                b.iter(|| {
                    let mut dec = Decoder::new();
                    let mut n = 0u64;
                    for part in bytes.chunks(chunk) {
                        dec.push(black_box(part), |f| {
                            n += 1;
                            black_box(f);
                        });
                    }
                    assert_eq!(n, frames);
                })
            },
        );
    }
    g.throughput(Throughput::Elements(frames));
    g.bench_function("frames_per_s", |b| {
        b.iter(|| {
            let mut dec = Decoder::new();
            let mut n = 0u64;
            dec.push(black_box(&bytes), |_| n += 1);
            n
        })
    });
    g.finish();
}

fn ingest(c: &mut Criterion) {
    let n = 600_000u32; // ten minutes at 1 kHz
    let bytes = recording(n);
    let mut g = c.benchmark_group("ingest");
    g.sample_size(10);
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("read_record_10min_1kHz", |b| {
        b.iter(|| {
            let (r, _) = read_record(black_box(&bytes)).unwrap();
            assert_eq!(r.len(), n as usize);
        })
    });
    g.finish();
}

criterion_group!(benches, decoder, ingest);
criterion_main!(benches);
