//! OKID recovers the Markov parameters of known systems from random, step, chirp and multisine
//! input: noise-free to 1e-8 (relative to the largest block), and with output noise a bias whose
//! size is pinned here (see also `okid_noise` for the Monte Carlo after ERA).

use nalgebra::{DMatrix, DVector};
use propid_numerics::okid::{gap_observer_order, okid, usable_rows, OkidError, OkidOptions};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

/// A discrete state-space system for the tests.
struct Sys {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
}

impl Sys {
    fn p(&self) -> usize {
        self.b.ncols()
    }
    fn q(&self) -> usize {
        self.c.nrows()
    }

    /// `Y_0 = D`, `Y_k = C A^(k-1) B`, in the project layout.
    fn markov(&self, len: usize) -> Vec<f64> {
        let mut out = Vec::new();
        out.extend(self.d.iter());
        let mut ak_b = self.b.clone();
        for _ in 1..len {
            out.extend((&self.c * &ak_b).iter());
            ak_b = &self.a * ak_b;
        }
        out
    }

    /// Simulates from steady state at the first input sample.
    fn simulate(&self, u: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let n = u[0].len();
        let u_at = |k: usize| DVector::from_iterator(self.p(), u.iter().map(|c| c[k]));
        let eye = DMatrix::<f64>::identity(self.a.nrows(), self.a.nrows());
        let mut x = (eye - &self.a).lu().solve(&(&self.b * u_at(0))).unwrap();
        let mut y = vec![Vec::with_capacity(n); self.q()];
        for k in 0..n {
            let uk = u_at(k);
            let yk = &self.c * &x + &self.d * &uk;
            for (i, ch) in y.iter_mut().enumerate() {
                ch.push(yk[i]);
            }
            x = &self.a * x + &self.b * uk;
        }
        y
    }
}

/// Second-order SISO with discrete poles `r e^{±iθ}` (or two real poles), thrust-like gain.
fn second_order(p1: (f64, f64), real: bool, d: f64) -> Sys {
    let (tr, det) = if real {
        (p1.0 + p1.1, p1.0 * p1.1)
    } else {
        (2.0 * p1.0 * p1.1.cos(), p1.0 * p1.0)
    };
    Sys {
        a: DMatrix::from_row_slice(2, 2, &[tr, -det, 1.0, 0.0]),
        b: DMatrix::from_row_slice(2, 1, &[1.0, 0.0]),
        c: DMatrix::from_row_slice(1, 2, &[0.8, 0.5]),
        d: DMatrix::from_row_slice(1, 1, &[d]),
    }
}

fn underdamped() -> Sys {
    second_order((0.95, 0.12), false, 0.0)
}

fn overdamped() -> Sys {
    second_order((0.9, 0.6), true, 0.0)
}

/// Two outputs (thrust and rotor speed, say), one input, a direct feed-through.
fn two_output() -> Sys {
    Sys {
        a: DMatrix::from_row_slice(3, 3, &[0.9, 0.2, 0.0, -0.2, 0.9, 0.1, 0.0, 0.0, 0.7]),
        b: DMatrix::from_row_slice(3, 1, &[0.5, 1.0, 0.3]),
        c: DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.5, 0.2, 0.7, 0.0]),
        d: DMatrix::from_row_slice(2, 1, &[0.1, 0.0]),
    }
}

/// Two inputs, two outputs, third order.
fn mimo() -> Sys {
    Sys {
        a: DMatrix::from_row_slice(3, 3, &[0.8, 0.3, 0.0, -0.3, 0.8, 0.0, 0.0, 0.1, 0.5]),
        b: DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 0.5, 0.4, 1.0]),
        c: DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.2, 0.0, 1.0, 1.0]),
        d: DMatrix::from_row_slice(2, 2, &[0.0, 0.2, 0.0, 0.0]),
    }
}

fn random_input(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    (0..n)
        .map(|_| 0.4 + 0.1 * rng.gen_range(-1.0..1.0))
        .collect()
}

fn step_input(n: usize, at: usize) -> Vec<f64> {
    (0..n).map(|k| if k < at { 0.3 } else { 0.45 }).collect()
}

