//! Block-Hankel matrix–vector products through FFT convolution, never forming the matrix.
//!
//! The block Hankel matrix of the project's convention (see `docs/ARCHITECTURE.md`) has `r`
//! block rows and `c` block columns of `q × p` Markov blocks,
//!
//! $$H(s)_{(a,b)} = Y_{a+b+1+s}, \qquad a = 0..r,\; b = 0..c,$$
//!
//! with block `k` stored column-major at `markov[k*q*p ..]`. Write
//! `h_ij[m] = Y_{m+1+s}(i, j)` for `m = 0 .. r+c-1`. Then for `y = H x` (x of length `c p`,
//! y of length `r q`, entry `b*p + j` of x belongs to block column `b`, input `j`)
//!
//! $$y_i[a] = \sum_j \sum_{b=0}^{c-1} h_{ij}[a+b]\, x_j[b]
//!         = \sum_j (h_{ij} * \tilde x_j)[a + c - 1],$$
//!
//! a correlation that becomes a convolution with the reversed vector
//! `x̃_j[b] = x_j[c-1-b]`. The full linear convolution has length `r + 2c - 2`; a circular
//! convolution of length `n ≥ r + c - 1` only aliases indices `≥ n` onto `0 .. r+2c-2-n ≤ c-2`,
//! below the `c - 1 .. c + r - 2` we read, so `n ≥ r + c - 1` is exact. The transpose
//! `z = Hᵀ x` is the same with the roles of rows and columns exchanged:
//! `z_j[b] = Σ_i (h_ij * x̃_i)[b + r - 1]` with `x̃_i[a] = x_i[r-1-a]`.
//!
//! Cost per product: `p + q` real FFTs of length `n` and `q p (n/2+1)` complex multiply-adds,
//! against `r q c p` for the dense product. The spectra of the `q p` sequences `h_ij` are
//! computed once per matrix by [`HankelOp::prepare`] and reused by every product.
//!
//! All FFT plans (lengths `2^a` and `3·2^a` up to the largest needed), spectra and scratch are
//! allocated in [`HankelOp::new`]; `prepare`, `apply` and `apply_t` allocate nothing.

use std::sync::Arc;

use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};

use super::truncated::error::TruncatedError;
use crate::hankel::{Hankel, HankelDims};

/// Smallest FFT length for which a plan is made.
const MIN_FFT_LEN: usize = 16;

/// One FFT length with its forward and inverse real plans.
struct Plan {
    len: usize,
    fwd: Arc<dyn RealToComplex<f64>>,
    inv: Arc<dyn ComplexToReal<f64>>,
}

/// What [`HankelOp::prepare`] last loaded into the spectra.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Shape {
    q: usize,
    p: usize,
    r: usize,
    c: usize,
    plan: usize,
}

/// FFT-based products with a block Hankel matrix `H(s)`; see the module documentation.
pub struct HankelOp {
    max_rows: usize,
    max_cols: usize,
    max_q: usize,
    max_p: usize,
    plans: Vec<Plan>,
    /// `q p` spectra of `h_ij`, each `max_len/2 + 1` long, already scaled by `1/n`.
    spectra: Vec<Complex<f64>>,
    /// `max(p, q)` spectra of the reversed input channels.
    xspec: Vec<Complex<f64>>,
    /// One accumulated output spectrum.
    acc: Vec<Complex<f64>>,
    /// One real time-domain buffer of the largest length.
    time: Vec<f64>,
    scratch: Vec<Complex<f64>>,
    /// Spectrum stride (`max_len/2 + 1`).
    stride: usize,
    shape: Option<Shape>,
}

impl std::fmt::Debug for HankelOp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HankelOp")
            .field("max_rows", &self.max_rows)
            .field("max_cols", &self.max_cols)
            .field("max_q", &self.max_q)
            .field("max_p", &self.max_p)
            .field(
                "fft_lengths",
                &self.plans.iter().map(|p| p.len).collect::<Vec<_>>(),
            )
            .field("shape", &self.shape)
            .finish()
    }
}

