//! Noise-free exact recovery of fn, ζ and DC gain (issue 2, "How we will know").

use propid_testkit as core_support;

use core_support::{record_input, rel, throttle, Plant, PulseSpec};
use propid_numerics::{IdentOptions, Limits, MarkovSeq, Workspace};

fn identify(plant: &Plant, u: &[f64], order: Option<usize>) -> propid_numerics::ModelReport {
    let y = plant.simulate(u, 3.0);
    let chans: Vec<&[f64]> = y.iter().map(|c| &c[..]).collect();
    let input = record_input(plant.dt, u, &chans);
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let opts = IdentOptions {
        order,
        ..IdentOptions::default()
    };
    ws.identify(&input, &opts).unwrap().to_report()
}

fn check(plant: &Plant, u: &[f64]) -> propid_numerics::ModelReport {
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
    let input = record_input(plant.dt, &u, &chans);
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

/// Regression: a Hankel matrix that starts at `Y_0 = D` has one rank too many and biases a
/// 2nd-order model; ours starts at `Y_1` and is exact.
#[test]
fn hankel_starting_at_y0_biases_a_second_order_model() {
    let mut plant = Plant::new(10.0, 0.2, 4.0, 0.005);
    plant.d[0] = 0.8;
    let exact = plant.markov(300);
    let mut shifted = vec![0.0];
    shifted.extend_from_slice(&exact[..299]);
    let opts = IdentOptions {
        order: Some(2),
        ..IdentOptions::default()
    };
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let good = ws
        .identify_markov(&MarkovSeq::from_data(1, 1, exact).unwrap(), plant.dt, &opts)
        .unwrap()
        .to_report();
    let bad = ws
        .identify_markov(
            &MarkovSeq::from_data(1, 1, shifted).unwrap(),
            plant.dt,
            &opts,
        )
        .unwrap()
        .to_report();
    assert!(rel(good.fn_hz, 10.0) < 1e-8 && rel(good.zeta, 0.2) < 1e-8);
    assert!((good.d[0][0] - 0.8).abs() < 1e-12);
    let bias = rel(bad.fn_hz, 10.0).max(rel(bad.zeta, 0.2));
    assert!(
        bias.is_nan() || bias > 1e-3,
        "Y_0 in the Hankel should bias the model, got {bias}"
    );
}

/// Regression: the one-sample convention. Scaling the Markov parameters as a unit-area impulse
/// (`Y_k / dt`) makes the DC gain wrong by exactly the sample rate; the pulse path does not.
#[test]
fn unit_area_scaling_makes_dc_gain_off_by_the_sample_rate() {
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005);
    let fs = 1.0 / plant.dt;
    let area: Vec<f64> = plant.markov(300).iter().map(|y| y * fs).collect();
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let r = ws
        .identify_markov(
            &MarkovSeq::from_data(1, 1, area).unwrap(),
            plant.dt,
            &IdentOptions::default(),
        )
        .unwrap()
        .to_report();
    assert!(rel(r.dc_gain.get(0) / plant.dc(0), fs) < 1e-8);
    let u = throttle(2400, &[(0, 0.4)], &pulses(100, 400, 5, &[1]));
    let ours = identify(&plant, &u, None);
    assert!(rel(ours.dc_gain.get(0), 4.0) < 1e-8);
}

/// The truncated (FFT + Lanczos) path gives the dense path's model, pulse and Markov entries.
#[test]
fn truncated_svd_path_matches_dense() {
    use propid_numerics::SvdChoice;
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005).with_output([0.3, 0.02], 0.1);
    let u = throttle(2400, &[(0, 0.4)], &pulses(100, 400, 5, &[1, 2]));
    let y = plant.simulate(&u, 3.0);
    let chans: Vec<&[f64]> = y.iter().map(|c| &c[..]).collect();
    let input = record_input(plant.dt, &u, &chans);
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let opts = IdentOptions {
        svd: SvdChoice::Truncated,
        ..IdentOptions::default()
    };
    let r = ws.identify(&input, &opts).unwrap().to_report();
    assert_eq!((r.order, r.svd.as_str()), (2, "truncated"));
    assert!(
        rel(r.fn_hz, 10.0) < 1e-8 && rel(r.zeta, 0.2) < 1e-8,
        "{} {}",
        r.fn_hz,
        r.zeta
    );
    assert!(rel(r.dc_gain.get(0), plant.dc(0)) < 1e-8 && rel(r.dc_gain.get(1), plant.dc(1)) < 1e-8);
    let markov = MarkovSeq::from_data(2, 1, plant.markov(300)).unwrap();
    let r = ws
        .identify_markov(&markov, plant.dt, &opts)
        .unwrap()
        .to_report();
    assert!(rel(r.fn_hz, 10.0) < 1e-8 && rel(r.zeta, 0.2) < 1e-8);
}
