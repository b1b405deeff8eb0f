//! Issue 11, item 3: honest verdicts. A clean simulated case is `explained` with the noise
//! floor measured within 20 % of the injected noise; a case with a hidden effect is
//! `effects_found`; a record whose thrust falls as the command rises is warned about.

use propid_diagnose::verdict::{VerdictKind, WarningKind};
use propid_diagnose::{self as diagnose, noise::FloorSource, Diagnosis};
use propid_numerics::EffectName;
use propid_sim::synth;

fn run(u: &[f64], y: &[f64], v: &[f64]) -> Diagnosis {
    diagnose::diagnose(synth::DT_S, u, y, &[], Some(v), &Default::default()).expect("diagnosis")
}

#[test]
fn clean_cases_are_explained_with_the_injected_noise_as_floor() {
    for i in 0..6 {
        let (cfg, m) = synth::case(None, i).unwrap();
        let d = run(&m.u, &m.y, &m.voltage);
        let f = d.noise_floor.expect("a noise floor");
        eprintln!(
            "clean {i}: floor {:.5} (true {:.5}), residual {:?}, verdict {:?}",
            f.rms, cfg.noise_rms_n, d.residual, d.verdict
        );
        assert_eq!(f.from, FloorSource::SteadyHolds);
        let rel = (f.rms / cfg.noise_rms_n - 1.0).abs();
        assert!(rel < 0.2, "case {i}: floor {f:?} vs {}", cfg.noise_rms_n);
        if d.findings.is_empty() {
            assert_eq!(
                d.verdict.kind,
                VerdictKind::Explained,
                "case {i}: {:?}",
                d.verdict
            );
        }
        assert!(d.warnings.is_empty(), "case {i}: {:?}", d.warnings);
    }
}

#[test]
fn a_found_effect_that_reaches_the_floor_is_effects_found() {
    for name in ["dead_time", "static_nonlinearity"] {
        let (_, m) = synth::case(EffectName::from_name(name), 0).unwrap();
        let d = run(&m.u, &m.y, &m.voltage);
        eprintln!("{name}: residual {:?}, verdict {:?}", d.residual, d.verdict);
        assert!(!d.findings.is_empty(), "{name}");
        assert_eq!(
            d.verdict.kind,
            VerdictKind::EffectsFound,
            "{name}: {:?}",
            d.verdict
        );
        let e = d.residual.extended_rms.expect("extended residual");
        assert!(e < d.residual.baseline_rms, "{name}: {:?}", d.residual);
    }
}

#[test]
fn a_large_unmodelled_error_is_unexplained_not_explained() {
    // The output of a clean case plus a slow sawtooth no effect in the catalogue describes.
    let (_, m) = synth::case(None, 0).unwrap();
    let y: Vec<f64> =
        m.y.iter()
            .enumerate()
            .map(|(k, v)| v + 0.5 * ((k % 977) as f64 / 977.0 - 0.5))
            .collect();
    let d = run(&m.u, &y, &m.voltage);
    assert_eq!(d.verdict.kind, VerdictKind::Unexplained, "{:?}", d.verdict);
    assert!(d.verdict.unexplained_share > 0.5, "{:?}", d.verdict);
}

#[test]
fn thrust_that_falls_with_the_command_is_a_nonpositive_gain_warning() {
    let (_, m) = synth::case(None, 0).unwrap();
    let u: Vec<f64> = m.u.iter().map(|v| 1.0 - v).collect();
    let d = run(&u, &m.y, &m.voltage);
    assert!(
        d.warnings
            .iter()
            .any(|w| w.kind == WarningKind::NonpositiveGain && w.model == "baseline"),
        "{:?}",
        d.warnings
    );
    let text = serde_json::to_string(&d).unwrap();
    assert!(text.contains(r#""kind":"nonpositive_gain""#), "{text}");
}
