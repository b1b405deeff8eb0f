//! Noise-free exact recovery of fn, ζ and DC gain (issue 2, "How we will know").

mod core_support;

use core_support::{rel, throttle, Plant, PulseSpec};
use propid::core::{IdentOptions, Limits, MarkovSeq, PulseInput, Workspace};

fn identify(plant: &Plant, u: &[f64], order: Option<usize>) -> propid::core::ModelReport {
    let y = plant.simulate(u, 3.0);
    let chans: Vec<&[f64]> = y.iter().map(|c| &c[..]).collect();
    let input = PulseInput {
        dt_s: plant.dt,
        u,
        y: &chans,
        missing: &[],
        pulse_starts: None,
    };
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let opts = IdentOptions {
        order,
        ..IdentOptions::default()
    };
    ws.identify(&input, &opts).unwrap().to_report()
}

fn check(plant: &Plant, u: &[f64]) -> propid::core::ModelReport {
    let r = identify(plant, u, None);
    assert_eq!(r.order, 2, "{r:?}");
    assert!(
        rel(r.fn_hz, plant.fn_hz) < 1e-8,
        "fn {} vs {}",
        r.fn_hz,
        plant.fn_hz
    );
    assert!(
        rel(r.zeta, plant.zeta) < 1e-8,
        "zeta {} vs {}",
        r.zeta,
        plant.zeta
    );
    assert!(
        rel(r.dc_gain.get(0), plant.dc(0)) < 1e-8,
        "dc {:?} vs {}",
        r.dc_gain,
        plant.dc(0)
    );
    r
}

/// Pulses spaced `gap` apart from `first`, cycling widths, signs and amplitudes.
fn pulses(first: usize, gap: usize, count: usize, widths: &[usize]) -> Vec<PulseSpec> {
    (0..count)
        .map(|i| {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            let amp = [0.05, 0.1, 0.02][i % 3];
            (first + i * gap, widths[i % widths.len()], sign * amp)
        })
        .collect()
}

#[test]
fn underdamped_siso_one_sample_pulses() {
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005);
    let u = throttle(2400, &[(0, 0.4)], &pulses(100, 400, 5, &[1]));
    let r = check(&plant, &u);
    assert_eq!(r.pulses, 5);
}

#[test]
fn pulse_widths_two_and_five_mixed_signs_and_amplitudes() {
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005);
    for widths in [&[2][..], &[5][..], &[1, 2, 5][..]] {
        let u = throttle(2400, &[(0, 0.4)], &pulses(100, 400, 5, widths));
        check(&plant, &u);
    }
}

#[test]
fn overdamped_siso() {
    let plant = Plant::new(4.0, 1.6, 2.5, 0.005);
    let u = throttle(4200, &[(0, 0.3)], &pulses(100, 800, 5, &[1, 3]));
    let r = check(&plant, &u);
    assert_eq!(r.time_constants_s.len(), 2);
}

#[test]
fn several_operating_points_in_one_record() {
    let plant = Plant::new(8.0, 0.35, 3.0, 0.005);
    // Level 0.3, then a step to 0.5 at 1300 (settles well before the next pulse at 1700).
    let mut p = pulses(100, 400, 3, &[1]);
    p.extend(pulses(1700, 400, 3, &[2]));
    let u = throttle(2900, &[(0, 0.3), (1300, 0.5)], &p);
    let r = check(&plant, &u);
    assert_eq!(r.pulses, 6);
}

#[test]
fn two_outputs() {
    let plant = Plant::new(12.0, 0.25, 4.0, 0.004).with_output([0.3, 0.02], 0.1);
    let u = throttle(2400, &[(0, 0.5)], &pulses(100, 450, 5, &[1, 2]));
    let r = check(&plant, &u);
    assert!(rel(r.dc_gain.get(1), plant.dc(1)) < 1e-8);
    assert_eq!(r.d.len(), 2);
}

#[test]
fn given_markov_parameters() {
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005).with_output([0.0, 0.01], 0.0);
    let markov = MarkovSeq::from_data(2, 1, plant.markov(300)).unwrap();
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let r = ws
        .identify_markov(&markov, plant.dt, &IdentOptions::default())
        .unwrap()
        .to_report();
    assert_eq!(r.order, 2);
    assert!(rel(r.fn_hz, 10.0) < 1e-8 && rel(r.zeta, 0.2) < 1e-8);
    assert!(rel(r.dc_gain.get(0), plant.dc(0)) < 1e-8);
}

#[test]
fn state_space_simulation_reproduces_the_markov_parameters() {
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005);
    let u = throttle(2400, &[(0, 0.4)], &pulses(100, 400, 5, &[1]));
    let y = plant.simulate(&u, 0.0);
    let chans = [&y[0][..]];
    let input = PulseInput {
        dt_s: plant.dt,
        u: &u,
        y: &chans,
        missing: &[],
        pulse_starts: None,
    };
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let ss = ws
        .identify(&input, &IdentOptions::default())
        .unwrap()
        .state_space();
    let mut imp = vec![0.0; 50];
    imp[0] = 1.0;
    let mut out = vec![0.0; 50];
    ss.simulate(&imp, &mut out).unwrap();
    let want = plant.markov(50);
    for k in 0..50 {
        assert!((out[k] - want[k]).abs() < 1e-9 * plant.gain, "k={k}");
    }
}
