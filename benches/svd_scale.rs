//! Scale run of the truncated Hankel SVD (plain `main`, not criterion): for records of 1 000,
//! 4 000 and 100 000 samples, the square Hankel `H(0)` (`s × s`, `s = (N − 1)/2`), its two
//! leading triplets and `Uᵀ H(1) V` (everything ERA needs from the SVD), timed, with the peak
//! resident memory of the process (`getrusage`, `ru_maxrss`).
//!
//! `cargo bench --bench svd_scale` (or `scripts/svd_scale.sh`). Targets (issue 6): 100 000
//! samples in well under 1 s and under 64 MB peak.

use std::time::Instant;

use propid::core::svd::truncated::TruncatedSvd;

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

/// Peak resident set size of this process in MiB (Linux reports kibibytes).
fn peak_rss_mib() -> f64 {
    // SAFETY: getrusage writes into the zeroed struct we pass; no other invariants.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    if rc != 0 {
        return f64::NAN;
    }
    usage.ru_maxrss as f64 / 1024.0
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
        let res = svd.compute(&m, 1, 1, s, s, 0, k, &mut sigma, &mut u, &mut v);
        let t2 = Instant::now();
        if let Err(e) = res {
            println!("{n:>7}  {s}x{s}: {e}");
            continue;
        }
        if let Err(e) = svd.project(&m, 1, 1, s, s, 1, k, &u, &v, &mut a) {
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
