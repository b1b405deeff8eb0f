//! The stand baseline on records the stand model generated (rpm and thrust at 100 Hz, a
//! staircase up and down): which baseline is chosen and why, and a load cell's lag hidden in
//! the thrust (drawn from a seed by the test kit's injector) found as `sensor_lag` with its
//! delay and lag.

use propid_numerics::segment::SegmentRules;
use propid_numerics::stand_model::fit::Channel;
use propid_numerics::stand_model::{
    simulate, CurrentLaw, Quantity, RotorLaw, Sensor, SpeedMap, StandParams, Supply,
};
use propid_numerics::EffectName;
use propid_testkit::inject::{inject, tolerance, Injection, Samples};
use rand::rngs::StdRng;
use rand::SeedableRng;

use super::{choose, BaselineKind, StandInput};
use crate::{diagnose_with, Diagnosis, Options};

const DT: f64 = 0.01;

fn truth() -> StandParams {
    StandParams {
        dead_time_s: 0.03,
        map: SpeedMap {
            speed_ref: 20_000.0,
            command_zero: 0.05,
            command_ref: 0.9,
            exponent: 1.0,
            voltage_ref: 16.0,
        },
        rotor: RotorLaw {
            tau_up_s: 0.04,
            tau_down_s: 0.06,
            tau_speed_exponent: 0.0,
            speed_ref: 20_000.0,
        },
        thrust_exponent: 2.0,
        k_t: 15.0 / (20_000.0f64 * 20_000.0),
        k_q: 0.0,
        current: CurrentLaw::default(),
        supply: Supply {
            open_circuit_v: 16.0,
            resistance_ohm: 0.0,
        },
    }
}

fn staircase() -> Vec<f64> {
    let levels = [0.3, 0.5, 0.4, 0.7, 0.9, 0.6, 0.8, 0.35, 0.75, 0.3];
    let per = (1.5 / DT) as usize;
    levels
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(per))
        .collect()
}

/// rpm and thrust of the stand (no sensor lag on either), with seeded noise.
fn record(seed: u64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let u = staircase();
    let ch = simulate(
        &truth(),
        DT,
        &u,
        None,
        &[
            (Quantity::Speed, Sensor::default()),
            (Quantity::Thrust, Sensor::default()),
        ],
    );
    let rpm_noise = propid_testkit::gaussian(u.len(), 20.0, seed);
    let thrust_noise = propid_testkit::gaussian(u.len(), 0.01, seed + 1000);
    let rpm = ch[0].iter().zip(&rpm_noise).map(|(a, b)| a + b).collect();
    let thrust = ch[1]
        .iter()
        .zip(&thrust_noise)
        .map(|(a, b)| a + b)
        .collect();
    (u, rpm, thrust)
}

fn run(u: &[f64], rpm: &[f64], thrust: &[f64]) -> Diagnosis {
    let stand = StandInput {
        channels: vec![
            Channel {
                key: "rpm",
                quantity: Quantity::Speed,
                y: rpm,
                interpolated: &[],
            },
            Channel {
                key: "thrust",
                quantity: Quantity::Thrust,
                y: thrust,
                interpolated: &[],
            },
        ],
        output: Some("thrust"),
    };
    diagnose_with(DT, u, thrust, &[], None, Some(&stand), &Options::default()).unwrap()
}

