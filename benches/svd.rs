//! Dense (one-sided Jacobi on the formed Hankel matrix) against truncated (FFT products +
//! Golub–Kahan–Lanczos) SVD of a square SISO Hankel matrix `s × s` from a noisy 2nd-order
//! impulse response: the measurement behind `core::svd::TRUNCATED_CROSSOVER`.
//!
//! `cargo bench --bench svd` (criterion). The truncated path is timed for `k = 2` (the
//! order-2 factors ERA needs) and for `k = 16` with only the leading 2 required to converge
//! (`compute_at_least`, what an automatic order choice asks for).

use std::time::Duration;

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use propid_numerics::hankel::{Hankel, HankelDims};
use propid_numerics::svd::dense::DenseSvd;
use propid_numerics::svd::hankel_op::HankelOp;
use propid_numerics::svd::truncated::TruncatedSvd;
use propid_numerics::svd::Triplets;

/// Impulse response of a 20 Hz, ζ = 0.1 oscillator at 1 kHz plus 1 % uniform noise.
fn markov(len: usize) -> Vec<f64> {
    let (wn, zeta, dt): (f64, f64, f64) = (2.0 * std::f64::consts::PI * 20.0, 0.1, 1e-3);
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let mut state = 12345u64;
    (0..len)
        .map(|k| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let e = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            let t = k.saturating_sub(1) as f64 * dt;
            let y = if k == 0 {
                0.0
            } else {
                (-zeta * wn * t).exp() * (wd * t).sin() * 0.1
            };
            y + 0.001 * e
        })
        .collect()
}

fn dense_hankel(m: &[f64], s: usize, out: &mut [f64]) {
    for b in 0..s {
        for a in 0..s {
            out[a + b * s] = m[a + b + 1];
        }
    }
}

fn bench_svd(c: &mut Criterion) {
    let mut group = c.benchmark_group("hankel_svd");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for &s in &[16usize, 32, 64, 96, 128, 192, 256] {
        let m = markov(2 * s + 2);
        let mut sigma = vec![0.0; s];
        let mut u = vec![0.0; s * 16];
        let mut v = vec![0.0; s * 16];
        let mut dense = DenseSvd::new(s, s);
        let mut h = vec![0.0; s * s];
        group.bench_with_input(BenchmarkId::new("dense_k2", s), &s, |bch, &s| {
            bch.iter(|| {
                dense_hankel(&m, s, &mut h);
                dense
                    .compute(&h, s, s, 2, Triplets::new(&mut sigma, &mut u, &mut v))
                    .unwrap();
                black_box(sigma[0])
            })
        });
        let mut tr = TruncatedSvd::new(s, s, 1, 1, 16);
        group.bench_with_input(BenchmarkId::new("truncated_k2", s), &s, |bch, &s| {
            bch.iter(|| {
                tr.compute(
                    Hankel::new(
                        &m,
                        HankelDims {
                            q: 1,
                            p: 1,
                            r: s,
                            c: s,
                        },
                        0,
                    ),
                    2,
                    Triplets::new(&mut sigma, &mut u, &mut v),
                )
                .unwrap();
                black_box(sigma[0])
            })
        });
        let k = 16.min(s);
        group.bench_with_input(BenchmarkId::new("truncated_k16_need2", s), &s, |bch, &s| {
            bch.iter(|| {
                tr.compute_at_least(
                    Hankel::new(
                        &m,
                        HankelDims {
                            q: 1,
                            p: 1,
                            r: s,
                            c: s,
                        },
                        0,
                    ),
                    k,
                    2,
                    Triplets::new(&mut sigma, &mut u, &mut v),
                )
                .unwrap();
                black_box(sigma[0])
            })
        });
    }
    group.finish();
}

fn bench_products(c: &mut Criterion) {
    let mut group = c.benchmark_group("hankel_product");
    group
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for &n in &[2_000usize, 8_000, 100_000] {
        let s = n / 2;
        let m = markov(n + 1);
        let mut op = HankelOp::new(s, s, 1, 1);
        op.prepare(Hankel::new(
            &m,
            HankelDims {
                q: 1,
                p: 1,
                r: s,
                c: s,
            },
            0,
        ))
        .unwrap();
        let x = vec![1.0; s];
        let mut y = vec![0.0; s];
        group.bench_with_input(BenchmarkId::new("fft_apply", n), &n, |bch, _| {
            bch.iter(|| {
                op.apply_prepared(&x, &mut y).unwrap();
                black_box(y[0])
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_svd, bench_products);
criterion_main!(benches);
