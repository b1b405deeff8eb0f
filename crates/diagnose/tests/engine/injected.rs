//! Effects hidden in measured data (issue 11, item 6): a real log of the repository gets one effect of known, seeded random parameters
//! ([`propid_testkit::inject`]), is written as a CSV text and read as `propid diagnose --json`
//! reads it ([`super::read`]),
//! which must name the effect with its parameter within the injector's stated tolerance, on top
//! of what the clean log already shows. Two draws per log here; `scripts/injection_table.sh`
//! runs many (README's table), including the dead time, which these logs do not all give back
//! (see docs/injection.md); a supply gain hidden on Silverbox's output is tested here. The shared motor-stand logs
//! (`../shared/data`, not copied into the repository) are used when present: a delay hidden in
//! the vanderploeg and bitcraze cf21 staircases (each on top of the log's own) and a supply sag
//! hidden in the vanderploeg and dantonio logs are tested here.

use propid_numerics::EffectName;
use std::path::{Path, PathBuf};

use super::read::{diagnose_json, How};
use propid_ingest::load::{load_bytes, Request};
use propid_testkit::inject::{
    inject, judge, tolerance, Injection, Log, Samples, REPO_LOGS, SHARED_LOGS,
};
use propid_wire::record::names;
use rand::rngs::StdRng;
use rand::SeedableRng;
use serde_json::Value;

/// `diagnose --json` of `s` written as a CSV text.
fn diagnose(s: &Samples) -> Value {
    let how = How {
        input: Some("u"),
        output: Some("y"),
        ..How::default()
    };
    diagnose_json("injected.csv", s.to_csv().as_bytes(), how)
}

/// `diagnose --json` findings of `s`.
fn findings(s: &Samples) -> Vec<Value> {
    diagnose(s)["findings"]
        .as_array()
        .cloned()
        .unwrap_or_default()
}

/// The shared dataset folder, or `None` (with a visible message) when it is absent.
fn shared(folder: &str) -> Option<PathBuf> {
    let root = std::env::var_os("PROPID_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("../shared/data"));
    let dir = root.join(folder);
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: {} is absent (shared dataset {folder}; set PROPID_SHARED_DATA)",
            dir.display()
        );
        None
    }
}

/// The repository's root.
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The repository logs named `wanted`, and the shared ones when their folder is present.
fn logs(wanted: &[&str]) -> Vec<(PathBuf, Log)> {
    let repo = REPO_LOGS.iter().map(|l| (repo().join(l.path), *l));
    let shared = SHARED_LOGS.iter().filter_map(|l| {
        let (folder, file) = l.path.split_once('/')?;
        Some((shared(folder)?.join(file), *l))
    });
    repo.chain(shared)
        .filter(|(_, l)| wanted.contains(&l.name))
        .collect()
}

/// The samples of `log` at `path` as the app's loader reads them (with the supply voltage when
/// the log has one).
fn samples(path: &Path, log: &Log) -> Samples {
    let outputs: Vec<String> = log.output.iter().map(|s| s.to_string()).collect();
    let req = Request {
        input: log.input,
        outputs: &outputs,
        optional: &[names::VOLTAGE],
        fs_hz: log.fs_hz,
        ..Request::default()
    };
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let loaded = load_bytes(path.display().to_string(), &bytes, &req).unwrap();
    Samples::from_record(
        &loaded.record,
        loaded.input.as_deref().unwrap(),
        &loaded.outputs[0],
        loaded.optional.first().map(String::as_str),
    )
    .unwrap()
}

/// `draws` seeded draws of `effect` in each of the logs named `wanted` (the shared ones when
/// present), each found within tolerance.
fn hidden_effect_is_found(effect: EffectName, wanted: &[&str], draws: u64) {
    hidden_effect_is_found_on_top(effect, wanted, draws, false);
}

