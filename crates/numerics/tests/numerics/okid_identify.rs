//! OKID + ERA end to end through `identify_any`: exact fn, ζ and DC gain from non-pulse
//! excitation, including records on which the pulse path fails.

use propid_testkit as core_support;

use core_support::Plant;
use propid_numerics::identify::{identify_any, AnyInput, PathTaken};
use propid_numerics::okid::OkidOptions;
use propid_numerics::pulses::PulseInput;
use propid_numerics::workspace::{IdentOptions, Limits, Workspace};
use propid_numerics::IdentError;
use rand::{Rng, SeedableRng};

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn identify(plant: &Plant, u: &[f64], order: Option<usize>) -> propid_numerics::identify::AnyModel {
    let y = plant.simulate(u, 2.0);
    let ys: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
    let us = [u];
    let input = AnyInput {
        dt_s: plant.dt,
        u: &us,
        y: &ys,
        missing: &[],
        pulse_starts: None,
    };
    let ident = IdentOptions {
        order,
        ..IdentOptions::default()
    };
    identify_any(&input, &ident, &OkidOptions::default()).expect("identify")
}

fn staircase(n: usize) -> Vec<f64> {
    (0..n).map(|k| 0.2 + 0.1 * (k / (n / 5)) as f64).collect()
}

fn random(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    (0..n)
        .map(|_| 0.4 + 0.05 * rng.gen_range(-1.0..1.0))
        .collect()
}

fn assert_exact(plant: &Plant, m: &propid_numerics::identify::AnyModel) {
    assert_eq!(m.path, PathTaken::Okid);
    assert_eq!(m.report.order, 2, "{:?}", m.report.singular_values);
    assert!(
        rel(m.report.fn_hz, plant.fn_hz) < 1e-8,
        "fn {}",
        m.report.fn_hz
    );
    assert!(
        rel(m.report.zeta, plant.zeta) < 1e-8,
        "zeta {}",
        m.report.zeta
    );
    assert!(rel(m.report.dc_gain.get(0), plant.dc(0)) < 1e-8);
}

#[test]
fn staircase_fails_the_pulse_path_and_okid_is_exact() {
    let plant = Plant::new(12.0, 0.4, 8.0, 0.002);
    let u = staircase(2000);
    let y = plant.simulate(&u, 2.0);
    let ys = [&y[0][..]];
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let pulse = PulseInput {
        dt_s: plant.dt,
        u: &u,
        y: &ys,
        missing: &[],
        pulse_starts: None,
    };
    assert_eq!(
        ws.identify(&pulse, &IdentOptions::default()).err(),
        Some(IdentError::NoPulse)
    );
    assert_exact(&plant, &identify(&plant, &u, None));
}

#[test]
fn random_input_underdamped_and_overdamped_are_exact() {
    let under = Plant::new(15.0, 0.2, 6.0, 0.002);
    assert_exact(&under, &identify(&under, &random(1500, 1), None));
    let over = Plant::new(4.0, 1.6, 3.0, 0.004);
    assert_exact(&over, &identify(&over, &random(1500, 2), None));
    let two = Plant::new(9.0, 0.5, 2.0, 0.002).with_output([0.3, 0.001], 0.05);
    let m = identify(&two, &random(2000, 3), None);
    assert_exact(&two, &m);
    assert!(rel(m.report.dc_gain.get(1), two.dc(1)) < 1e-8);
}

#[test]
fn clean_pulse_experiment_takes_the_pulse_path() {
    let plant = Plant::new(10.0, 0.3, 5.0, 0.002);
    let mut u = vec![0.4; 3000];
    for s in (100..3000).step_by(400) {
        u[s] = 0.45;
    }
    let m = identify(&plant, &u, None);
    assert_eq!(m.path, PathTaken::Pulse);
    assert!(m.okid.is_none());
    assert!(rel(m.report.fn_hz, plant.fn_hz) < 1e-6);
}

use propid_numerics::operating_points::{operating_points, OpOptions};

fn input_of<'a>(dt: f64, u: &'a [&'a [f64]], y: &'a [&'a [f64]]) -> AnyInput<'a> {
    AnyInput {
        dt_s: dt,
        u,
        y,
        missing: &[],
        pulse_starts: None,
    }
}

#[test]
fn pulses_at_two_levels_give_two_pulse_operating_points() {
    let plant = Plant::new(10.0, 0.3, 5.0, 0.002);
    let mut u: Vec<f64> = (0..6000)
        .map(|k| if k < 3000 { 0.3 } else { 0.5 })
        .collect();
    for s in (200..6000).step_by(400).filter(|s| (s % 3000) > 100) {
        u[s] += 0.05;
    }
    let y = plant.simulate(&u, 1.0);
    let (us, ys) = ([&u[..]], [&y[0][..]]);
    let ident = IdentOptions {
        order: Some(2),
        ..IdentOptions::default()
    };
    let t = operating_points(&input_of(plant.dt, &us, &ys), &ident, &OpOptions::default());
    assert_eq!(t.kind, "staircase");
    assert_eq!(t.points.len(), 2, "{:?}", t.skipped);
    for (p, level) in t.points.iter().zip([0.3, 0.5]) {
        assert_eq!(p.path, PathTaken::Pulse);
        assert!((p.level - level).abs() < 1e-12);
        assert!(rel(p.fn_hz, 10.0) < 1e-6, "{}", p.fn_hz);
    }
}

#[test]
fn a_ramp_is_cut_into_windows() {
    let plant = Plant::new(6.0, 0.8, 3.0, 0.004);
    let mut rng = rand::rngs::StdRng::seed_from_u64(4);
    let u: Vec<f64> = (0..4000)
        .map(|k| 0.2 + 0.5 * k as f64 / 4000.0 + 0.01 * rng.gen_range(-1.0..1.0))
        .collect();
    let y = plant.simulate(&u, 0.0);
    let (us, ys) = ([&u[..]], [&y[0][..]]);
    let t = operating_points(
        &input_of(plant.dt, &us, &ys),
        &IdentOptions::default(),
        &OpOptions::default(),
    );
    assert_eq!(t.kind, "ramp");
    assert_eq!(t.points.len(), 4, "{:?}", t.skipped);
    assert!(t.points.windows(2).all(|w| w[1].level > w[0].level));
    for p in &t.points {
        assert!(rel(p.dc_gain.get(0), plant.dc(0)) < 1e-6, "{:?}", p.dc_gain);
    }
}

#[test]
fn random_input_is_a_single_operating_point() {
    let plant = Plant::new(6.0, 0.8, 3.0, 0.004);
    let u = random(2000, 8);
    let y = plant.simulate(&u, 0.0);
    let (us, ys) = ([&u[..]], [&y[0][..]]);
    let t = operating_points(
        &input_of(plant.dt, &us, &ys),
        &IdentOptions::default(),
        &OpOptions::default(),
    );
    assert_eq!(t.kind, "single");
    assert!(t.points.is_empty() && t.skipped.is_empty());
}
