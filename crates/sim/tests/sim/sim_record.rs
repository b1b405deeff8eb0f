//! Record mode and exact fault accounting, without a pty (simulated clock, fast).

use propid_sim::config::SimConfig;
use propid_sim::record::record;
use propid_wire::protocol::{Decoder, EventCode, Frame, Message};

fn decode(bytes: &[u8]) -> (Vec<Frame>, Decoder) {
    let mut dec = Decoder::new();
    let mut frames = Vec::new();
    dec.push(bytes, |f| frames.push(f));
    (frames, dec)
}

#[test]
fn recording_holds_the_whole_experiment_with_every_pulse() {
    let cfg = SimConfig::default();
    let mut rec = Vec::new();
    let sum = record(&cfg, 60.0, &mut rec).unwrap();
    assert!(sum.finished, "{:?}", sum.notices);
    let k = cfg.experiment.pulses_per_level as usize;
    let levels = cfg.experiment.levels.len();
    assert_eq!(sum.pulses as usize, k * levels);
    let (frames, dec) = decode(&rec);
    assert_eq!(dec.stats().dropped.total(), 0);
    let edges = |code| {
        frames
            .iter()
            .filter(|f| matches!(f.msg, Message::Event(e) if e.code == code))
            .count()
    };
    assert_eq!(edges(EventCode::ImpulseStart), k * levels);
    assert_eq!(edges(EventCode::ImpulseEnd), k * levels);
    // Every pulse is one sample wide and the SAMPLE at its index carries the pulse level.
    let samples: Vec<_> = frames
        .iter()
        .filter_map(|f| match f.msg {
            Message::Sample(s) => Some(s),
            _ => None,
        })
        .collect();
    for f in &frames {
        if let Message::Event(e) = f.msg {
            if e.code == EventCode::ImpulseStart {
                let s = samples[e.sample_index as usize];
                assert_eq!((s.sample_index, s.throttle), (e.sample_index, e.arg));
                let next = samples[e.sample_index as usize + 1];
                assert_ne!(next.throttle, e.arg, "one period wide");
            }
        }
    }
    // The thrust at the top operating point is near the plant's static gain times the level.
    let top = *cfg.experiment.levels.last().unwrap();
    let at_top: Vec<f32> = samples
        .iter()
        .filter(|s| s.throttle == (top * 1e4) as u16)
        .map(|s| s.thrust_n)
        .collect();
    let mean = at_top.iter().sum::<f32>() as f64 / at_top.len() as f64;
    let want = cfg.plant.gain_n_per_throttle * top;
    assert!((mean - want).abs() < 0.05 * want, "{mean} vs {want}");
}

#[test]
fn same_seed_same_bytes() {
    let cfg = SimConfig::default();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    record(&cfg, 2.0, &mut a).unwrap();
    record(&cfg, 2.0, &mut b).unwrap();
    assert_eq!(a, b);
}

#[test]
fn every_injected_fault_is_counted_exactly_by_the_host_decoder() {
    let mut cfg = SimConfig::default();
    cfg.faults.bit_flip_per_byte = 0.001;
    cfg.faults.garbage_bursts_per_s = 10.0;
    cfg.faults.drop_sample_prob = 0.01;
    cfg.faults.stalls_per_s = 2.0;
    let mut rec = Vec::new();
    let sum = record(&cfg, 8.0, &mut rec).unwrap();
    let f = sum.faults;
    assert!(f.corrupted_frames > 10 && f.garbage_bursts > 10 && f.dropped_samples > 10);
    assert!(f.stalls > 0);
    let (frames, dec) = decode(&rec);
    assert_eq!(dec.stats().dropped.total(), f.frames_dropped());
    let samples: Vec<_> = frames
        .iter()
        .filter_map(|fr| match fr.msg {
            Message::Sample(s) => Some((fr.seq, s.sample_index)),
            _ => None,
        })
        .collect();
    let inner: u64 = samples
        .windows(2)
        .map(|w| (w[1].1 - w[0].1 - 1) as u64)
        .sum();
    let head = samples[0].1 as u64;
    let tail = sum.firmware.samples - 1 - samples.last().unwrap().1 as u64;
    // Stalls delay, never lose: the lost samples are exactly the dropped and corrupted ones.
    assert_eq!(head + inner + tail, f.samples_lost());
    assert!(inner > 0);
    // A device-side drop leaves no seq jump: seq gaps between consecutive decoded frames come
    // only from corrupted frames.
    let seqs: Vec<u16> = frames.iter().map(|fr| fr.seq).collect();
    let seq_gaps: u64 = seqs
        .windows(2)
        .map(|w| w[1].wrapping_sub(w[0]).wrapping_sub(1) as u64)
        .sum();
    assert!(seq_gaps <= f.corrupted_frames, "{seq_gaps} {f:?}");
}

#[test]
fn csv_stands_cannot_record_the_binary_plan() {
    let mut cfg = SimConfig::default();
    cfg.stand.protocol = propid_sim::config::WireProtocol::Csv;
    let err = record(&cfg, 1.0, &mut Vec::new()).unwrap_err();
    assert!(err.to_string().contains("tsp"), "{err}");
}