impl HankelOp {
    /// Allocates everything for Hankel matrices of up to `max_block_rows × max_block_cols`
    /// blocks of at most `max_q × max_p` (each argument is raised to at least 1).
    pub fn new(max_block_rows: usize, max_block_cols: usize, max_q: usize, max_p: usize) -> Self {
        let max_rows = max_block_rows.max(1);
        let max_cols = max_block_cols.max(1);
        let max_q = max_q.max(1);
        let max_p = max_p.max(1);
        let needed = max_rows + max_cols - 1;
        let mut planner = RealFftPlanner::<f64>::new();
        let mut plans = Vec::new();
        for len in fft_lengths(needed) {
            plans.push(Plan {
                len,
                fwd: planner.plan_fft_forward(len),
                inv: planner.plan_fft_inverse(len),
            });
        }
        let max_len = plans.last().map_or(MIN_FFT_LEN, |p| p.len);
        let scratch_len = plans
            .iter()
            .map(|p| p.fwd.get_scratch_len().max(p.inv.get_scratch_len()))
            .max()
            .unwrap_or(0);
        let stride = max_len / 2 + 1;
        let zero = Complex::new(0.0, 0.0);
        HankelOp {
            max_rows,
            max_cols,
            max_q,
            max_p,
            plans,
            spectra: vec![zero; max_q * max_p * stride],
            xspec: vec![zero; max_q.max(max_p) * stride],
            acc: vec![zero; stride],
            time: vec![0.0; max_len],
            scratch: vec![zero; scratch_len],
            stride,
            shape: None,
        }
    }

    /// Largest number of block rows this operator accepts.
    pub fn max_block_rows(&self) -> usize {
        self.max_rows
    }

    /// Largest number of block columns this operator accepts.
    pub fn max_block_cols(&self) -> usize {
        self.max_cols
    }

    /// Loads `H(shift)` (`r × c` blocks of `q × p` from `markov`, [`Hankel`]): computes and keeps the
    /// spectra of the `q p` sequences `h_ij` (one real FFT each). Checks every Markov value
    /// used for finiteness.
    pub fn prepare(&mut self, h: Hankel<'_>) -> Result<(), TruncatedError> {
        let Hankel {
            markov,
            dims: HankelDims { q, p, r, c },
            shift,
        } = h;
        self.shape = None;
        check_dim("q", q, self.max_q)?;
        check_dim("p", p, self.max_p)?;
        check_dim("block rows", r, self.max_rows)?;
        check_dim("block cols", c, self.max_cols)?;
        let qp = q * p;
        let len = r + c - 1;
        let needed = (len + 1 + shift) * qp;
        if markov.len() < needed {
            return Err(TruncatedError::MarkovTooShort {
                needed,
                got: markov.len(),
            });
        }
        let start = (1 + shift) * qp;
        if let Some(i) = markov[start..needed].iter().position(|v| !v.is_finite()) {
            return Err(TruncatedError::NonFinite {
                what: "markov",
                index: start + i,
            });
        }
        let plan =
            self.plans
                .iter()
                .position(|pl| pl.len >= len)
                .ok_or(TruncatedError::Dimension {
                    what: "block rows + block cols",
                    got: r + c,
                    max: self.max_rows + self.max_cols,
                })?;
        let n = self.plans[plan].len;
        let half = n / 2 + 1;
        let scale = 1.0 / n as f64;
        for j in 0..p {
            for i in 0..q {
                let time = &mut self.time[..n];
                time.fill(0.0);
                for (m, t) in time[..len].iter_mut().enumerate() {
                    *t = markov[start + m * qp + i + j * q] * scale;
                }
                let off = (i + j * q) * self.stride;
                let out = &mut self.spectra[off..off + half];
                self.plans[plan]
                    .fwd
                    .process_with_scratch(time, out, &mut self.scratch)
                    .map_err(|e| TruncatedError::Fft(e.to_string()))?;
            }
        }
        self.shape = Some(Shape { q, p, r, c, plan });
        Ok(())
    }

    /// `y = H x` for the matrix loaded by the last [`prepare`](Self::prepare):
    /// `x` has `c p` entries, `y` receives `r q`.
    pub fn apply_prepared(&mut self, x: &[f64], y: &mut [f64]) -> Result<(), TruncatedError> {
        let s = self.shape.ok_or(TruncatedError::NotPrepared)?;
        self.product(s, false, x, y)
    }

