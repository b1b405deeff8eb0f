//! Isolated outliers and a start-up transient through the binary: the summary says what was
//! left out (the engine's counts and findings, in memory:
//! crates/diagnose/tests/engine/outliers.rs).

use crate::support::propid;
use propid_sim::synth;
use propid_testkit::inject::Samples;
use propid_testkit::logs::settling_tare_pulses;

#[test]
fn the_summary_says_what_was_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("rec.csv");
    let f = file.to_str().unwrap();
    // one dropout of the load cell, where the command holds 3 samples either side
    let (_, m) = synth::case(None, 0).unwrap();
    let mut s = Samples {
        dt_s: synth::DT_S,
        t0_s: 0.0,
        u: m.u,
        y: m.y,
        voltage: Some(m.voltage),
    };
    let a = (3000..s.u.len() - 3)
        .find(|&k| s.u[k - 3..=k + 3].iter().all(|&x| x == s.u[k]))
        .expect("a hold");
    s.y[a] = 0.0;
    std::fs::write(&file, s.to_csv()).unwrap();
    let (code, out, err) = propid(&["diagnose", "--input", "u", "--output", "y", f]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("outliers: 1 isolated sample(s) of the output left out"),
        "{out}"
    );
    // a load cell's tare settling from 0.3 N
    std::fs::write(&file, settling_tare_pulses(0.3)).unwrap();
    let (code, out, err) = propid(&["diagnose", f]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("start-up transient: the first "), "{out}");
}
