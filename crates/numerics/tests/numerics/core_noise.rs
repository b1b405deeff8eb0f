//! Seeded Monte Carlo with measurement noise: bias and scatter of fn, ζ and DC gain
//! (numbers documented in docs/core.md), the tiny-Hankel pitfall, and the jackknife against
//! the observed scatter.

use propid_testkit as core_support;

use core_support::{add_noise, record_input, throttle, Plant};
use propid_numerics::{IdentOptions, Limits, Workspace};

const TRIALS: u64 = 30;

/// 1 kHz, fn = 15 Hz, ζ = 0.5, K = 4 N/throttle; 40 one-sample pulses of ±0.2 every 250 ms;
/// load-cell noise 5 mN.
fn record(seed: u64, plant: &Plant) -> (Vec<f64>, Vec<f64>) {
    let pulses: Vec<_> = (0..40)
        .map(|i| (200 + 250 * i, 1, if i % 2 == 0 { 0.2 } else { -0.2 }))
        .collect();
    let u = throttle(200 + 250 * 40 + 50, &[(0, 0.5)], &pulses);
    let mut y = plant.simulate(&u, 2.0).remove(0);
    add_noise(&mut y, 0.005, seed);
    (u, y)
}

struct Stats {
    mean: f64,
    std: f64,
}

fn stats(v: &[f64]) -> Stats {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let std = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    Stats { mean, std }
}

fn run(opts: &IdentOptions) -> (Vec<[f64; 6]>, Vec<usize>) {
    let plant = Plant::new(15.0, 0.5, 4.0, 0.001);
    let limits = Limits {
        max_samples: 16384,
        ..Limits::default()
    };
    let mut ws = Workspace::new(&limits).unwrap();
    let mut out = Vec::new();
    let mut orders = Vec::new();
    for seed in 0..TRIALS {
        let (u, y) = record(seed, &plant);
        let chans = [&y[..]];
        let input = record_input(plant.dt, &u, &chans);
        let m = ws.identify(&input, opts).unwrap();
        let (sf, sz, sd) = m.uncertainty(0);
        orders.push(m.order());
        out.push([m.fn_hz(), m.zeta(), m.dc_gain(0, 0), sf, sz, sd]);
    }
    (out, orders)
}

#[test]
fn monte_carlo_bias_and_scatter() {
    let (est, orders) = run(&IdentOptions {
        order: Some(2),
        ..IdentOptions::default()
    });
    let col = |i: usize| est.iter().map(|e| e[i]).collect::<Vec<_>>();
    let (f, z, g) = (stats(&col(0)), stats(&col(1)), stats(&col(2)));
    let (jf, jz, jg) = (
        stats(&col(3)).mean,
        stats(&col(4)).mean,
        stats(&col(5)).mean,
    );
    eprintln!(
        "fn: bias {:+.3} % std {:.3} % (jackknife {:.3} %)\nzeta: bias {:+.3} % std {:.3} % (jackknife {:.3} %)\ndc: bias {:+.3} % std {:.3} % (jackknife {:.3} %)",
        100.0 * (f.mean / 15.0 - 1.0), 100.0 * f.std / 15.0, 100.0 * jf / 15.0,
        100.0 * (z.mean / 0.5 - 1.0), 100.0 * z.std / 0.5, 100.0 * jz / 0.5,
        100.0 * (g.mean / 4.0 - 1.0), 100.0 * g.std / 4.0, 100.0 * jg / 4.0,
    );
    assert!(orders.iter().all(|o| *o == 2));
    // Bounds: a few standard errors of the documented numbers (docs/core.md).
    assert!((f.mean / 15.0 - 1.0).abs() < 0.01, "fn bias");
    assert!((z.mean / 0.5 - 1.0).abs() < 0.05, "zeta bias");
    assert!((g.mean / 4.0 - 1.0).abs() < 0.02, "dc bias");
    assert!(
        f.std / 15.0 < 0.02 && z.std / 0.5 < 0.08 && g.std / 4.0 < 0.03,
        "scatter"
    );
    // The jackknife estimates the trial-to-trial scatter within a factor of two.
    for (j, s) in [(jf, f.std), (jz, z.std), (jg, g.std)] {
        assert!(j > 0.5 * s && j < 2.0 * s, "jackknife {j} vs scatter {s}");
    }
}

#[test]
fn automatic_order_on_noisy_data_is_two() {
    let (_, orders) = run(&IdentOptions {
        jackknife: false,
        ..IdentOptions::default()
    });
    let twos = orders.iter().filter(|o| **o == 2).count();
    assert!(twos as u64 >= TRIALS * 9 / 10, "orders {orders:?}");
}

