//! One cyclic sweep of the one-sided Jacobi SVD of [`SmallJacobi`]: the pair order, the
//! orthogonality test and the rotation
//!
//! $$\zeta = \frac{\beta - \alpha}{2\gamma},\quad
//!   t = \frac{\operatorname{sign}\zeta}{|\zeta| + \sqrt{1 + \zeta^2}},\quad
//!   c = \frac{1}{\sqrt{1+t^2}},\; s = c\,t$$
//!
//! (Demmel & Veselić 1992, alg. 4.1; see the parent module), with the bookkeeping that skips
//! pairs known to be orthogonal.

use super::SmallJacobi;
use crate::svd::kernels::dot;

impl SmallJacobi {
    /// One cyclic sweep over all column pairs; returns whether any rotation was applied.
    /// Columns with squared norm at most `negligible` (rounding level of `‖B‖_F²`) count as
    /// zero: rotating them would chase rounding noise forever. The squared column norms are
    /// computed at the start of the sweep and updated by each rotation (`‖w_i‖² − t γ`,
    /// `‖w_j‖² + t γ`, exact for the rotation that annihilates `γ`), so a pair costs one dot
    /// product instead of three; a pair found orthogonal whose columns no rotation touched
    /// since (the `clock` stamps) is orthogonal still and is not recomputed.
    ///
    /// The rotation of the module docs in a form with two square roots and one division:
    /// with `d = β − α`, `h = 2γ`, `r = √(d² + h²)`, it is
    /// `c = (r + |d|) / √(2r(r + |d|))`, `s = sign(d h) |h| / √(2r(r + |d|))`
    /// (`t = s/c = sign(ζ) / (|ζ| + √(1 + ζ²))`, the smaller angle).
    pub(super) fn sweep(&mut self, negligible: f64, with_q: bool, clock: &mut u64) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor supports AVX2 (checked just above).
            return unsafe { self.sweep_avx2(negligible, with_q, clock) };
        }
        self.sweep_body(negligible, with_q, clock)
    }

    /// [`sweep`](Self::sweep) compiled with AVX2: the same operations in the same order on
    /// wider registers, so the same bits (see [`crate::svd::kernels`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn sweep_avx2(&mut self, negligible: f64, with_q: bool, clock: &mut u64) -> bool {
        self.sweep_body(negligible, with_q, clock)
    }

    #[inline(always)]
    fn sweep_body(&mut self, negligible: f64, with_q: bool, clock: &mut u64) -> bool {
        let n = self.n;
        for i in 0..n {
            let col = &self.w[i * n..(i + 1) * n];
            self.norms[i] = dot(col, col);
        }
        let mut rotated = false;
        // The pairs (i, j) of one anti-diagonal i + j = τ + 1 share no column, so the order
        // within it is free; the dependences of the row-cyclic order ((i, j) after (i, j−1) and
        // after (i−1, j)) are kept, so every rotation is the row-cyclic one, bit for bit. Two
        // pairs of an anti-diagonal are processed together, so that their dot products and
        // rotation parameters (latency-bound chains of square roots and a division) overlap.
        for tau in 0..(2 * n).saturating_sub(3) {
            let (lo, hi) = ((tau + 2).saturating_sub(n), tau / 2);
            let mut i = lo;
            while i <= hi {
                let j = tau + 1 - i;
                if i < hi {
                    rotated |= self.pair2(i, j, negligible, with_q, clock);
                    i += 2;
                } else {
                    rotated |= self.pair1(i, j, negligible, with_q, clock);
                    i += 1;
                }
            }
        }
        rotated
    }

    /// Pair `(i, j)` alone.
    #[inline(always)]
    fn pair1(
        &mut self,
        i: usize,
        j: usize,
        negligible: f64,
        with_q: bool,
        clock: &mut u64,
    ) -> bool {
        if !self.live(i, j, negligible) {
            return false;
        }
        let (a, b) = (self.norms[i], self.norms[j]);
        let (wi, wj) = two_cols(&mut self.w, self.n, i, j);
        let g = dot(wi, wj);
        let rot = needs_rotation(a, b, g).then(|| rotation(a, b, g));
        if let Some((c, s, _)) = rot {
            rotate(wi, wj, c, s);
        }
        self.settle((i, j), (a, b, g), rot, with_q, clock)
    }

    /// Pairs `(i, j)` and `(i + 1, j − 1)` of one anti-diagonal (`i + 1 < j − 1`), their
    /// chains interleaved, the bookkeeping in the row-cyclic order.
    #[inline(always)]
    fn pair2(
        &mut self,
        i: usize,
        j: usize,
        negligible: f64,
        with_q: bool,
        clock: &mut u64,
    ) -> bool {
        let (i2, j2) = (i + 1, j - 1);
        let live = (self.live(i, j, negligible), self.live(i2, j2, negligible));
        let (a1, b1) = (self.norms[i], self.norms[j]);
        let (a2, b2) = (self.norms[i2], self.norms[j2]);
        let n = self.n;
        let (wi, wi2, wj2, wj) = four_cols(&mut self.w, n, i, j2, j);
        let g1 = if live.0 { dot(wi, wj) } else { 0.0 };
        let g2 = if live.1 { dot(wi2, wj2) } else { 0.0 };
        let need = (
            live.0 && needs_rotation(a1, b1, g1),
            live.1 && needs_rotation(a2, b2, g2),
        );
        let (p1, p2) = (rotation(a1, b1, g1), rotation(a2, b2, g2));
        let rot1 = need.0.then_some(p1);
        let rot2 = need.1.then_some(p2);
        if let Some((c, s, _)) = rot1 {
            rotate(wi, wj, c, s);
        }
        if let Some((c, s, _)) = rot2 {
            rotate(wi2, wj2, c, s);
        }
        let mut rotated = false;
        if live.0 {
            rotated |= self.settle((i, j), (a1, b1, g1), rot1, with_q, clock);
        }
        if live.1 {
            rotated |= self.settle((i2, j2), (a2, b2, g2), rot2, with_q, clock);
        }
        rotated
    }

    /// Whether pair `(i, j)` needs its dot product: not found orthogonal with both columns
    /// untouched since, and neither column numerically zero.
    #[inline(always)]
    fn live(&self, i: usize, j: usize, negligible: f64) -> bool {
        let stamp = self.checked[i + j * self.n];
        let fresh = self.touched[i] > stamp || self.touched[j] > stamp;
        fresh && self.norms[i] > negligible && self.norms[j] > negligible
    }

    /// Bookkeeping after pair `(i, j)` with Gram entries `a, b, g` and rotation `rot`
    /// (`c, s, t`); returns whether it rotated.
    #[inline(always)]
    fn settle(
        &mut self,
        (i, j): (usize, usize),
        (a, b, g): (f64, f64, f64),
        rot: Option<(f64, f64, f64)>,
        with_q: bool,
        clock: &mut u64,
    ) -> bool {
        let n = self.n;
        let Some((c, s, t)) = rot else {
            self.checked[i + j * n] = *clock;
            return false;
        };
        self.norms[i] = a - t * g;
        self.norms[j] = b + t * g;
        if with_q {
            let (qi, qj) = two_cols(&mut self.q, n, i, j);
            rotate(qi, qj, c, s);
        }
        *clock += 1;
        self.touched[i] = *clock;
        self.touched[j] = *clock;
        true
    }
}

