//! Effects hidden in measured data (issue 11, item 6): a real log of the repository gets one effect of known, seeded random parameters
//! ([`propid_testkit::inject`]), is written as a CSV file and read by `propid diagnose --json`,
//! which must name the effect with its parameter within the injector's stated tolerance, on top
//! of what the clean log already shows. Two draws per log here; `scripts/injection_table.sh`
//! runs many (README's table), including the dead time and the supply sag, which these two
//! logs do not yet give back (see docs/injection.md).

use std::path::Path;

use crate::support::propid;
use propid::cli::load::{load, Request};
use propid_testkit::inject::{inject, judge, tolerance, Injection, Samples, REPO_LOGS};
use propid_wire::record::names;
use rand::rngs::StdRng;
use rand::SeedableRng;
use serde_json::Value;

/// `diagnose --json` findings of `s`, written as `file`.
fn findings(file: &Path, s: &Samples) -> Vec<Value> {
    std::fs::write(file, s.to_csv()).unwrap();
    let f = file.to_str().unwrap();
    let (code, out, err) = propid(&["diagnose", "--json", "--input", "u", "--output", "y", f]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).expect("one JSON object");
    v["findings"].as_array().cloned().unwrap_or_default()
}

/// `draws` seeded draws of `effect` in each of the repository logs named `logs`, each found
/// within tolerance.
fn hidden_effect_is_found(effect: &str, logs: &[&str], draws: u64) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("injected.csv");
    for log in REPO_LOGS.iter().filter(|l| logs.contains(&l.name)) {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(log.path);
        let outputs: Vec<String> = log.output.iter().map(|s| s.to_string()).collect();
        let req = Request {
            input: log.input,
            outputs: &outputs,
            optional: &[names::VOLTAGE],
            fs_hz: log.fs_hz,
            ..Request::default()
        };
        let loaded = load(&path, &req).unwrap();
        let s = Samples::from_record(
            &loaded.record,
            loaded.input.as_deref().unwrap(),
            &loaded.outputs[0],
            None,
        )
        .unwrap();
        let clean = findings(&file, &s);
        assert!(
            clean.iter().all(|f| f["effect"] != effect),
            "{}: the clean log already names {effect}: {clean:?}",
            log.name
        );
        for k in 0..draws {
            // The same seeds as the first draws of scripts/injection_table.sh.
            let inj = Injection::draw(effect, &s, &mut StdRng::seed_from_u64(1000 + k)).unwrap();
            let got = findings(&file, &inject(&s, &inj));
            let o = judge(&inj, &clean, &got);
            assert!(
                o.within(&inj),
                "{}: {inj:?} → {o:?} (tolerance {}); findings {got:?}",
                log.name,
                tolerance(&inj)
            );
        }
    }
}

/// Silverbox and the tanks. Not the robot arm: its sine sweep runs through its own lightly
/// damped 12.7 Hz mode (ζ ≈ 0.005), and a sinusoid drawn near that mode is absorbed by the
/// baseline's `fn`/`ζ` (its found rate is in docs/injection.md).
#[test]
fn a_sinusoid_hidden_in_real_logs_is_found_with_its_frequency_and_amplitude() {
    hidden_effect_is_found("periodic_disturbance", &["silverbox", "cascaded_tanks"], 2);
}

/// Silverbox and the robot arm. Not the tanks: their level creeps with a time constant of the
/// order of the record (0.25 Hz, 1024 samples), which the baseline trades against a line.
#[test]
fn a_drift_hidden_in_real_logs_is_found_with_its_rate() {
    hidden_effect_is_found("baseline_drift", &["silverbox", "robot_arm"], 2);
}
