//! Markov parameters: the response of a discrete-time LTI system to a unit input held for one
//! sample.
//!
//! For `x_{k+1} = A x_k + B u_k`, `y_k = C x_k + D u_k` and an input that is 1 for exactly one
//! sample (`u_0 = 1`, the Kronecker delta) the output is
//!
//! ```text
//! Y_0 = D,    Y_k = C A^(k-1) B   (k >= 1)
//! ```
//!
//! (Juang & Pappa 1985, eq. 2). This is **not** a unit-area impulse: there is no `1/dt` anywhere.
//! With the one-sample convention the DC gain is `sum_k Y_k = D + C (I - A)^-1 B` in output
//! units per unit input; a unit-area convention would scale every `Y_k` by `1/dt` and make DC
//! gains wrong by a factor of the sample rate.
//!
//! Layout (a contract, see docs/ARCHITECTURE.md): `q` outputs, `p` inputs, block `k` stored at
//! `data[k*q*p .. (k+1)*q*p]`, column-major inside the block (element (i, j) at `i + j*q`).

use super::IdentError;

/// A sequence of Markov parameters `Y_0 .. Y_{L-1}`, each a `q × p` block.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkovSeq {
    q: usize,
    p: usize,
    len: usize,
    data: Vec<f64>,
}

impl MarkovSeq {
    /// A zero sequence of `len` blocks (allocates once). Use [`MarkovSeq::set_len`] to reuse it
    /// for shorter sequences without allocating.
    pub fn zeros(q: usize, p: usize, len: usize) -> Self {
        Self {
            q,
            p,
            len,
            data: vec![0.0; q * p * len],
        }
    }

    /// Wraps existing data laid out as described in the module docs.
    pub fn from_data(q: usize, p: usize, data: Vec<f64>) -> Result<Self, IdentError> {
        if q == 0 || p == 0 {
            return Err(IdentError::InvalidInput(
                "Markov blocks need q >= 1 and p >= 1",
            ));
        }
        if data.len() % (q * p) != 0 {
            return Err(IdentError::InvalidInput(
                "Markov data length is not a multiple of q*p",
            ));
        }
        let len = data.len() / (q * p);
        Ok(Self { q, p, len, data })
    }

    /// Number of outputs.
    pub fn outputs(&self) -> usize {
        self.q
    }

    /// Number of inputs.
    pub fn inputs(&self) -> usize {
        self.p
    }

    /// Number of blocks `L`.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there are no blocks.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of blocks the storage can hold without reallocating.
    pub fn capacity(&self) -> usize {
        self.data.len() / (self.q * self.p).max(1)
    }

    /// Changes the shape in place (no allocation while `q*p*len` fits the storage).
    pub fn set_len(&mut self, q: usize, p: usize, len: usize) -> Result<(), IdentError> {
        if q == 0 || p == 0 {
            return Err(IdentError::InvalidInput(
                "Markov blocks need q >= 1 and p >= 1",
            ));
        }
        let need = q * p * len;
        if need > self.data.len() {
            return Err(IdentError::LimitsExceeded {
                what: "Markov storage (q*p*blocks)",
                value: need,
                limit: self.data.len(),
            });
        }
        self.q = q;
        self.p = p;
        self.len = len;
        Ok(())
    }

    /// All blocks, flat (`q*p*len` values).
    pub fn as_slice(&self) -> &[f64] {
        &self.data[..self.q * self.p * self.len]
    }

    /// All blocks, flat and mutable.
    pub fn as_mut_slice(&mut self) -> &mut [f64] {
        let n = self.q * self.p * self.len;
        &mut self.data[..n]
    }

    /// Block `k` (`q*p` values, column-major).
    pub fn block(&self, k: usize) -> &[f64] {
        let s = self.q * self.p;
        &self.data[k * s..(k + 1) * s]
    }

    /// Block `k`, mutable.
    pub fn block_mut(&mut self, k: usize) -> &mut [f64] {
        let s = self.q * self.p;
        &mut self.data[k * s..(k + 1) * s]
    }

    /// Element (output `i`, input `j`) of block `k`.
    pub fn get(&self, k: usize, i: usize, j: usize) -> f64 {
        self.data[k * self.q * self.p + i + j * self.q]
    }
}
