//! Candidates not taken, through the binary: every one is a "not taken" line of the summary
//! with its score, held-out change and reason (the engine's `rejected` list, in memory:
//! crates/diagnose/tests/engine/rejected.rs).

use super::support::propid;

#[test]
fn candidates_not_taken_are_said_in_the_summary() {
    let (code, text, err) = propid(&[
        "diagnose",
        "tests/data/cascaded-tanks/dataBenchmark.csv",
        "--input",
        "uEst",
        "--output",
        "yEst",
        "--fs",
        "0.25",
    ]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("- not taken: "))
        .collect();
    let mode = lines
        .iter()
        .find(|l| l.starts_with("- not taken: stiffness_nonlinearity (score "))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        mode.ends_with("fits in-sample but with physically implausible values: not taken"),
        "{mode}"
    );
    // a candidate that lowered the held-out fit says by how much, in points and in its reason
    let lowered = lines
        .iter()
        .find(|l| l.contains("held-out -"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        lowered.contains("lowers the held-out fit by ") && lowered.ends_with(" pp: not taken"),
        "{lowered}"
    );
}