#[test]
fn the_baseline_is_chosen_by_the_data_and_says_why() {
    let (_, rpm, thrust) = record(1);
    let rules = SegmentRules::for_record(DT, true);
    let ch = |key, quantity, y| Channel {
        key,
        quantity,
        y,
        interpolated: &[],
    };
    let both = StandInput {
        channels: vec![
            ch("rpm", Quantity::Speed, &rpm),
            ch("thrust", Quantity::Thrust, &thrust),
        ],
        output: Some("thrust"),
    };
    let c = choose(true, Some(&both), &rules);
    assert_eq!(c.kind, BaselineKind::Stand, "{c:?}");
    assert!(c.why.contains("rpm, thrust"), "{c:?}");
    // a signal in its own units, no stand channel, an output that is none of them, a table
    // of steady states: the generic baseline, each with its reason
    assert_eq!(
        choose(false, Some(&both), &rules).kind,
        BaselineKind::Generic
    );
    assert_eq!(choose(true, None, &rules).kind, BaselineKind::Generic);
    let other = StandInput {
        output: None,
        ..both.clone()
    };
    let c = choose(true, Some(&other), &rules);
    assert!(c.why.contains("none of the stand"), "{c:?}");
    // a thrust alone: the rotor's lag and the load cell's cannot be told apart
    let alone = StandInput {
        channels: vec![ch("thrust", Quantity::Thrust, &thrust)],
        output: Some("thrust"),
    };
    let c = choose(true, Some(&alone), &rules);
    assert_eq!(c.kind, BaselineKind::Generic, "{c:?}");
    assert!(c.why.contains("rotor's speed"), "{c:?}");
    let steady = SegmentRules::for_record(2.0, true);
    let c = choose(true, Some(&both), &steady);
    assert_eq!(c.kind, BaselineKind::Generic, "{c:?}");
}

#[test]
fn a_clean_stand_names_its_own_parts_and_no_spring_nor_sensor_lag() {
    let (u, rpm, thrust) = record(2);
    let d = run(&u, &rpm, &thrust);
    assert_eq!(d.baseline.choice.kind, BaselineKind::Stand);
    // chosen on the held-out figures of both searches, said with them
    let why = &d.baseline.choice.why;
    assert!(
        why.contains("held out on thrust") && why.contains("generic search"),
        "{why}"
    );
    let names: Vec<EffectName> = d.findings.iter().map(|f| f.effect).collect();
    assert!(
        !names.contains(&EffectName::StiffnessNonlinearity),
        "{names:?}"
    );
    assert!(!names.contains(&EffectName::SensorLag), "{names:?}");
    // the stand's own dead time is what the baseline (no dead time) misses most
    assert!(names.contains(&EffectName::DeadTime), "{names:?}");
    let st = d.stand.as_ref().unwrap();
    assert!(st.channels.contains_key("rpm") && st.channels.contains_key("thrust"));
    assert!(st.mean_fit_percent > st.baseline_mean_fit_percent);
    assert!(d.stand_baseline().is_some());
    let dead = d
        .findings
        .iter()
        .find(|f| f.effect == EffectName::DeadTime)
        .and_then(|f| f.params["delay_s"].as_f64())
        .unwrap();
    assert!((dead - 0.03).abs() < DT, "{dead}");
}

#[test]
fn a_load_cells_lag_hidden_in_the_thrust_is_found_as_a_sensor_lag_with_its_figures() {
    for seed in 0..3u64 {
        let (u, rpm, thrust) = record(10 + seed);
        let s = Samples {
            dt_s: DT,
            t0_s: 0.0,
            u: u.clone(),
            y: thrust,
            voltage: None,
        };
        let mut rng = StdRng::seed_from_u64(seed);
        let inj = Injection::draw(EffectName::SensorLag, &s, &mut rng).unwrap();
        let Injection::SensorLag { delay_s, tau_s, .. } = inj else {
            unreachable!()
        };
        let lagged = inject(&s, &inj).y;
        let d = run(&u, &rpm, &lagged);
        let f = d
            .findings
            .iter()
            .find(|f| f.effect == EffectName::SensorLag)
            .unwrap_or_else(|| panic!("#{seed} {inj:?}: {:?}", d.findings));
        assert_eq!(f.params["channel"], "thrust");
        let (d_got, t_got) = (
            f.params["delay_s"].as_f64().unwrap(),
            f.params["tau_s"].as_f64().unwrap(),
        );
        assert!(
            (d_got - delay_s).abs() <= DT,
            "#{seed} delay {d_got} vs {delay_s}"
        );
        assert!(
            (t_got / tau_s - 1.0).abs() <= tolerance(&inj),
            "#{seed} tau {t_got} vs {tau_s}"
        );
        let names: Vec<EffectName> = d.findings.iter().map(|f| f.effect).collect();
        assert!(
            !names.contains(&EffectName::StiffnessNonlinearity),
            "{names:?}"
        );
    }
}