/// Regression: a tiny 4 × 4 Hankel matrix (a common default) is useless on noisy data; the
/// automatic near-square size is far more accurate.
#[test]
fn tiny_hankel_is_useless_on_noisy_data() {
    let auto = run(&IdentOptions {
        order: Some(2),
        jackknife: false,
        ..IdentOptions::default()
    })
    .0;
    let tiny = run(&IdentOptions {
        order: Some(2),
        jackknife: false,
        hankel_blocks: Some((4, 4)),
        ..IdentOptions::default()
    })
    .0;
    // A model without a valid pole pair (NaN) counts as a 100 % error.
    let err = |x: f64, truth: f64| {
        if x.is_finite() {
            (x - truth) / truth
        } else {
            1.0
        }
    };
    let rms = |e: &[[f64; 6]], i: usize, truth: f64| {
        (e.iter().map(|x| err(x[i], truth).powi(2)).sum::<f64>() / e.len() as f64).sqrt()
    };
    let (za, zt) = (rms(&auto, 1, 0.5), rms(&tiny, 1, 0.5));
    let (fa, ft) = (rms(&auto, 0, 15.0), rms(&tiny, 0, 15.0));
    eprintln!("zeta rms error: auto {za:.4}, 4x4 {zt:.4}; fn: auto {fa:.4}, 4x4 {ft:.4}");
    assert!(zt > 3.0 * za, "zeta: tiny {zt} vs auto {za}");
    assert!(ft > 3.0 * fa, "fn: tiny {ft} vs auto {fa}");
}

/// Regression: noisy pulses wider than one sample. Deconvolving them leaves a random walk at
/// `fs/w` that looked like extra modes; ERA on the per-width responses does not.
#[test]
fn wide_noisy_pulses_identify_like_one_sample_pulses() {
    let plant = Plant::new(15.0, 0.5, 4.0, 0.001);
    let limits = Limits {
        max_samples: 16384,
        ..Limits::default()
    };
    let mut ws = Workspace::new(&limits).unwrap();
    for widths in [&[2usize][..], &[5][..], &[1, 2, 5][..]] {
        let mut fz = Vec::new();
        for seed in 0..10 {
            let pulses: Vec<_> = (0..40)
                .map(|i| {
                    (
                        200 + 250 * i,
                        widths[i % widths.len()],
                        if i % 2 == 0 { 0.1 } else { -0.1 },
                    )
                })
                .collect();
            let u = throttle(200 + 250 * 40 + 50, &[(0, 0.5)], &pulses);
            let mut y = plant.simulate(&u, 2.0).remove(0);
            add_noise(&mut y, 0.005, 100 + seed);
            let chans = [&y[..]];
            let input = record_input(plant.dt, &u, &chans);
            let m = ws
                .identify(
                    &input,
                    &IdentOptions {
                        jackknife: false,
                        ..IdentOptions::default()
                    },
                )
                .unwrap();
            assert_eq!(m.order(), 2, "widths {widths:?} seed {seed}");
            fz.push([
                m.fn_hz() / 15.0 - 1.0,
                m.zeta() / 0.5 - 1.0,
                m.dc_gain(0, 0) / 4.0 - 1.0,
            ]);
        }
        for i in 0..3 {
            let worst = fz.iter().map(|e| e[i].abs()).fold(0.0, f64::max);
            assert!(
                worst < 0.08,
                "widths {widths:?}: relative error {worst} in {}",
                ["fn", "zeta", "dc"][i]
            );
        }
    }
}

/// Issue 6: on the same Monte Carlo, the truncated (FFT + Lanczos) path is no worse than the
/// dense square-Hankel SVD in bias and scatter of ζ (it computes the same leading triplets).
#[test]
fn truncated_path_matches_dense_statistics() {
    use propid_numerics::SvdChoice;
    let base = IdentOptions {
        order: Some(2),
        jackknife: false,
        ..IdentOptions::default()
    };
    let dense = run(&IdentOptions {
        svd: SvdChoice::Dense,
        ..base
    })
    .0;
    let trunc = run(&IdentOptions {
        svd: SvdChoice::Truncated,
        ..base
    })
    .0;
    for (d, t) in dense.iter().zip(&trunc) {
        for i in 0..3 {
            assert!(
                ((d[i] - t[i]) / d[i]).abs() < 1e-8,
                "dense {d:?} truncated {t:?}"
            );
        }
    }
}

/// A long record through an explicitly large Hankel matrix (far beyond the dense capacity):
/// the workspace routes it to the truncated path and stays exact on exact data.
#[test]
fn large_hankel_goes_through_the_truncated_path() {
    use propid_numerics::MarkovSeq;
    let plant = Plant::new(15.0, 0.05, 4.0, 0.001);
    let n = 20_000;
    let markov = MarkovSeq::from_data(1, 1, plant.markov(n)).unwrap();
    let limits = Limits {
        max_samples: n,
        max_block_rows: 10_000,
        max_block_cols: 10_000,
        ..Limits::default()
    };
    let mut ws = Workspace::new(&limits).unwrap();
    let opts = IdentOptions {
        order: Some(2),
        hankel_blocks: Some((9_000, 9_000)),
        ..IdentOptions::default()
    };
    let m = ws.identify_markov(&markov, plant.dt, &opts).unwrap();
    assert_eq!(m.svd_path().as_str(), "truncated");
    assert!(((m.fn_hz() - 15.0) / 15.0).abs() < 1e-8 && ((m.zeta() - 0.05) / 0.05).abs() < 1e-8);
}