    /// `y = Hᵀ x` for the matrix loaded by the last [`prepare`](Self::prepare):
    /// `x` has `r q` entries, `y` receives `c p`.
    pub fn apply_t_prepared(&mut self, x: &[f64], y: &mut [f64]) -> Result<(), TruncatedError> {
        let s = self.shape.ok_or(TruncatedError::NotPrepared)?;
        self.product(s, true, x, y)
    }

    /// `y = H(shift) x` in one call ([`prepare`](Self::prepare) then
    /// [`apply_prepared`](Self::apply_prepared)).
    pub fn apply(&mut self, h: Hankel<'_>, x: &[f64], y: &mut [f64]) -> Result<(), TruncatedError> {
        self.prepare(h)?;
        self.apply_prepared(x, y)
    }

    /// `y = H(shift)ᵀ x` in one call.
    pub fn apply_t(
        &mut self,
        h: Hankel<'_>,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), TruncatedError> {
        self.prepare(h)?;
        self.apply_t_prepared(x, y)
    }

    /// The product itself. `transpose == false`: inputs are the `p` block-column channels
    /// (length `c`), outputs the `q` block-row channels (length `r`); `true`: the reverse.
    fn product(
        &mut self,
        s: Shape,
        transpose: bool,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), TruncatedError> {
        let (n_in, len_in, n_out, len_out) = if transpose {
            (s.q, s.r, s.p, s.c)
        } else {
            (s.p, s.c, s.q, s.r)
        };
        check_slice("x", x.len(), n_in * len_in)?;
        check_slice("y", y.len(), n_out * len_out)?;
        let x = &x[..n_in * len_in];
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(TruncatedError::NonFinite { what: "x", index });
        }
        let plan = &self.plans[s.plan];
        let n = plan.len;
        let half = n / 2 + 1;
        let stride = self.stride;
        // Spectra of the reversed, zero-padded input channels.
        for ch in 0..n_in {
            let time = &mut self.time[..n];
            time.fill(0.0);
            for b in 0..len_in {
                time[len_in - 1 - b] = x[b * n_in + ch];
            }
            let out = &mut self.xspec[ch * stride..ch * stride + half];
            plan.fwd
                .process_with_scratch(time, out, &mut self.scratch)
                .map_err(|e| TruncatedError::Fft(e.to_string()))?;
        }
        // Each output channel: sum over input channels of spectrum products, one inverse FFT.
        for out_ch in 0..n_out {
            let acc = &mut self.acc[..half];
            acc.fill(Complex::new(0.0, 0.0));
            for in_ch in 0..n_in {
                let (i, j) = if transpose {
                    (in_ch, out_ch)
                } else {
                    (out_ch, in_ch)
                };
                let h = &self.spectra[(i + j * s.q) * stride..][..half];
                let xs = &self.xspec[in_ch * stride..][..half];
                for ((a, hv), xv) in acc.iter_mut().zip(h).zip(xs) {
                    *a += hv * xv;
                }
            }
            // A real signal's spectrum has exactly real DC (and Nyquist for even n) bins.
            acc[0].im = 0.0;
            if n % 2 == 0 {
                acc[half - 1].im = 0.0;
            }
            let time = &mut self.time[..n];
            plan.inv
                .process_with_scratch(acc, time, &mut self.scratch)
                .map_err(|e| TruncatedError::Fft(e.to_string()))?;
            for a in 0..len_out {
                y[a * n_out + out_ch] = time[a + len_in - 1];
            }
        }
        Ok(())
    }
}

/// FFT lengths `2^a` and `3·2^a` from [`MIN_FFT_LEN`] up to the first one `≥ needed`.
fn fft_lengths(needed: usize) -> Vec<usize> {
    let mut lens = Vec::new();
    let mut pow = MIN_FFT_LEN;
    loop {
        for len in [pow, 3 * pow / 2] {
            lens.push(len);
            if len >= needed {
                return lens;
            }
        }
        pow *= 2;
    }
}

fn check_dim(what: &'static str, got: usize, max: usize) -> Result<(), TruncatedError> {
    if got == 0 || got > max {
        return Err(TruncatedError::Dimension { what, got, max });
    }
    Ok(())
}