/// [`hidden_effect_is_found`]; with `on_top` the clean log may already name the effect (a
/// stand's own delay), and the injected one is judged on top of it ([`judge`]).
fn hidden_effect_is_found_on_top(effect: EffectName, wanted: &[&str], draws: u64, on_top: bool) {
    for (path, log) in logs(wanted) {
        let s = samples(&path, &log);
        let clean = findings(&s);
        assert!(
            on_top || clean.iter().all(|f| f["effect"] != effect.as_str()),
            "{}: the clean log already names {effect}: {clean:?}",
            log.name
        );
        for k in 0..draws {
            // The same seeds as the first draws of scripts/injection_table.sh.
            let inj = Injection::draw(effect, &s, &mut StdRng::seed_from_u64(1000 + k)).unwrap();
            let got = findings(&inject(&s, &inj));
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

/// Silverbox, the tanks, and the motor-stand logs when present. Not the robot arm: its sine
/// sweep runs through its own lightly damped 12.7 Hz mode (ζ ≈ 0.005), and a sinusoid drawn
/// within the resolution of that mode (the second draw, 12.46 Hz) is absorbed by it (its found
/// rate is in docs/injection.md).
#[test]
fn a_sinusoid_hidden_in_real_logs_is_found_with_its_frequency_and_amplitude() {
    hidden_effect_is_found(
        EffectName::PeriodicDisturbance,
        &[
            "silverbox",
            "cascaded_tanks",
            "vanderploeg 90PERCENT",
            "dantonio ramp",
        ],
        2,
    );
}

/// Silverbox, the robot arm, and the vanderploeg staircase when present. Not the tanks: under
/// the linear baseline their level already trends by about 7e-4 per second (the Torricelli
/// outflow against a slowly varying pump voltage), which a drift term takes up with the
/// injected one, and which the clean log does not name (its held-out figure falls).
#[test]
fn a_drift_hidden_in_real_logs_is_found_with_its_rate() {
    hidden_effect_is_found(
        EffectName::BaselineDrift,
        &["silverbox", "robot_arm", "vanderploeg 90PERCENT"],
        2,
    );
}

/// In a thrust-curve ramp that runs one way (dantonio, when present) neither a drift (a change
/// of the map) nor a delay of a few samples (a shift of the map) can be told: diagnose says so,
/// for the clean log and for every injected one; on the other logs it says neither.
#[test]
fn a_drift_or_a_delay_in_a_one_way_ramp_is_said_unidentifiable() {
    let warned = |v: &Value, kind: &str| {
        v["warnings"]
            .as_array()
            .is_some_and(|w| w.iter().any(|w| w["kind"] == kind))
    };
    let kinds = [
        (EffectName::BaselineDrift, "baseline_drift_unidentifiable"),
        (EffectName::DeadTime, "dead_time_unidentifiable"),
    ];
    for (path, log) in logs(&["dantonio ramp", "silverbox", "robot_arm", "cascaded_tanks"]) {
        let s = samples(&path, &log);
        let one_way = log.name == "dantonio ramp";
        let clean = diagnose(&s);
        for (_, kind) in kinds {
            assert_eq!(warned(&clean, kind), one_way, "{} {kind}", log.name);
        }
        if one_way {
            for (effect, kind) in kinds {
                for k in 0..2 {
                    let mut rng = StdRng::seed_from_u64(1000 + k);
                    let inj = Injection::draw(effect, &s, &mut rng).unwrap();
                    assert!(warned(&diagnose(&inject(&s, &inj)), kind), "{inj:?}");
                }
            }
        }
    }
}

/// The vanderploeg staircase, when present: its thrust delayed by 2–6 samples on top of the
/// stand's own delay (its load cell lags the voltage channel, so the delay's share on the
/// output's side must be found too; docs/injection.md: 20 of 20 draws). Without the shared
/// data, `diagnose_staircase` hides the same kind of delay in a simulated staircase.
#[test]
fn a_delay_hidden_in_a_motor_stand_log_is_found_on_top_of_its_own() {
    hidden_effect_is_found_on_top(EffectName::DeadTime, &["vanderploeg 90PERCENT"], 2, true);
}

/// The motor-stand logs with a supply voltage, when present: their thrust scaled by the
/// measured voltage as a propeller's would be (thrust ∝ V^n, `n` 1–2, on top of the stand's own
/// supply dependence). The vanderploeg staircase names its own sag already (the injected one
/// adds to it); on dantonio's ramp the voltage both follows the load and discharges, and only
/// its discharge tells a sag from the thrust curve (docs/injection.md gives both logs' rates).
#[test]
fn a_supply_sag_hidden_in_a_motor_stand_log_is_found_with_its_gain() {
    hidden_effect_is_found_on_top(
        EffectName::SupplySag,
        &["vanderploeg 90PERCENT", "dantonio ramp"],
        2,
        true,
    );
}

/// The Silverbox slice (an electronic mass-spring-damper with a cubic spring): its output
/// scaled by a discharging battery's voltage. Fitted on the drive the gain came back 20 % low
/// (a hardening spring answers a scaled drive by less than the scale); with the side settled
/// on the final model it is found on the output, within 2 % (docs/injection.md: 20 draws).
#[test]
fn a_supply_gain_on_a_nonlinear_springs_output_is_found_there() {
    for (path, log) in logs(&["silverbox"]) {
        let s = samples(&path, &log);
        let clean = findings(&s);
        for k in 0..2 {
            let inj = Injection::draw(
                EffectName::SupplySag,
                &s,
                &mut StdRng::seed_from_u64(1000 + k),
            )
            .unwrap();
            let got = findings(&inject(&s, &inj));
            let o = judge(&inj, &clean, &got);
            assert!(o.error.is_some_and(|e| e.abs() < 0.02), "{inj:?} → {o:?}");
            let sag = got.iter().find(|f| f["effect"] == "supply_sag").unwrap();
            assert_eq!(sag["scales"], "output", "{sag}");
            assert_eq!(sag["output_share"], 1.0, "{sag}");
        }
    }
}

/// Bitcraze's cf21 staircase, when present: its load cell lags the command by about ten
/// samples, which a time scale per direction and a series mode imitate in-sample; the clean log
/// must name that delay (the model with it predicts the held-out steps best), and a further
/// 2–6 samples hidden in it are found on top of it, within a sample ([`judge`]), never as a mode
/// with an inverse response (share g > 1, the Padé stand-in for a delay:
/// `extra_mode::MAX_SHARE`).
#[test]
fn a_delay_hidden_behind_a_slow_load_cell_is_found_on_top_of_its_own() {
    for (path, log) in logs(&["bitcraze cf21"]) {
        let s = samples(&path, &log);
        let clean = findings(&s);
        let own = clean
            .iter()
            .find(|f| f["effect"] == "dead_time")
            .and_then(|f| f["delay_samples"].as_f64());
        assert!(
            own.is_some_and(|d| (8.0..=12.0).contains(&d)),
            "the load cell's own delay: {clean:?}"
        );
        for k in 0..2 {
            let inj = Injection::draw(
                EffectName::DeadTime,
                &s,
                &mut StdRng::seed_from_u64(1000 + k),
            )
            .unwrap();
            let got = findings(&inject(&s, &inj));
            let o = judge(&inj, &clean, &got);
            assert!(o.within(&inj), "{inj:?} → {o:?}; findings {got:?}");
            let inverse = got
                .iter()
                .filter(|f| f["effect"] == "extra_mode")
                .any(|f| f["gain"].as_f64().is_some_and(|g| g > 1.05));
            assert!(!inverse, "a mode with an inverse response: {got:?}");
        }
    }
}
