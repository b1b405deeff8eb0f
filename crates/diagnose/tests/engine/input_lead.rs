//! The input lead (`crates/diagnose/src/lead.rs`): a stand logger that sends the command, reads
//! the load cell and writes both on one row logs a thrust that has already answered the command
//! beside it. With the lead the record is explained to the noise by its quadratic static map
//! alone; the same stand logged a row later (the plain hold) keeps that finding without a lead.
//! (The summary's `input lead` line: tests/cli/diagnose_input_lead.rs.)

use propid_testkit::logs::same_row_staircase;
use serde_json::Value;

use super::read::{diagnose_json, How};

fn effects(v: &Value) -> Vec<&str> {
    v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|f| f["effect"].as_str())
        .collect()
}

#[test]
fn a_thrust_read_on_the_commands_own_row_is_explained_with_a_lead() {
    let v = diagnose_json(
        "same_row_0.csv",
        same_row_staircase(0).as_bytes(),
        How::default(),
    );
    let lead = v["input_lead"]["samples"]
        .as_f64()
        .unwrap_or_else(|| panic!("{v}"));
    assert!(lead >= 0.5, "{}", v["input_lead"]);
    assert_eq!(effects(&v), ["static_nonlinearity"], "{v}");
    assert_ne!(v["verdict"]["kind"], "unexplained", "{}", v["verdict"]);
    // A row later, the plain hold: no lead, the same finding, explained as well.
    let v = diagnose_json(
        "same_row_1.csv",
        same_row_staircase(1).as_bytes(),
        How::default(),
    );
    assert!(v.get("input_lead").is_none(), "{}", v["input_lead"]);
    assert_eq!(effects(&v), ["static_nonlinearity"], "{v}");
    assert_ne!(v["verdict"]["kind"], "unexplained", "{}", v["verdict"]);
}
