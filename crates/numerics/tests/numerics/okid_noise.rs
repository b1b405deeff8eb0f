//! OKID + ERA with output noise: a seeded Monte Carlo of the bias and scatter of fn, ζ and the DC
//! gain, for random-input and staircase records (where the pulse path has nothing to work with).
//!
//! Measured (release build, 40 seeds each; plant fn = 12 Hz, ζ = 0.3, DC gain 6, dt = 2 ms,
//! order 2, white output noise at the given fraction of the output's standard deviation; bias
//! and standard deviation relative to the true value):
//!
//! | excitation | samples | noise | fn bias | fn sd | ζ bias | ζ sd | gain bias | gain sd |
//! |---|---|---|---|---|---|---|---|---|
//! | random ±0.05 | 3000 | 5 % | +0.11 % | 0.08 % | +0.55 % | 0.27 % | +0.06 % | 0.21 % |
//! | staircase, 5 levels | 3000 | 1 % | +0.56 % | 0.72 % | +1.6 % | 1.3 % | −0.02 % | 0.68 % |
//!
//! The bias comes from the finite observer order (OKID truncates the Kalman filter's infinite
//! observer after ℓ lags) and ERA's truncation of a noisy Hankel; damping is the most biased
//! (upward), as with the pulse path. A staircase carries far less information than a random
//! input (four steps; the Markov parameters are the *derivative* of the step responses), so the
//! same accuracy needs five times less noise. At 5 % noise a 5-level staircase at 500 Hz no
//! longer determines the individual Markov parameters (their standard error from OKID is about
//! the size of the parameters themselves), though the DC gain stays within 1 %. The bounds
//! asserted below leave a margin of about 2× over these numbers.

use propid_testkit as core_support;

use core_support::Plant;
use propid_numerics::identify::{identify_any, AnyInput, PathTaken};
use propid_numerics::okid::OkidOptions;
use propid_numerics::workspace::IdentOptions;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

struct Stats {
    bias: f64,
    sd: f64,
}

fn stats(v: &[f64], truth: f64) -> Stats {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    Stats {
        bias: (mean - truth) / truth,
        sd: var.sqrt() / truth,
    }
}

fn monte_carlo(make_u: impl Fn(u64) -> Vec<f64>, seeds: u64, noise_rel: f64) -> [Stats; 3] {
    let plant = Plant::new(12.0, 0.3, 6.0, 0.002);
    let (mut f, mut z, mut g) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 0..seeds {
        let u = make_u(seed);
        let mut y = plant.simulate(&u, 3.0).remove(0);
        let mean = y.iter().sum::<f64>() / y.len() as f64;
        let sd = (y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / y.len() as f64).sqrt();
        let noise = Normal::new(0.0, noise_rel * sd).unwrap();
        let mut rng = rand::rngs::StdRng::seed_from_u64(1000 + seed);
        for v in &mut y {
            *v += noise.sample(&mut rng);
        }
        let us = [&u[..]];
        let ys = [&y[..]];
        let input = AnyInput {
            dt_s: plant.dt,
            u: &us,
            y: &ys,
            missing: &[],
            pulse_starts: None,
        };
        let ident = IdentOptions {
            order: Some(2),
            jackknife: false,
            ..IdentOptions::default()
        };
        let m = identify_any(&input, &ident, &OkidOptions::default()).expect("identify");
        assert_eq!(m.path, PathTaken::Okid);
        f.push(m.report.fn_hz);
        z.push(m.report.zeta);
        g.push(m.report.dc_gain.get(0));
    }
    [stats(&f, 12.0), stats(&z, 0.3), stats(&g, plant.dc(0))]
}

fn report(name: &str, s: &[Stats; 3]) {
    eprintln!(
        "{name}: fn bias {:+.4} sd {:.4} | zeta bias {:+.4} sd {:.4} | gain bias {:+.4} sd {:.4}",
        s[0].bias, s[0].sd, s[1].bias, s[1].sd, s[2].bias, s[2].sd
    );
}

#[test]
fn random_input_with_output_noise() {
    let s = monte_carlo(
        |seed| {
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            (0..3000)
                .map(|_| 0.4 + 0.05 * rng.gen_range(-1.0..1.0))
                .collect()
        },
        40,
        0.05,
    );
    report("random", &s);
    assert!(s[0].bias.abs() < 0.003 && s[0].sd < 0.002);
    assert!(s[1].bias.abs() < 0.012 && s[1].sd < 0.006);
    assert!(s[2].bias.abs() < 0.002 && s[2].sd < 0.005);
}

#[test]
fn staircase_with_output_noise() {
    // Five levels, 600 samples each: the pulse path finds no pulse; OKID uses the four steps.
    let s = monte_carlo(
        |_| (0..3000).map(|k| 0.2 + 0.1 * (k / 600) as f64).collect(),
        40,
        0.01,
    );
    report("staircase", &s);
    assert!(s[0].bias.abs() < 0.012 && s[0].sd < 0.015);
    assert!(s[1].bias.abs() < 0.035 && s[1].sd < 0.03);
    assert!(s[2].bias.abs() < 0.003 && s[2].sd < 0.015);
}
