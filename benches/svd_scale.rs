//! Scale run of the truncated Hankel SVD (plain `main`, not criterion): for records of 1 000,
//! 4 000 and 100 000 samples, the square Hankel `H(0)` (`s × s`, `s = (N − 1)/2`), its two
//! leading triplets and `Uᵀ H(1) V` (everything ERA needs from the SVD), timed, with the peak
//! resident memory of the process (`VmHWM`). Sizes can be given as arguments; for a clean
//! peak-memory figure per size run one size per process, as `scripts/svd_scale.sh` does.
//!
//! `cargo bench --bench svd_scale [-- N...]` (or `scripts/svd_scale.sh`). Targets (issue 6): 100 000
//! samples in well under 1 s and under 64 MB peak.

use std::time::Instant;

use propid_numerics::hankel::{Hankel, HankelDims};
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

/// Peak resident set size of this process in MiB: `VmHWM` from `/proc/self/status` (Linux).
/// (`getrusage`'s `ru_maxrss` is not used: it keeps the parent's high-water mark across
/// `exec`, so under `cargo bench` it reports cargo's own peak.)
fn peak_rss_mib() -> f64 {
    let Ok(status) = std::fs::read_to_string("/proc/self/status") else {
        return f64::NAN;
    };
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else is accepted.
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sizes = if sizes.is_empty() {
        vec![1_000, 4_000, 100_000]
    } else {
        sizes
    };
    println!("samples  hankel        build_ms  svd_ms  project_ms  total_ms  steps  sigma1      sigma2      peak_rss_MiB");
    for n in sizes {
        let m = markov(n);
        let s = (n - 2) / 2;
        let k = 2;
        let t0 = Instant::now();
        let mut svd = TruncatedSvd::new(s, s, 1, 1, k);
        let (mut sigma, mut u, mut v) = (vec![0.0; k], vec![0.0; s * k], vec![0.0; s * k]);
        let mut a = vec![0.0; k * k];
        let t1 = Instant::now();
        let res = svd.compute(
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
            Triplets::new(&mut sigma, &mut u, &mut v),
        );
        let t2 = Instant::now();
        if let Err(e) = res {
            println!("{n:>7}  {s}x{s}: {e}");
            continue;
        }
        if let Err(e) = svd.project(
            Hankel::new(
                &m,
                HankelDims {
                    q: 1,
                    p: 1,
                    r: s,
                    c: s,
                },
                1,
            ),
            k,
            &u,
            &v,
            &mut a,
        ) {
            println!("{n:>7}  {s}x{s}: {e}");
            continue;
        }
        let t3 = Instant::now();
        let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
        println!(
            "{n:>7}  {:<12}  {:>8.2}  {:>6.2}  {:>10.2}  {:>8.2}  {:>5}  {:<10.6e}  {:<10.6e}  {:.1}",
            format!("{s}x{s}"),
            ms(t1 - t0),
            ms(t2 - t1),
            ms(t3 - t2),
            ms(t3 - t0),
            svd.steps(),
            sigma[0],
            sigma[1],
            peak_rss_mib()
        );
    }
}
