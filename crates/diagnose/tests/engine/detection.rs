//! Issue 5, "How we will know": for each effect, 20 seeded cases with random parameters and
//! random plants (even cases underdamped, odd cases overdamped), generated in-process with the
//! simulated plant. The detector sees only the measured throttle, thrust and supply voltage.
//! Each case must name the effect, estimate its parameters within the stated tolerance, name no
//! other effect, and validate the extended model better than the baseline. 50 clean cases
//! measure the false-alarm rate, which must be at most 5 %. The effects of issue 11
//! (`asymmetric_dynamics`, `stiffness_nonlinearity`) are checked on a few cases here and on 20
//! in the detection table.

use propid_diagnose::{self as diagnose, Diagnosis, Finding};
use propid_numerics::EffectName;
use propid_sim::plant::PlantConfig;
use propid_sim::synth::{self, Measured};

const CASES: u64 = 20;

fn run(name: &str, i: u64) -> (PlantConfig, Diagnosis, Measured) {
    let (cfg, m) = synth::case(EffectName::from_name(name), i).expect("valid plant");
    let d = diagnose::diagnose(
        synth::DT_S,
        &m.u,
        &m.y,
        &[],
        Some(&m.voltage),
        &Default::default(),
    )
    .expect("diagnosis");
    (cfg, d, m)
}

fn num(f: &Finding, key: &str) -> f64 {
    f.params
        .get(key)
        .and_then(|v| v.as_f64())
        .unwrap_or_else(|| panic!("finding {} lacks {key}", f.effect))
}

/// Runs every case of `name` and checks naming, uniqueness, gain and `check_params`.
fn check_effect(
    name: &str,
    check_params: impl Fn(&PlantConfig, &Finding, &Measured) -> Result<(), String>,
) {
    check_cases(name, 0..CASES, check_params)
}

/// [`check_effect`] over the cases `cases` only.
fn check_cases(
    name: &str,
    cases: std::ops::Range<u64>,
    check_params: impl Fn(&PlantConfig, &Finding, &Measured) -> Result<(), String>,
) {
    let mut failures = Vec::new();
    for i in cases {
        let (cfg, d, m) = run(name, i);
        let names: Vec<&str> = d.findings.iter().map(|f| f.effect.as_str()).collect();
        let Some(f) = d.findings.iter().find(|f| f.effect.as_str() == name) else {
            failures.push(format!("case {i}: not named (found {names:?})"));
            continue;
        };
        if names.len() != 1 {
            failures.push(format!("case {i}: other effects named too: {names:?}"));
        }
        if let Err(e) = check_params(&cfg, f, &m) {
            failures.push(format!("case {i}: {e}"));
        }
        let ext = d
            .extended
            .as_ref()
            .expect("extended model when an effect is found");
        if ext.fit_percent <= d.baseline.fit_percent {
            failures.push(format!(
                "case {i}: extended fit {:.2} % does not beat baseline {:.2} %",
                ext.fit_percent, d.baseline.fit_percent
            ));
        }
        assert!(f.score.is_finite() && !f.evidence.is_empty());
    }
    assert!(failures.is_empty(), "{name}:\n{}", failures.join("\n"));
}

fn rel(est: f64, truth: f64, tol: f64, what: &str) -> Result<(), String> {
    let e = ((est - truth) / truth).abs();
    if e <= tol {
        Ok(())
    } else {
        Err(format!(
            "{what} {est:.5} vs true {truth:.5} (rel. error {e:.3} > {tol})"
        ))
    }
}

#[test]
fn dead_time_is_found_to_one_sample() {
    check_effect("dead_time", |cfg, f, _| {
        let truth = (cfg.effects.dead_time.as_ref().unwrap().delay_s / synth::DT_S).round();
        let est = num(f, "delay_samples");
        let ok =
            (est - truth).abs() <= 1.0 && (num(f, "delay_s") - est * synth::DT_S).abs() < 1e-12;
        ok.then_some(())
            .ok_or(format!("delay {est} samples vs true {truth}"))
    });
}

#[test]
fn static_nonlinearity_exponent_within_10_percent() {
    check_effect("static_nonlinearity", |cfg, f, _| {
        let p = cfg.effects.static_nonlinearity.as_ref().unwrap().exponent;
        let curv = f
            .params
            .get("curvature")
            .and_then(|v| v.as_str())
            .unwrap_or("");
        let want = if p > 1.0 { "hardens" } else { "softens" };
        if curv != want {
            return Err(format!("curvature {curv} for exponent {p}"));
        }
        rel(num(f, "exponent"), p, 0.10, "exponent")
    });
}

#[test]
fn extra_mode_frequency_within_5_percent_and_damping_within_003() {
    check_effect("extra_mode", |cfg, f, _| {
        let m = cfg.effects.extra_mode.as_ref().unwrap();
        rel(num(f, "fn_hz"), m.fn_hz, 0.05, "fn_hz")?;
        let z = num(f, "zeta");
        ((z - m.zeta).abs() <= 0.03)
            .then_some(())
            .ok_or(format!("zeta {z:.4} vs true {:.4}", m.zeta))
    });
}