/// Linear chirp from 0 to half the Nyquist frequency.
fn chirp_input(n: usize) -> Vec<f64> {
    let nf = n as f64;
    (0..n)
        .map(|k| {
            let t = k as f64;
            let phase = std::f64::consts::PI * 0.5 * t * t / (2.0 * nf);
            0.4 + 0.05 * phase.sin()
        })
        .collect()
}

/// Random-phase multisine with `m` harmonics of `1/n` spread over the band.
fn multisine_input(n: usize, m: usize, seed: u64) -> Vec<f64> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let phases: Vec<f64> = (0..m)
        .map(|_| rng.gen_range(0.0..std::f64::consts::TAU))
        .collect();
    (0..n)
        .map(|k| {
            let s: f64 = phases
                .iter()
                .enumerate()
                .map(|(h, ph)| {
                    let f = (3 * h + 1) as f64 / n as f64;
                    (std::f64::consts::TAU * f * k as f64 + ph).sin()
                })
                .sum();
            0.4 + 0.02 * s / (m as f64).sqrt()
        })
        .collect()
}

fn run(sys: &Sys, u: &[Vec<f64>], opts: &OkidOptions) -> propid_numerics::okid::OkidResult {
    let y = sys.simulate(u);
    let us: Vec<&[f64]> = u.iter().map(|c| c.as_slice()).collect();
    let ys: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
    okid(&us, &ys, None, opts).expect("okid")
}

/// Largest absolute error over the blocks, relative to the largest block entry.
fn rel_err(sys: &Sys, r: &propid_numerics::okid::OkidResult) -> f64 {
    let truth = sys.markov(r.len);
    let scale = truth.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let err = truth
        .iter()
        .zip(&r.markov)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    err / scale
}

fn assert_exact(sys: &Sys, u: Vec<Vec<f64>>, what: &str) {
    let r = run(sys, &u, &OkidOptions::default());
    let e = rel_err(sys, &r);
    assert!(
        e < 1e-8,
        "{what}: relative Markov error {e:e} (ell {}, rank {}/{}, cond {:e})",
        r.observer_order,
        r.rank,
        r.params,
        r.condition
    );
    assert!(r.markov.iter().all(|v| v.is_finite()));
}

#[test]
fn noise_free_random_input_is_exact() {
    assert_exact(&underdamped(), vec![random_input(800, 1)], "underdamped");
    assert_exact(&overdamped(), vec![random_input(800, 2)], "overdamped");
    assert_exact(&two_output(), vec![random_input(1200, 3)], "two-output");
    let u = vec![random_input(1500, 4), random_input(1500, 5)];
    assert_exact(&mimo(), u, "mimo");
}

#[test]
fn noise_free_step_from_rest_is_exact() {
    // One step from an operating point: the regressor is rank deficient, the minimum-norm
    // solution still reproduces the record and hence the Markov parameters.
    assert_exact(
        &underdamped(),
        vec![step_input(600, 100)],
        "underdamped step",
    );
    assert_exact(&overdamped(), vec![step_input(600, 100)], "overdamped step");
    assert_exact(&two_output(), vec![step_input(900, 150)], "two-output step");
}

#[test]
fn noise_free_step_with_many_lags_is_regularised_and_exact() {
    // With 20 lags a single step cannot give a full-rank regressor (the input window takes only
    // 22 distinct values): the truncated SVD drops directions, says so, and stays exact.
    let opts = OkidOptions {
        observer_order: Some(20),
        ..OkidOptions::default()
    };
    let sys = underdamped();
    let r = run(&sys, &[step_input(600, 100)], &opts);
    assert!(r.regularised, "rank {} of {}", r.rank, r.params);
    assert!(r.rank < r.params);
    assert!(r.condition.is_finite() && r.condition > 1e10);
    assert!(rel_err(&sys, &r) < 1e-8);
}

#[test]
fn noise_free_data_choose_the_deadbeat_observer_order() {
    let r = run(
        &underdamped(),
        &[random_input(800, 1)],
        &OkidOptions::default(),
    );
    assert!(r.observer_order_chosen);
    assert_eq!(r.observer_order, 2);
    assert_eq!(r.observer_order_max, 40);
    let r = run(
        &two_output(),
        &[random_input(1200, 3)],
        &OkidOptions::default(),
    );
    assert_eq!(r.observer_order, 2, "n = 3, q = 2: ceil(n/q) = 2");
    let r = run(&overdamped(), &[chirp_input(1000)], &OkidOptions::default());
    assert_eq!(r.observer_order, 2);
}

