//! Discrete-time state-space model and its simulation.
//!
//! ```text
//! x_{k+1} = A x_k + B u_k
//! y_k     = C x_k + D u_k
//! ```
//!
//! Inputs and outputs are deviations from the operating point the model was identified at.
//! Signals are sample-major: `u[k*p + j]` is input `j` at sample `k`, `y[k*q + i]` output `i`.

use nalgebra::DMatrix;

use super::IdentError;

/// A discrete-time LTI model `(A, B, C, D)` with its sample period.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpace {
    /// State matrix, `n × n`.
    pub a: DMatrix<f64>,
    /// Input matrix, `n × p`.
    pub b: DMatrix<f64>,
    /// Output matrix, `q × n`.
    pub c: DMatrix<f64>,
    /// Feed-through, `q × p`.
    pub d: DMatrix<f64>,
    /// Sample period, seconds.
    pub dt_s: f64,
}

/// A state-space model `(A, B, C, D)` in flat column-major storage, borrowed (the
/// workspace's preallocated buffers): `a` `n × n`, `b` `n × p`, `c` `q × n`, `d` `q × p`.
#[derive(Debug, Clone, Copy)]
pub struct Abcd<'a> {
    /// State matrix.
    pub a: &'a [f64],
    /// Input matrix.
    pub b: &'a [f64],
    /// Output matrix.
    pub c: &'a [f64],
    /// Feed-through.
    pub d: &'a [f64],
    /// Order `n`.
    pub n: usize,
    /// Outputs `q`.
    pub q: usize,
    /// Inputs `p`.
    pub p: usize,
}

/// Where a realisation writes `(A, B, C, D)` (flat, column-major, as [`Abcd`]).
#[derive(Debug)]
pub struct AbcdMut<'a> {
    /// State matrix.
    pub a: &'a mut [f64],
    /// Input matrix.
    pub b: &'a mut [f64],
    /// Output matrix.
    pub c: &'a mut [f64],
    /// Feed-through.
    pub d: &'a mut [f64],
}

impl StateSpace {
    /// Checks the shapes: `A` square, `B` with `A`'s rows, `C` with `A`'s columns, `D` `q × p`.
    pub fn new(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
        dt_s: f64,
    ) -> Result<Self, IdentError> {
        let n = a.nrows();
        if a.ncols() != n || b.nrows() != n || c.ncols() != n {
            return Err(IdentError::InvalidInput("state-space shapes do not agree"));
        }
        if d.nrows() != c.nrows() || d.ncols() != b.ncols() {
            return Err(IdentError::InvalidInput("D must be outputs × inputs"));
        }
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(IdentError::InvalidInput("dt_s must be finite and > 0"));
        }
        Ok(Self { a, b, c, d, dt_s })
    }

    /// Model order `n`.
    pub fn order(&self) -> usize {
        self.a.nrows()
    }

    /// Number of inputs `p`.
    pub fn inputs(&self) -> usize {
        self.b.ncols()
    }

    /// Number of outputs `q`.
    pub fn outputs(&self) -> usize {
        self.c.nrows()
    }

    /// Simulates from `x_0 = 0`: `u` holds `N*p` values, `y_out` receives `N*q`.
    pub fn simulate(&self, u: &[f64], y_out: &mut [f64]) -> Result<(), IdentError> {
        let mut x = vec![0.0; self.order()];
        self.simulate_from(&mut x, u, y_out)
    }

    /// Simulates from the state `x` (updated in place to the final state); no allocation.
    pub fn simulate_from(
        &self,
        x: &mut [f64],
        u: &[f64],
        y_out: &mut [f64],
    ) -> Result<(), IdentError> {
        let (n, p, q) = (self.order(), self.inputs(), self.outputs());
        if x.len() != n || p == 0 || u.len() % p != 0 {
            return Err(IdentError::InvalidInput(
                "state or input length does not fit the model",
            ));
        }
        let steps = u.len() / p;
        if y_out.len() != steps * q {
            return Err(IdentError::InvalidInput(
                "output buffer must hold samples × outputs",
            ));
        }
        // Two state copies on the stack for small orders would avoid this; n is small, so a
        // single scratch update in place via a temporary per row is enough.
        for k in 0..steps {
            let uk = &u[k * p..(k + 1) * p];
            for i in 0..q {
                let mut acc = 0.0;
                for l in 0..n {
                    acc += self.c[(i, l)] * x[l];
                }
                for j in 0..p {
                    acc += self.d[(i, j)] * uk[j];
                }
                y_out[k * q + i] = acc;
            }
            next_state(&self.a, &self.b, x, uk);
        }
        Ok(())
    }
}

/// `x ← A x + B u` without allocation for `n <= 32` (stack scratch), heap beyond.
fn next_state(a: &DMatrix<f64>, b: &DMatrix<f64>, x: &mut [f64], u: &[f64]) {
    let n = x.len();
    let mut stack = [0.0; 32];
    let mut heap;
    let next: &mut [f64] = if n <= 32 {
        &mut stack[..n]
    } else {
        heap = vec![0.0; n];
        &mut heap
    };
    for (i, slot) in next.iter_mut().enumerate() {
        let mut acc = 0.0;
        for l in 0..n {
            acc += a[(i, l)] * x[l];
        }
        for (j, uj) in u.iter().enumerate() {
            acc += b[(i, j)] * uj;
        }
        *slot = acc;
    }
    x.copy_from_slice(next);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn impulse_response_is_markov_sequence() {
        let a = DMatrix::from_row_slice(2, 2, &[0.9, 0.2, -0.1, 0.8]);
        let b = DMatrix::from_row_slice(2, 1, &[1.0, 0.5]);
        let c = DMatrix::from_row_slice(1, 2, &[1.0, -1.0]);
        let d = DMatrix::from_row_slice(1, 1, &[0.3]);
        let ss = StateSpace::new(a.clone(), b.clone(), c.clone(), d, 0.01).unwrap();
        let mut u = vec![0.0; 6];
        u[0] = 1.0;
        let mut y = vec![0.0; 6];
        ss.simulate(&u, &mut y).unwrap();
        assert_eq!(y[0], 0.3);
        let mut ak = DMatrix::identity(2, 2);
        for yk in &y[1..] {
            let want = (&c * &ak * &b)[(0, 0)];
            assert!((yk - want).abs() < 1e-15);
            ak = &a * ak;
        }
    }

    #[test]
    fn shape_errors() {
        let a = DMatrix::zeros(2, 2);
        let b = DMatrix::zeros(3, 1);
        let c = DMatrix::zeros(1, 2);
        let d = DMatrix::zeros(1, 1);
        assert!(StateSpace::new(a, b, c, d, 0.01).is_err());
    }
}
