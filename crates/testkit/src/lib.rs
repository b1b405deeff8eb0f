//! # propid-testkit — the test cases the suites share
//!
//! Exact zero-order-hold 2nd-order plants and pulse records (the core's tests, the CLI's), and a
//! CSV bench's rows ([`csv_bench`], the daemon's tests), effects hidden in real logs
//! ([`inject`], the diagnosis's tests on measured data), stand logs as CSV text ([`logs`]).
//! Pure functions, no I/O: a dev-dependency only, so the numerics crate can test against it
//! without the simulated stand's pty and serial dependencies entering its dependency tree. Cases
//! that need the simulated plant and its hidden effects are `propid_sim::synth`.

pub mod csv_bench;
pub mod dialects;
pub mod inject;
pub mod logs;

use nalgebra::{DMatrix, Matrix2, Vector2};
use propid_numerics::PulseInput;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A 2nd-order plant `K ωn² / (s² + 2ζωn s + ωn²)` on output 0, sampled with a zero-order hold;
/// extra outputs are other rows of `C` (with a feed-through each).
#[derive(Debug, Clone)]
pub struct Plant {
    pub fn_hz: f64,
    pub zeta: f64,
    pub gain: f64,
    pub dt: f64,
    pub ad: Matrix2<f64>,
    pub bd: Vector2<f64>,
    /// Rows of C and D per output.
    pub c: Vec<[f64; 2]>,
    pub d: Vec<f64>,
}

impl Plant {
    pub fn new(fn_hz: f64, zeta: f64, gain: f64, dt: f64) -> Self {
        let wn = 2.0 * std::f64::consts::PI * fn_hz;
        let ac = Matrix2::new(0.0, 1.0, -wn * wn, -2.0 * zeta * wn);
        let bc = Vector2::new(0.0, gain * wn * wn);
        let ad = (ac * dt).exp();
        let bd = ac.try_inverse().unwrap() * (ad - Matrix2::identity()) * bc;
        Self {
            fn_hz,
            zeta,
            gain,
            dt,
            ad,
            bd,
            c: vec![[1.0, 0.0]],
            d: vec![0.0],
        }
    }

    /// Adds an output `c·x + d·u`.
    pub fn with_output(mut self, c: [f64; 2], d: f64) -> Self {
        self.c.push(c);
        self.d.push(d);
        self
    }

    /// DC gain of output `i`: `d + c (I − A)^-1 B`.
    pub fn dc(&self, i: usize) -> f64 {
        let x = (Matrix2::identity() - self.ad).try_inverse().unwrap() * self.bd;
        self.c[i][0] * x[0] + self.c[i][1] * x[1] + self.d[i]
    }

    /// Outputs for the throttle `u` from steady state at `u[0]`, plus `offset` per output.
    pub fn simulate(&self, u: &[f64], offset: f64) -> Vec<Vec<f64>> {
        let inv = (Matrix2::identity() - self.ad).try_inverse().unwrap();
        let mut x = inv * self.bd * u[0];
        let mut y = vec![Vec::with_capacity(u.len()); self.c.len()];
        for &uk in u {
            for (i, yi) in y.iter_mut().enumerate() {
                yi.push(self.c[i][0] * x[0] + self.c[i][1] * x[1] + self.d[i] * uk + offset);
            }
            x = self.ad * x + self.bd * uk;
        }
        y
    }

    /// Exact Markov parameters `Y_0 .. Y_{len-1}` (q × 1 blocks).
    pub fn markov(&self, len: usize) -> Vec<f64> {
        let q = self.c.len();
        let mut out = Vec::with_capacity(len * q);
        out.extend_from_slice(&self.d);
        let mut x = self.bd;
        for _ in 1..len {
            for i in 0..q {
                out.push(self.c[i][0] * x[0] + self.c[i][1] * x[1]);
            }
            x = self.ad * x;
        }
        out
    }

    /// State-space matrices as DMatrix (A, B, C, D).
    pub fn matrices(&self) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let q = self.c.len();
        let a = DMatrix::from_iterator(2, 2, self.ad.iter().copied());
        let b = DMatrix::from_iterator(2, 1, self.bd.iter().copied());
        let c = DMatrix::from_fn(q, 2, |i, j| self.c[i][j]);
        let d = DMatrix::from_fn(q, 1, |i, _| self.d[i]);
        (a, b, c, d)
    }
}

/// A pulse: (start, width, amplitude).
pub type PulseSpec = (usize, usize, f64);

/// Throttle: `levels` as (from sample, level) steps, plus pulses on top.
pub fn throttle(n: usize, levels: &[(usize, f64)], pulses: &[PulseSpec]) -> Vec<f64> {
    let mut u = vec![0.0; n];
    for (k, uk) in u.iter_mut().enumerate() {
        *uk = levels
            .iter()
            .rfind(|(s, _)| *s <= k)
            .map_or(0.0, |(_, l)| *l);
    }
    for &(s, w, a) in pulses {
        for uk in &mut u[s..s + w] {
            *uk += a;
        }
    }
    u
}

/// Relative error.
pub fn rel(got: f64, want: f64) -> f64 {
    ((got - want) / want).abs()
}

/// Adds zero-mean Gaussian noise of standard deviation `sd` (a load cell's) to `y`, drawn in
/// order from `StdRng::seed_from_u64(seed)`: the same seed gives the same record.
pub fn add_noise(y: &mut [f64], sd: f64, seed: u64) {
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sd).unwrap();
    for v in y {
        *v += noise.sample(&mut rng);
    }
}

/// `n` samples of Gaussian noise of standard deviation `sd`, seeded (what [`add_noise`] adds).
pub fn gaussian(n: usize, sd: f64, seed: u64) -> Vec<f64> {
    let mut v = vec![0.0; n];
    add_noise(&mut v, sd, seed);
    v
}

/// The identification input of a record without gaps: throttle `u` and output channels `y`
/// at period `dt_s`, nothing missing, no device pulse starts (pulses are found from `u`).
pub fn record_input<'a>(dt_s: f64, u: &'a [f64], y: &'a [&'a [f64]]) -> PulseInput<'a> {
    PulseInput {
        dt_s,
        u,
        y,
        missing: &[],
        pulse_starts: None,
    }
}
