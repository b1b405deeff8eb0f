//! The input lead through the binary: the summary says it (the engine's finding on the same
//! log, in memory: crates/diagnose/tests/engine/input_lead.rs).

use propid_testkit::logs::same_row_staircase;

use crate::support::propid;

#[test]
fn the_summary_says_the_input_lead() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("same_row_0.csv");
    std::fs::write(&file, same_row_staircase(0)).unwrap();
    let (code, text, err) = propid(&["diagnose", file.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("input lead "), "{text}");
}