#[test]
fn noise_free_chirp_is_exact() {
    assert_exact(&underdamped(), vec![chirp_input(1000)], "underdamped chirp");
    assert_exact(&overdamped(), vec![chirp_input(1000)], "overdamped chirp");
    assert_exact(&two_output(), vec![chirp_input(1500)], "two-output chirp");
}

#[test]
fn noise_free_multisine_is_exact() {
    assert_exact(
        &underdamped(),
        vec![multisine_input(1024, 60, 7)],
        "underdamped",
    );
    assert_exact(
        &overdamped(),
        vec![multisine_input(1024, 60, 8)],
        "overdamped",
    );
    assert_exact(
        &two_output(),
        vec![multisine_input(2048, 100, 9)],
        "two-output",
    );
}

#[test]
fn noise_free_random_is_exact_with_any_observer_order_above_the_deadbeat_one() {
    for ell in [2, 3, 8, 25] {
        let opts = OkidOptions {
            observer_order: Some(ell),
            markov_len: Some(60),
            ..OkidOptions::default()
        };
        let r = run(&underdamped(), &[random_input(800, 11)], &opts);
        assert_eq!(r.observer_order, ell);
        assert_eq!(r.len, 60);
        assert!(rel_err(&underdamped(), &r) < 1e-8, "ell {ell}");
    }
}

#[test]
fn observer_order_too_small_for_the_system_is_not_exact() {
    // ℓ·q < n: no deadbeat observer exists, the regression cannot be exact (guards the
    // exactness tests against passing for a trivial reason).
    let opts = OkidOptions {
        observer_order: Some(1),
        ..OkidOptions::default()
    };
    let r = run(&underdamped(), &[random_input(800, 12)], &opts);
    assert!(rel_err(&underdamped(), &r) > 1e-3);
}

#[test]
fn missing_samples_skip_their_rows_and_stay_exact() {
    let sys = underdamped();
    let u = vec![random_input(800, 13)];
    let mut y = sys.simulate(&u);
    let mut u = u;
    let mut missing = vec![false; 800];
    for k in 300..310 {
        missing[k] = true;
        y[0][k] = f64::NAN;
        u[0][k] = f64::NAN;
    }
    let opts = OkidOptions::default();
    let r = okid(&[&u[0]], &[&y[0]], Some(&missing), &opts).unwrap();
    assert_eq!(r.rows_skipped, 10 + r.observer_order_max);
    assert!(rel_err(&sys, &r) < 1e-8);
}

#[test]
fn rows_with_a_whole_window_are_counted() {
    // Samples 3 and 9 of 12 lost: with 2 lags a row k ≥ 2 needs k−2..=k present.
    let lost = |k: usize| k == 3 || k == 9;
    let rows: Vec<usize> = (0..12usize)
        .filter(|&k| k >= 2 && !(k - 2..=k).any(lost))
        .collect();
    assert_eq!(rows, [2, 6, 7, 8]);
    assert_eq!(usable_rows(12, 2, &lost), 4);
    assert_eq!(usable_rows(12, 0, &lost), 10);
    assert_eq!(usable_rows(12, 2, &|_| false), 10);
    // Without a gap the rule is the automatic order's own: nothing below 40 is needed for
    // 800 samples (800 ≥ 20·40), and the largest order below it is taken.
    assert_eq!(gap_observer_order(800, 1, 1, 40, &|_| false), Some(39));
    assert_eq!(gap_observer_order(6, 1, 1, 1, &|_| false), None);
}

