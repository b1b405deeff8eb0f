//! Block Hankel matrices of Markov parameters, without forming them unless asked.
//!
//! `H(s)` has `r` block rows and `c` block columns of `q × p` blocks; block (a, b) is
//! `Y_{a+b+1+s}` (Juang & Pappa 1985, eq. 4): `H(0)` starts at `Y_1`, never at `Y_0 = D` (a
//! Hankel matrix that starts at `D` has one rank too many and biases a low-order model). Row
//! `a*q + i`, column `b*p + j` of `H(s)` is element (i, j) of that block. Exact data give
//! `H(s) = P_r A^s Q_c` with `P_r = [C; CA; …; CA^(r-1)]`, `Q_c = [B, AB, …, A^(c-1)B]`.

/// Shape of a block Hankel matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct HankelDims {
    /// Outputs per block.
    pub q: usize,
    /// Inputs per block.
    pub p: usize,
    /// Block rows.
    pub r: usize,
    /// Block columns.
    pub c: usize,
}

/// The block Hankel matrix `H(shift)` of the Markov parameters `markov` (flat, layout of
/// [`crate::markov`]) with shape `dims`: what the SVDs and the Hankel products take, never
/// formed unless asked ([`HankelDims::fill`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hankel<'a> {
    /// Markov blocks `Y_0 ..`, at least `dims.blocks_needed(shift)` of them.
    pub markov: &'a [f64],
    /// Block shape.
    pub dims: HankelDims,
    /// `s` of `H(s)`: block (a, b) is `Y_{a+b+1+s}`.
    pub shift: usize,
}

impl<'a> Hankel<'a> {
    /// `H(shift)` of `markov` with shape `dims`.
    pub fn new(markov: &'a [f64], dims: HankelDims, shift: usize) -> Self {
        Self {
            markov,
            dims,
            shift,
        }
    }
}

impl HankelDims {
    /// Scalar rows `r*q`.
    pub fn rows(&self) -> usize {
        self.r * self.q
    }

    /// Scalar columns `c*p`.
    pub fn cols(&self) -> usize {
        self.c * self.p
    }

    /// Markov blocks `Y_0 ..` that `H(shift)` reaches: `r + c + shift`.
    pub fn blocks_needed(&self, shift: usize) -> usize {
        self.r + self.c + shift
    }

    /// Element (row, col) of `H(shift)` from the flat Markov data.
    #[inline]
    pub fn element(&self, markov: &[f64], shift: usize, row: usize, col: usize) -> f64 {
        let (a, i) = (row / self.q, row % self.q);
        let (b, j) = (col / self.p, col % self.p);
        markov[(a + b + 1 + shift) * self.q * self.p + i + j * self.q]
    }

    /// Forms `H(shift)` column-major into `out` (`rows*cols` values).
    pub fn fill(&self, markov: &[f64], shift: usize, out: &mut [f64]) {
        let rows = self.rows();
        for col in 0..self.cols() {
            for row in 0..rows {
                out[row + col * rows] = self.element(markov, shift, row, col);
            }
        }
    }

    /// `y = H(shift) x` (`x`: cols, `y`: rows), without forming `H`: `O(rows · cols)`.
    pub fn apply(&self, markov: &[f64], shift: usize, x: &[f64], y: &mut [f64]) {
        let (q, p) = (self.q, self.p);
        let qp = q * p;
        for a in 0..self.r {
            for i in 0..q {
                let mut acc = 0.0;
                for b in 0..self.c {
                    let blk = &markov[(a + b + 1 + shift) * qp..];
                    let xb = &x[b * p..(b + 1) * p];
                    for (j, xj) in xb.iter().enumerate() {
                        acc += blk[i + j * q] * xj;
                    }
                }
                y[a * q + i] = acc;
            }
        }
    }

    /// `y = H(shift)ᵀ x` (`x`: rows, `y`: cols), without forming `H`: `O(rows · cols)`.
    pub fn apply_t(&self, markov: &[f64], shift: usize, x: &[f64], y: &mut [f64]) {
        let (q, p) = (self.q, self.p);
        let qp = q * p;
        for b in 0..self.c {
            for j in 0..p {
                let mut acc = 0.0;
                for a in 0..self.r {
                    let blk = &markov[(a + b + 1 + shift) * qp + j * q..];
                    let xa = &x[a * q..(a + 1) * q];
                    for (i, xi) in xa.iter().enumerate() {
                        acc += blk[i] * xi;
                    }
                }
                y[b * p + j] = acc;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_and_products() {
        // q = 2, p = 1: Y_k = [k, 10k].
        let markov: Vec<f64> = (0..8).flat_map(|k| [k as f64, 10.0 * k as f64]).collect();
        let d = HankelDims {
            q: 2,
            p: 1,
            r: 2,
            c: 3,
        };
        assert_eq!(d.element(&markov, 0, 0, 0), 1.0);
        assert_eq!(d.element(&markov, 0, 1, 0), 10.0);
        assert_eq!(d.element(&markov, 0, 3, 2), 40.0);
        assert_eq!(d.element(&markov, 1, 0, 0), 2.0);
        let mut h = vec![0.0; 12];
        d.fill(&markov, 0, &mut h);
        let x = [1.0, -1.0, 2.0];
        let mut y = [0.0; 4];
        d.apply(&markov, 0, &x, &mut y);
        for (r, yr) in y.iter().enumerate() {
            let want: f64 = (0..3).map(|c| h[r + c * 4] * x[c]).sum();
            assert_eq!(*yr, want);
        }
        let z = [1.0, 0.5, -1.0, 2.0];
        let mut w = [0.0; 3];
        d.apply_t(&markov, 0, &z, &mut w);
        for (c, wc) in w.iter().enumerate() {
            let want: f64 = (0..4).map(|r| h[r + c * 4] * z[r]).sum();
            assert_eq!(*wc, want);
        }
    }
}
