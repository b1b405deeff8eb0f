use nalgebra::Complex;

use super::fit::{fit, start_of, Data, FitOptions};
use super::select::{
    arx_poles, modes_settle_within, select, tail_score_abcd, SelectOptions, Start,
};
use super::OeModel;

/// Deterministic uniform noise in [−1, 1] (an LCG).
fn noise(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

/// A random-level input (held for 7 samples).
fn input(n: usize) -> Vec<f64> {
    let r = noise(n / 7 + 1, 3);
    (0..n).map(|k| 2.0 + r[k / 7]).collect()
}

/// A lightly damped pair `0.9 ± 0.3j` with output map `[1.0, 0.5]`, `D = 0`, about `u₀ = 2`,
/// `y₀ = 5`.
fn pair_system() -> OeModel {
    OeModel {
        integrator: false,
        real: vec![],
        pairs: vec![(0.9, 0.3)],
        c: vec![vec![1.0, 0.5]],
        d: vec![0.0],
        u0: 2.0,
        y0: vec![5.0],
    }
}

#[test]
fn a_second_order_output_error_system_with_noise_is_recovered() {
    let n = 3000;
    let u = input(n);
    let truth = pair_system();
    let clean = truth.simulate(&u, None);
    let e = noise(n, 11);
    let y: Vec<f64> = clean[0].iter().zip(&e).map(|(y, e)| y + 0.05 * e).collect();
    let ys = [y.as_slice()];
    let data = Data {
        u: &u,
        y: &ys,
        missing: &[],
    };
    // Start well away from the truth: 0.7 ± 0.5j.
    let (st, theta) = start_of(&[Complex::new(0.7, 0.5), Complex::new(0.7, -0.5)], false, 1);
    let f = fit(st, &theta, &data, n, &FitOptions::default()).unwrap();
    let (s, w) = f.model.pairs[0];
    assert!(
        (s - 0.9).abs() < 2e-3 && (w - 0.3).abs() < 2e-3,
        "pair {s} {w}"
    );
    let g = f.model.dc_gain().unwrap()[0];
    let g0 = truth.dc_gain().unwrap()[0];
    assert!((g - g0).abs() < 0.01 * g0.abs(), "gain {g} vs {g0}");
    // The residual is the noise: RMS ≈ 0.05/√3.
    let rms = (f.cost / n as f64).sqrt();
    assert!(rms < 0.035, "rms {rms}");
}

#[test]
fn an_integrator_is_kept_and_chosen_on_the_held_out_tail() {
    let n = 4000;
    // Zero-mean input: the plant integrates it (position from force).
    let u: Vec<f64> = input(n).iter().map(|v| v - 2.0).collect();
    let truth = OeModel {
        integrator: true,
        real: vec![0.8],
        pairs: vec![],
        c: vec![vec![0.05, 0.2]],
        d: vec![0.0],
        u0: 0.0,
        y0: vec![1.0],
    };
    let clean = truth.simulate(&u, None);
    let e = noise(n, 5);
    let y: Vec<f64> = clean[0].iter().zip(&e).map(|(y, e)| y + 0.01 * e).collect();
    let ys = [y.as_slice()];
    let data = Data {
        u: &u,
        y: &ys,
        missing: &[],
    };
    // Starts as ERA gives them on such data: a pole just outside the circle and one inside.
    let starts = vec![
        (
            Start::Era,
            vec![Complex::new(1.002, 0.0), Complex::new(0.7, 0.0)],
        ),
        (Start::Era, vec![Complex::new(1.002, 0.0)]),
    ];
    let s = select(&data, &starts, &SelectOptions::default()).unwrap();
    assert!(s.model.integrator, "candidates {:?}", s.candidates);
    assert!(s.model.dc_gain().is_none());
    assert_eq!(s.model.poles()[0], Complex::new(1.0, 0.0));
    assert!((s.model.real[0] - 0.8).abs() < 0.02, "{:?}", s.model.real);
    // The stable variant of the same start is worse on the tail.
    let stable = s
        .candidates
        .iter()
        .filter(|c| !c.integrator)
        .map(|c| c.score)
        .fold(f64::INFINITY, f64::min);
    assert!(s.best().score < stable);
}

#[test]
fn a_start_outside_the_circle_is_brought_in_and_the_fit_stays_stable() {
    let n = 2000;
    let u = input(n);
    let truth = pair_system();
    let y = truth.simulate(&u, None).remove(0);
    let ys = [y.as_slice()];
    let data = Data {
        u: &u,
        y: &ys,
        missing: &[],
    };
    let (st, theta) = start_of(&[Complex::new(1.1, 0.2), Complex::new(1.1, -0.2)], false, 1);
    let f = fit(st, &theta, &data, n, &FitOptions::default()).unwrap();
    assert!(f.model.poles().iter().all(|z| z.norm() < 1.0));
    assert!((f.model.pairs[0].0 - 0.9).abs() < 1e-3);
}

#[test]
fn arx_poles_of_noise_free_data_are_the_plant_poles() {
    let n = 1500;
    let u = input(n);
    let y = pair_system().simulate(&u, None).remove(0);
    let ys = [y.as_slice()];
    let data = Data {
        u: &u,
        y: &ys,
        missing: &[],
    };
    let z = arx_poles(&data, 2, n).unwrap();
    assert!(
        z.iter().any(|z| (z - Complex::new(0.9, 0.3)).norm() < 1e-6),
        "{z:?}"
    );
}

#[test]
fn the_abcd_score_of_the_true_model_is_near_zero_and_a_wrong_one_is_not() {
    let n = 2000;
    let u = input(n);
    let truth = pair_system();
    let y = truth.simulate(&u, None).remove(0);
    let ys = [y.as_slice()];
    let data = Data {
        u: &u,
        y: &ys,
        missing: &[],
    };
    let (a, b, c, d) = truth.abcd();
    let (_, good) = tail_score_abcd(&a, &b, &c, &d, &data, 0.25);
    assert!(good < 1e-6, "{good}");
    let c2 = vec![vec![2.0, 0.5]];
    let (_, bad) = tail_score_abcd(&a, &b, &c2, &d, &data, 0.25);
    assert!(bad > 0.1, "{bad}");
}

#[test]
fn an_integrating_models_other_modes_must_settle_within_a_tenth_of_the_tail() {
    let m = |real: Vec<f64>, pairs: Vec<(f64, f64)>| OeModel {
        integrator: true,
        real,
        pairs,
        c: vec![vec![1.0; 3]],
        d: vec![0.0],
        u0: 0.0,
        y0: vec![0.0],
    };
    // Tail 6210 samples: modes up to 621 samples are judged.
    assert!(modes_settle_within(
        &m(vec![0.9972, -0.96], vec![]),
        6210,
        24841
    ));
    // A second pole at τ ≈ 1720 samples: a second integrator over the tail.
    assert!(!modes_settle_within(
        &m(vec![0.99942, 0.99], vec![]),
        6210,
        24841
    ));
    // A pair that decays fast enough but turns once in 240 000 samples: no oscillation.
    assert!(!modes_settle_within(
        &m(vec![], vec![(0.99714, 2.6e-5)]),
        6210,
        24841
    ));
    assert!(modes_settle_within(
        &m(vec![], vec![(0.9, 0.3)]),
        6210,
        24841
    ));
}