#[test]
fn baseline_drift_rate_within_15_percent() {
    check_effect("baseline_drift", |cfg, f, _| {
        let r = cfg.effects.baseline_drift.as_ref().unwrap().rate_per_s;
        rel(num(f, "rate_per_s"), r, 0.15, "rate_per_s")
    });
}

#[test]
fn periodic_disturbance_frequency_within_1_percent_amplitude_within_15_percent() {
    check_effect("periodic_disturbance", |cfg, f, _| {
        let p = cfg.effects.periodic_disturbance.as_ref().unwrap();
        rel(num(f, "freq_hz"), p.freq_hz, 0.01, "freq_hz")?;
        rel(num(f, "amplitude"), p.amplitude, 0.15, "amplitude")
    });
}

/// The simulated stand scales the throttle by `1 + g (V − battery_v)`; diagnose reports the
/// gain per volt at the record's mean voltage `V̄`, the same law when `g_V = g / (1 + g (V̄ −
/// battery_v))`. Measured: median 0.5 %, at most 1.0 % (the detection table); compared with
/// `g` itself the error was 9 % at the median, 13 % at most.
#[test]
fn supply_sag_gain_per_volt_within_3_percent() {
    check_effect("supply_sag", |cfg, f, m| {
        let g = cfg.effects.supply_sag.as_ref().unwrap().gain_per_volt;
        let v_mean = m.voltage.iter().sum::<f64>() / m.voltage.len() as f64;
        let at_mean = g / (1.0 + g * (v_mean - cfg.battery_v));
        rel(num(f, "gain_per_volt"), at_mean, 0.03, "gain_per_volt")
    });
}

#[test]
fn throttle_saturation_level_within_001() {
    check_effect("saturation", |cfg, f, _| {
        let l = cfg.effects.saturation.as_ref().unwrap().level;
        let est = num(f, "level");
        let sig = f.params.get("signal").and_then(|v| v.as_str());
        ((est - l).abs() <= 0.01 && sig == Some("throttle"))
            .then_some(())
            .ok_or(format!("level {est:.4} ({sig:?}) vs true {l:.4}"))
    });
}

// The two effects of issue 11: a few cases here (CI time); the 20-case rates are in the
// detection table (`scripts/detection_table.sh`). Cases 0..4 hold both directions of the
// asymmetry, hardening and softening springs, under- and overdamped plants.

#[test]
fn asymmetric_dynamics_ratio_within_10_percent() {
    check_cases("asymmetric_dynamics", 0..4, |cfg, f, _| {
        let a = cfg.effects.asymmetric_dynamics.as_ref().unwrap();
        let (up, down) = (num(f, "up"), num(f, "down"));
        if ((up * down).sqrt() - 1.0).abs() > 1e-9 {
            return Err(format!(
                "up {up} and down {down} not relative to their mean"
            ));
        }
        rel(
            num(f, "down_over_up"),
            a.down_scale / a.up_scale,
            0.10,
            "down/up",
        )
    });
}

#[test]
fn stiffness_nonlinearity_cubic_coefficient_within_15_percent() {
    check_cases("stiffness_nonlinearity", 0..4, |cfg, f, _| {
        let e = cfg
            .effects
            .stiffness_nonlinearity
            .as_ref()
            .unwrap()
            .k3_per_k1;
        let curv = f.params.get("curvature").and_then(|v| v.as_str());
        let want = if e > 0.0 { "hardens" } else { "softens" };
        if curv != Some(want) {
            return Err(format!("curvature {curv:?} for k3/k1 {e}"));
        }
        rel(num(f, "k3_per_k1"), e, 0.15, "k3_per_k1")
    });
}

#[test]
fn the_new_effects_are_not_named_on_clean_cases() {
    for i in 0..3 {
        let (_, d, _) = run("clean", i);
        let names: Vec<&str> = d.findings.iter().map(|f| f.effect.as_str()).collect();
        assert!(
            !names.contains(&"asymmetric_dynamics") && !names.contains(&"stiffness_nonlinearity"),
            "clean case {i}: {names:?}"
        );
    }
}

#[test]
fn false_alarm_rate_on_50_clean_cases_is_at_most_5_percent() {
    let n = 50;
    // Two threads (CI has two cores); each case is independent and seeded.
    let half = |range: std::ops::Range<u64>| {
        let mut found = Vec::new();
        for i in range {
            let (_, d, _) = run("clean", i);
            if !d.findings.is_empty() {
                found.push((i, d.findings.iter().map(|f| f.effect).collect::<Vec<_>>()));
            } else {
                assert!(d.extended.is_none() && d.gain.is_none());
            }
        }
        found
    };
    let alarms: Vec<_> = std::thread::scope(|s| {
        let a = s.spawn(|| half(0..n / 2));
        let b = s.spawn(|| half(n / 2..n));
        let mut v = a.join().expect("first half");
        v.extend(b.join().expect("second half"));
        v
    });
    let rate = alarms.len() as f64 / n as f64;
    eprintln!(
        "false-alarm rate on {n} clean cases: {:.1} % {alarms:?}",
        100.0 * rate
    );
    assert!(rate <= 0.05, "false-alarm rate {rate} > 5 %: {alarms:?}");
}
