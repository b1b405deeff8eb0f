//! A `sample_index` jump far beyond the largest gap, through the real binary: `propid replay`
//! ends the segment there (counted, never bridged), keeps identifying after it, and places
//! every sample by the same rule as the offline ingest of the same recording (`propid
//! identify`'s reader): one rule, live and offline.

use crate::daemon_proc;

use daemon_proc::{dropped_total, kind, of_type, stats, BIN};
use propid_ingest::read_record;
use propid_wire::protocol::message::SampleFlags;
use propid_wire::protocol::{encode_frame, Decoder, EventCode, Message, MAX_FRAME_LEN};
use serde_json::Value;
use std::process::Command;

/// The jump: far beyond ingest's largest masked gap (65 536 samples).
const JUMP: u32 = 200_000;

/// A noise-free recording of the simulated stand at two operating points (fn 25 Hz, ζ 0.5,
/// 8 N per unit throttle).
fn recording() -> Vec<u8> {
    let mut cfg = daemon_proc::clean_stand();
    cfg.experiment.levels = vec![0.35, 0.55];
    let mut bytes = Vec::new();
    let sum = propid_sim::record::record(&cfg, 60.0, &mut bytes).unwrap();
    assert!(sum.finished);
    bytes
}

/// The recording as a device whose counter jumped by `JUMP` in the ramp to the second level
/// would have sent it (SAMPLE and EVENT indices from there on shifted), with the SAMPLE
/// `dup_at` sent twice. Returns the bytes and the first shifted (original) index.
fn with_jump_and_duplicate(bytes: &[u8], dup_at: u32) -> (Vec<u8>, u32) {
    let mut frames = Vec::new();
    Decoder::new().push(bytes, |f| frames.push(f));
    let last_pulse = frames
        .iter()
        .filter_map(|f| match f.msg {
            Message::Event(e) if e.code == EventCode::ImpulseStart => Some(e.sample_index),
            _ => None,
        })
        .nth(7)
        .expect("8 pulses at the first level");
    let ramp = frames
        .iter()
        .find_map(|f| match f.msg {
            Message::Sample(s)
                if s.sample_index > last_pulse && s.flags.contains(SampleFlags::RAMP_ACTIVE) =>
            {
                Some(s.sample_index)
            }
            _ => None,
        })
        .expect("a ramp to the second level");
    let from = ramp + 100;
    let mut out = Vec::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    for f in frames {
        let mut msg = f.msg;
        let mut copies = 1;
        match &mut msg {
            Message::Sample(s) if s.sample_index >= from => s.sample_index += JUMP,
            Message::Sample(s) if s.sample_index == dup_at => copies = 2,
            Message::Event(e) if e.sample_index >= from => e.sample_index += JUMP,
            _ => {}
        }
        for _ in 0..copies {
            let n = encode_frame(f.seq, &msg, &mut buf);
            out.extend_from_slice(&buf[..n]);
        }
    }
    (out, from)
}

#[test]
fn index_jump_beyond_the_largest_gap_is_a_new_segment_in_replay_as_in_ingest() {
    let (bytes, from) = with_jump_and_duplicate(&recording(), 300);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("jump.tsp");
    std::fs::write(&path, &bytes).unwrap();
    let out = Command::new(BIN).arg("replay").arg(&path).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let s = stats(&lines);
    assert_eq!(dropped_total(s), 0);
    assert_eq!(s["samples_lost"], u64::from(JUMP), "{s}");
    assert_eq!(
        (s["large_gaps"].as_u64(), s["gaps"].as_u64()),
        (Some(1), Some(1))
    );
    assert_eq!(
        (s["segments"].as_u64(), s["duplicates"].as_u64()),
        (Some(2), Some(1))
    );
    // announced as a new segment and a gap of the exact size, never masked inside a window
    let seg = kind(&lines, "segment")
        .into_iter()
        .filter(|l| l["boot_id"] == 0)
        .count();
    assert_eq!(seg, 1, "{lines:#?}");
    let gaps = kind(&lines, "gap");
    assert_eq!(gaps.len(), 1);
    assert_eq!(gaps[0]["count"], u64::from(JUMP));
    assert_eq!(gaps[0]["before"], u64::from(from + JUMP));
    // both levels still identified, exactly, the second one after the jump
    let models = of_type(&lines, "model");
    assert_eq!(models.len(), 4, "{lines:#?}");
    for m in &models {
        assert_eq!(m["pulses_skipped"], 0);
        for (key, truth) in [("fn_hz", 25.0), ("zeta", 0.5), ("dc_gain", 8.0)] {
            let v = m[key].as_f64().unwrap();
            assert!((v / truth - 1.0).abs() < 1e-4, "{key} {v}");
        }
    }
    assert!(models[3]["first_sample"].as_u64().unwrap() > u64::from(from + JUMP));

    // the offline reader places the same samples by the same rule
    let (record, ingest) = read_record(&bytes).unwrap();
    let a = ingest.assemble;
    assert_eq!(s["samples_lost"], a.samples_lost);
    assert_eq!(s["large_gaps"], a.large_gaps);
    assert_eq!(s["gaps"], a.gaps + a.large_gaps);
    assert_eq!(s["segments"], a.segments);
    assert_eq!(s["duplicates"], a.duplicates);
    assert_eq!(s["clock_wraps"], a.clock_wraps);
    // the record does not hold 200 000 filled samples either: only what was received
    assert_eq!(record.len() as u64, s["samples"].as_u64().unwrap() - 1);
    assert_eq!(record.missing_count(), 0);
}

/// A device reset as the very last thing received (a HELLO of a new boot, no sample after
/// it): announced by a `segment` line like every boot, and counted in `segments` — the
/// published counter and the published lines agree exactly (the soak's link-fault runs once
/// saw one line more than the counter).
#[test]
fn a_hello_of_a_new_boot_as_the_last_frame_is_one_segment_line_and_counted() {
    let bytes = recording();
    let mut frames = Vec::new();
    Decoder::new().push(&bytes, |f| frames.push(f));
    let (seq, mut hello) = frames
        .iter()
        .find_map(|f| match f.msg {
            Message::Hello(h) => Some((f.seq, h)),
            _ => None,
        })
        .expect("the recording starts with a HELLO");
    hello.boot_id = hello.boot_id.wrapping_add(1);
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(seq, &Message::Hello(hello), &mut buf);
    let mut out = bytes.clone();
    out.extend_from_slice(&buf[..n]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("reset_at_end.tsp");
    std::fs::write(&path, &out).unwrap();
    let run = Command::new(BIN).arg("replay").arg(&path).output().unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let lines: Vec<Value> = String::from_utf8(run.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let segments = kind(&lines, "segment");
    assert_eq!(segments.len(), 2, "{segments:#?}");
    assert_eq!(segments[1]["boot_id"], hello.boot_id);
    assert_eq!(stats(&lines)["segments"], 2, "{}", stats(&lines));
    // the record's segments of samples are one: the new boot sent none
    let (_, ingest) = read_record(&out).unwrap();
    assert_eq!(ingest.assemble.segments, 1);
}
