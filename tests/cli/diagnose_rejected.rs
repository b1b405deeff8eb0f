//! Issue 11: candidates that were tried and not taken are said, not left in silence. On the
//! DaISy robot arm (tests/data) the search names no effect, but a sinusoid fits in-sample
//! (score far above the threshold) and lowers the held-out fit, and an extra mode fits only
//! with implausible values: both are listed in `rejected` with their score, held-out change and
//! reason, and in the human summary as "not taken" lines.

use super::support::propid;

const ARGS: [&str; 8] = [
    "diagnose",
    "tests/data/daisy-mechanical/robot_arm.csv",
    "--input",
    "u_torque",
    "--output",
    "y_accel",
    "--fs",
    "100",
];

#[test]
fn candidates_not_taken_are_listed_with_score_held_out_change_and_reason() {
    let mut args = ARGS.to_vec();
    args.push("--json");
    let (code, out, err) = propid(&args);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let rejected = v["rejected"].as_array().expect("a rejected array");
    let taken: Vec<&str> = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|f| f["effect"].as_str())
        .collect();
    assert!(!rejected.is_empty(), "{v}");
    for r in rejected {
        let mut keys: Vec<&str> = r.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        keys.sort_unstable();
        assert_eq!(keys, ["cv_gain_pp", "effect", "reason", "score"], "{r}");
        assert!(r["score"].as_f64().unwrap() >= 40.0, "{r}");
        assert!(!taken.contains(&r["effect"].as_str().unwrap()), "{r}");
    }
    let sine = rejected
        .iter()
        .find(|r| r["effect"] == "periodic_disturbance")
        .unwrap_or_else(|| panic!("{v}"));
    let gain = sine["cv_gain_pp"].as_f64().unwrap();
    assert!(gain < 0.0, "{sine}");
    let reason = sine["reason"].as_str().unwrap();
    assert_eq!(
        reason,
        format!(
            "fits in-sample but lowers the held-out fit by {:.1} pp: not taken",
            -gain
        )
    );
    let (code, text, err) = propid(&ARGS);
    assert_eq!(code, 0, "{err}");
    let line = text
        .lines()
        .find(|l| l.starts_with("- not taken: periodic_disturbance (score "))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(line.ends_with(reason), "{line}");
    assert!(
        line.contains(&format!("held-out {gain:+.2} points")),
        "{line}"
    );
}
