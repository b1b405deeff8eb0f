//! Stand logs as CSV text for the diagnosis's tests (the engine's in memory, the binary's few
//! end-to-end ones): a logger that writes the thrust on the command's own row
//! ([`same_row_staircase`]), a load cell's tare settling at the start ([`settling_tare_pulses`]).

use crate::{add_noise, throttle, Plant};

/// A 40 Hz staircase up and down of a propeller (T = 12·u² N, first-order lag of 60 ms, no
/// dead time) as `Time (s),ESC signal (µs),Thrust (N)`, the thrust of each row read `late` rows
/// after the command beside it was sent (0: on the same row), noise σ = 0.01 N from a fixed
/// linear congruential sequence.
pub fn same_row_staircase(late: usize) -> String {
    let dt = 0.025;
    let levels = [0.1, 0.3, 0.5, 0.7, 0.5, 0.3, 0.1, 0.4, 0.6, 0.2];
    let u: Vec<f64> = levels
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(120))
        .collect();
    let a = (-dt / 0.06f64).exp();
    // y[k]: the thrust after the command u[k] acted for one sample.
    let mut y = Vec::with_capacity(u.len());
    let mut t = 12.0 * u[0] * u[0];
    for &uk in &u {
        t = a * t + (1.0 - a) * 12.0 * uk * uk;
        y.push(t);
    }
    let mut seed: u64 = 7;
    let mut noise = || {
        // Sum of 12 uniforms: ≈ Gaussian, σ = 1.
        (0..12)
            .map(|_| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (seed >> 11) as f64 / (1u64 << 53) as f64
            })
            .sum::<f64>()
            - 6.0
    };
    let mut text = String::from("Time (s),ESC signal (µs),Thrust (N)\n");
    for k in late..u.len() {
        let thrust = y[k - late] + 0.01 * noise();
        let cmd = 1000.0 + 1000.0 * u[k];
        text.push_str(&format!("{:.3},{cmd:.0},{thrust:.5}\n", k as f64 * dt));
    }
    text
}

/// 4 s at 1 kHz of a plant (fn 12 Hz, ζ 0.7, 12 N/throttle) held at 0.45 (5.4 N), one-sample
/// pulses of ±0.05/±0.1 every 250 samples from 0.2 s, 0.01 N noise, plus a load cell's tare
/// settling from `a` N with τ = 0.3 s, as `t_s,throttle,thrust_N`.
pub fn settling_tare_pulses(a: f64) -> String {
    let n = 4000;
    let pulses: Vec<_> = (0..15)
        .map(|i| {
            let amp = if i % 4 < 2 { 0.05 } else { 0.1 };
            (200 + 250 * i, 1, if i % 2 == 0 { amp } else { -amp })
        })
        .collect();
    let u = throttle(n, &[(0, 0.45)], &pulses);
    let mut y = Plant::new(12.0, 0.7, 12.0, 0.001)
        .simulate(&u, 0.0)
        .remove(0);
    add_noise(&mut y, 0.01, 21);
    let mut text = String::from("t_s,throttle,thrust_N\n");
    for k in 0..n {
        let t = k as f64 * 0.001;
        let v = y[k] + a * (-t / 0.3).exp();
        text.push_str(&format!("{t:.4},{:.4},{v:.5}\n", u[k]));
    }
    text
}