fn check_slice(what: &'static str, got: usize, expected: usize) -> Result<(), TruncatedError> {
    if got < expected {
        return Err(TruncatedError::SliceLength {
            what,
            got,
            expected,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dense `H(shift)` (row-major, `r q × c p`) for reference.
    fn dense(markov: &[f64], q: usize, p: usize, r: usize, c: usize, s: usize) -> Vec<f64> {
        let (rows, cols) = (r * q, c * p);
        let mut h = vec![0.0; rows * cols];
        for a in 0..r {
            for b in 0..c {
                let blk = (a + b + 1 + s) * q * p;
                for i in 0..q {
                    for j in 0..p {
                        h[(a * q + i) * cols + b * p + j] = markov[blk + i + j * q];
                    }
                }
            }
        }
        h
    }

    fn pseudo(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            })
            .collect()
    }

    fn check(q: usize, p: usize, r: usize, c: usize, s: usize) {
        let markov = pseudo((r + c + s + 1) * q * p, 7);
        let h = dense(&markov, q, p, r, c, s);
        let (rows, cols) = (r * q, c * p);
        let x = pseudo(cols, 3);
        let xt = pseudo(rows, 5);
        let mut op = HankelOp::new(r + 3, c + 2, q, p);
        let mut y = vec![0.0; rows];
        let mut z = vec![0.0; cols];
        let hk = Hankel::new(&markov, HankelDims { q, p, r, c }, s);
        op.apply(hk, &x, &mut y).unwrap();
        op.apply_t(hk, &xt, &mut z).unwrap();
        for (row, yv) in y.iter().enumerate() {
            let want: f64 = (0..cols).map(|k| h[row * cols + k] * x[k]).sum();
            assert!((yv - want).abs() < 1e-12, "H x row {row}: {yv} vs {want}");
        }
        for (col, zv) in z.iter().enumerate() {
            let want: f64 = (0..rows).map(|k| h[k * cols + col] * xt[k]).sum();
            assert!((zv - want).abs() < 1e-12, "Hᵀ x col {col}: {zv} vs {want}");
        }
    }

    #[test]
    fn siso_products_match_dense() {
        check(1, 1, 1, 1, 0);
        check(1, 1, 7, 7, 0);
        check(1, 1, 20, 33, 1);
        check(1, 1, 64, 5, 2);
    }

    #[test]
    fn block_products_match_dense() {
        check(2, 1, 9, 11, 0);
        check(3, 2, 6, 4, 1);
        check(1, 3, 17, 8, 0);
    }

    #[test]
    fn fft_lengths_cover_needed() {
        assert_eq!(fft_lengths(1), vec![16]);
        assert_eq!(fft_lengths(17), vec![16, 24]);
        assert_eq!(*fft_lengths(99_999).last().unwrap(), 131_072);
        assert!(fft_lengths(1000).windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        let mut op = HankelOp::new(4, 4, 1, 1);
        let markov = vec![1.0; 20];
        let mut y = vec![0.0; 4];
        let dims = |r, c| HankelDims { q: 1, p: 1, r, c };
        let e = op.apply(Hankel::new(&markov, dims(5, 4), 0), &[0.0; 4], &mut y);
        assert!(matches!(e, Err(TruncatedError::Dimension { .. })));
        let e = op.apply(Hankel::new(&markov[..5], dims(4, 4), 0), &[0.0; 4], &mut y);
        assert!(matches!(e, Err(TruncatedError::MarkovTooShort { .. })));
        let mut bad = markov.clone();
        bad[3] = f64::NAN;
        let e = op.apply(Hankel::new(&bad, dims(4, 4), 0), &[0.0; 4], &mut y);
        assert_eq!(
            e,
            Err(TruncatedError::NonFinite {
                what: "markov",
                index: 3
            })
        );
        let e = op.apply(Hankel::new(&markov, dims(4, 4), 0), &[0.0; 3], &mut y);
        assert!(matches!(
            e,
            Err(TruncatedError::SliceLength { what: "x", .. })
        ));
        let mut op2 = HankelOp::new(4, 4, 1, 1);
        assert!(op2.apply_prepared(&[0.0; 4], &mut y).is_err());
    }
}
