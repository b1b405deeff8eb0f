//! `Workspace::identify` on pulse records of 256, 1 024 and 4 096 samples (1 kHz, fn = 15 Hz,
//! ζ = 0.5, one-sample pulses of ±0.2 every 128 samples, 5 mN noise), with and without the
//! jackknife. Run: `cargo bench --bench identify`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::{Matrix2, Vector2};
use propid_numerics::{IdentOptions, Limits, PulseInput, Workspace};
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

fn record(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (dt, wn, zeta, gain) = (0.001, 2.0 * std::f64::consts::PI * 15.0, 0.5, 4.0);
    let ac = Matrix2::new(0.0, 1.0, -wn * wn, -2.0 * zeta * wn);
    let bc = Vector2::new(0.0, gain * wn * wn);
    let ad = (ac * dt).exp();
    let bd = ac.try_inverse().unwrap() * (ad - Matrix2::identity()) * bc;
    let mut u = vec![0.5; n];
    for (i, s) in (20..n - 100).step_by(128).enumerate() {
        u[s] += if i % 2 == 0 { 0.2 } else { -0.2 };
    }
    let mut x = (Matrix2::identity() - ad).try_inverse().unwrap() * bd * 0.5;
    let mut rng = StdRng::seed_from_u64(1);
    let noise = Normal::new(0.0, 0.005).unwrap();
    let y = u
        .iter()
        .map(|&uk| {
            let yk = x[0] + 2.0 + noise.sample(&mut rng);
            x = ad * x + bd * uk;
            yk
        })
        .collect();
    (u, y)
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("identify");
    for n in [256usize, 1024, 4096] {
        let (u, y) = record(n);
        let chans = [&y[..]];
        let input = PulseInput {
            dt_s: 0.001,
            u: &u,
            y: &chans,
            missing: &[],
            pulse_starts: None,
        };
        let mut ws = Workspace::new(&Limits::default()).unwrap();
        for (name, jackknife) in [("jackknife", true), ("no_jackknife", false)] {
            let opts = IdentOptions {
                jackknife,
                ..IdentOptions::default()
            };
            ws.identify(&input, &opts)
                .expect("benchmark record identifies");
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                b.iter(|| ws.identify(&input, &opts).map(|m| m.order()).unwrap())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