#[test]
fn randomly_lost_samples_lower_the_automatic_observer_order_instead_of_failing() {
    // 5 % of 800 samples lost at random: at the automatic order (40 lags) a row keeps its
    // whole window with probability 0.95^41 ≈ 12 %, fewer than the 164 rows 82 parameters
    // need. The order falls to what the rows allow, and the recovery stays exact; an order
    // given by the caller is not lowered.
    let sys = underdamped();
    let u = vec![random_input(800, 21)];
    let mut y = sys.simulate(&u);
    let mut u = u;
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let mut missing = vec![false; 800];
    for k in 0..800 {
        if rng.gen_range(0.0..1.0) < 0.05 {
            missing[k] = true;
            y[0][k] = f64::NAN;
            u[0][k] = f64::NAN;
        }
    }
    let given = OkidOptions {
        observer_order: Some(40),
        ..OkidOptions::default()
    };
    assert!(matches!(
        okid(&[&u[0]], &[&y[0]], Some(&missing), &given),
        Err(OkidError::TooShort { .. })
    ));
    let r = okid(&[&u[0]], &[&y[0]], Some(&missing), &OkidOptions::default()).unwrap();
    assert!(r.observer_order_max < 40, "{}", r.observer_order_max);
    assert!(
        r.rows + r.observer_order_max >= 20 * r.observer_order_max,
        "{} rows at {}",
        r.rows,
        r.observer_order_max
    );
    assert!(rel_err(&sys, &r) < 1e-8, "{}", rel_err(&sys, &r));
}

#[test]
fn output_noise_gives_a_small_documented_bias() {
    // White output noise at 2 % of the output spread, 4000 samples, random input: the recovered
    // Markov parameters stay within 2 % of the largest block (the ARX truncation bias of OKID
    // with a finite ℓ, plus the noise itself). ℓ is chosen by output error.
    let sys = underdamped();
    let u = vec![random_input(4000, 21)];
    let mut y = sys.simulate(&u);
    let mean = y[0].iter().sum::<f64>() / 4000.0;
    let sd = (y[0].iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 4000.0).sqrt();
    let noise = Normal::new(0.0, 0.02 * sd).unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(22);
    for v in y[0].iter_mut() {
        *v += noise.sample(&mut rng);
    }
    let r = okid(&[&u[0]], &[&y[0]], None, &OkidOptions::default()).unwrap();
    let e = rel_err(&sys, &r);
    assert!(
        e < 0.02,
        "noisy relative error {e} (ell {})",
        r.observer_order
    );
    assert!(e > 1e-6, "noise must show");
    assert!((r.residual_rms[0] / (0.02 * sd) - 1.0).abs() < 0.2);
}

#[test]
fn bad_input_is_a_typed_error() {
    let u = random_input(500, 1);
    let y = vec![1.0; 500];
    let opts = OkidOptions::default();
    assert_eq!(
        okid(&[&u], &[&y], None, &opts),
        Err(OkidError::ConstantOutput(0))
    );
    assert_eq!(
        okid(&[&y], &[&u], None, &opts),
        Err(OkidError::ConstantInput(0))
    );
    assert_eq!(okid(&[], &[&u], None, &opts), Err(OkidError::NoChannels));
    assert!(matches!(
        okid(&[&u[..400]], &[&u], None, &opts),
        Err(OkidError::LengthMismatch { .. })
    ));
    let mut bad = u.clone();
    bad[17] = f64::NAN;
    assert!(matches!(
        okid(&[&u], &[&bad], None, &opts),
        Err(OkidError::NonFinite { sample: 17, .. })
    ));
    assert!(matches!(
        okid(&[&u[..6]], &[&u[..6]], None, &opts),
        Err(OkidError::TooShort { .. })
    ));
    let zero = OkidOptions {
        observer_order: Some(0),
        ..opts
    };
    assert_eq!(
        okid(&[&u], &[&u], None, &zero),
        Err(OkidError::ZeroObserverOrder)
    );
}

#[test]
fn significance_truncation_drops_noise_directions_and_says_so() {
    let sys = underdamped();
    let u = vec![random_input(3000, 31)];
    let mut y = sys.simulate(&u);
    let noise = Normal::new(0.0, 0.05).unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(32);
    for v in y[0].iter_mut() {
        *v += noise.sample(&mut rng);
    }
    let opts = OkidOptions {
        observer_order: Some(20),
        significance: 3.0,
        ..OkidOptions::default()
    };
    let r = okid(&[&u[0]], &[&y[0]], None, &opts).unwrap();
    assert!(r.regularised);
    assert!(r.rank < r.params, "rank {} of {}", r.rank, r.params);
    assert!(r.markov.iter().all(|v| v.is_finite()));
    // Noise-free data keep every direction with the same option: still exact.
    let r = run(
        &sys,
        &[random_input(800, 33)],
        &OkidOptions {
            significance: 3.0,
            ..OkidOptions::default()
        },
    );
    assert!(rel_err(&sys, &r) < 1e-8);
}
