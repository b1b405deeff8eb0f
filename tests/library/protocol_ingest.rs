//! `ingest::read_record` on arbitrary input never panics, and every record it returns keeps the
//! record contract: channels as long as the mask, NaN exactly at missing samples, events sorted
//! and inside the record, a positive sample period.

use propid_ingest::read_record;
use propid_wire::protocol::message::{Event, EventCode, Sample, SampleFlags};
use propid_wire::protocol::{encode_frame, Message, MAX_FRAME_LEN};
use propid_wire::record::Record;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn check_contract(r: &Record) -> Result<(), TestCaseError> {
    prop_assert!(r.dt_s.is_finite() && r.dt_s > 0.0);
    for c in &r.channels {
        prop_assert_eq!(c.data.len(), r.missing.len());
        for (v, m) in c.data.iter().zip(&r.missing) {
            prop_assert_eq!(v.is_nan(), *m, "channel {}", c.name);
        }
    }
    prop_assert!(r.events.windows(2).all(|w| w[0].sample <= w[1].sample));
    prop_assert!(r.events.iter().all(|e| e.sample < r.len()));
    Ok(())
}

/// A device stream: samples with random index steps, flags and values, and events.
fn device_stream() -> impl Strategy<Value = Vec<u8>> {
    let item = prop_oneof![
        8 => (0u32..4, any::<u16>(), any::<f32>()).prop_map(|(step, flags, v)| (0u8, step, flags, v)),
        1 => (0u32..4, 1u16..10, any::<f32>()).prop_map(|(step, code, v)| (1u8, step, code, v)),
    ];
    prop::collection::vec(item, 1..200).prop_map(|items| {
        let mut out = Vec::new();
        let mut buf = [0u8; MAX_FRAME_LEN];
        let mut idx = 0u32;
        for (seq, (kind, step, x, v)) in items.into_iter().enumerate() {
            idx = idx.wrapping_add(step);
            let msg = if kind == 0 {
                Message::Sample(Sample {
                    sample_index: idx,
                    t_us: idx.wrapping_mul(1000),
                    throttle: 100,
                    flags: SampleFlags(x | 0x2),
                    thrust_n: v,
                    torque_nm: 0.1,
                    rpm: v,
                    voltage_v: 12.0,
                    current_a: 1.0,
                })
            } else {
                Message::Event(Event {
                    code: EventCode::from_u8(x as u8),
                    arg: 0,
                    t_us: 0,
                    sample_index: idx.wrapping_add(step),
                })
            };
            let n = encode_frame(seq as u16, &msg, &mut buf);
            out.extend_from_slice(&buf[..n]);
        }
        out
    })
}

proptest! {
    #![proptest_config(Config {
        cases: 256,
        rng_seed: RngSeed::Fixed(0x1A9E_2026),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..3000)) {
        if let Ok((r, _)) = read_record(&bytes) {
            check_contract(&r)?;
        }
    }

    #[test]
    fn random_text_never_panics(text in "([0-9,.*#a-zA-Z_ -]{0,40}\\n){0,40}") {
        if let Ok((r, _)) = read_record(text.as_bytes()) {
            check_contract(&r)?;
        }
    }

    #[test]
    fn device_streams_keep_the_record_contract(bytes in device_stream()) {
        match read_record(&bytes) {
            Ok((r, s)) => {
                check_contract(&r)?;
                // Index steps of at most 3: no large gap, no reset; every position is a
                // received sample or a counted lost one.
                prop_assert_eq!(r.len() as u64, s.assemble.samples + s.assemble.samples_lost);
            }
            // Only events, or a single sample without a known rate.
            Err(e) => prop_assert!(
                matches!(e, propid_ingest::IngestError::NoSamples
                    | propid_ingest::IngestError::NoTimebase),
                "{e}"
            ),
        }
    }
}