/// Orthogonality test of a column pair with squared norms `a, b` and inner product `g`:
/// rotate unless `|g| ≤ 4ε √(ab)` (squared; `W` is scaled to order one, see `iterate`).
#[inline(always)]
fn needs_rotation(a: f64, b: f64, g: f64) -> bool {
    let eps = 4.0 * f64::EPSILON;
    g * g > eps * eps * a * b
}

/// `(c, s, t)` of the rotation annihilating `g` (see `sweep`); meaningless (NaN) when
/// `g = 0` and `a = b`, a case [`needs_rotation`] excludes.
#[inline(always)]
fn rotation(a: f64, b: f64, g: f64) -> (f64, f64, f64) {
    let (d, h) = (b - a, 2.0 * g);
    let r = (d * d + h * h).sqrt();
    let inv = 1.0 / (2.0 * r * (r + d.abs())).sqrt();
    let c = (r + d.abs()) * inv;
    let s = (h.abs() * inv).copysign(d * h);
    (c, s, s / c)
}

/// Mutable views of columns `i < i + 1 < l < j` of a column-major `n`-row matrix, as
/// `(i, i + 1, l, j)`.
#[inline(always)]
fn four_cols(
    m: &mut [f64],
    n: usize,
    i: usize,
    l: usize,
    j: usize,
) -> (&mut [f64], &mut [f64], &mut [f64], &mut [f64]) {
    let (lo, rest) = m.split_at_mut((i + 1) * n);
    let (mid, rest) = rest.split_at_mut(n);
    let (gap, hi) = rest.split_at_mut((j - i - 2) * n);
    let col_l = &mut gap[(l - i - 2) * n..(l - i - 1) * n];
    (&mut lo[i * n..], &mut mid[..], col_l, &mut hi[..n])
}

/// Mutable views of columns `i < j` of a column-major `n`-row matrix.
#[inline(always)]
pub(super) fn two_cols(m: &mut [f64], n: usize, i: usize, j: usize) -> (&mut [f64], &mut [f64]) {
    let (lo, hi) = m.split_at_mut(j * n);
    (&mut lo[i * n..(i + 1) * n], &mut hi[..n])
}

/// `(x, y) ← (c x − s y, s x + c y)`.
#[inline(always)]
fn rotate(x: &mut [f64], y: &mut [f64], c: f64, s: f64) {
    for (a, b) in x.iter_mut().zip(y.iter_mut()) {
        let (xa, yb) = (*a, *b);
        *a = c * xa - s * yb;
        *b = s * xa + c * yb;
    }
}
