//! Inner kernels of the SVD paths on caller-owned slices (no allocation).
//!
//! A dot product summed left to right is bound by the latency of one floating-point add per
//! element (about 4 cycles); [`dot`] keeps [`LANES`] independent partial sums, which the compiler
//! maps to vector registers, and adds them at the end. The result differs from the sequential
//! sum by rounding only (the error bound of recursive summation, `n ε Σ|a_i b_i|`, holds for
//! any summation order; Higham, *Accuracy and Stability of Numerical Algorithms* 2nd ed., §3.1).

/// Independent partial sums in [`dot`].
pub const LANES: usize = 8;

/// `Σ a_i b_i` over the common length, with [`LANES`] partial sums.
#[inline(always)]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            acc[l] += x[l] * y[l];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    let s = ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]));
    s + tail
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_sequential_sum() {
        for n in [0usize, 1, 7, 8, 9, 17, 64, 101] {
            let a: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 3.0).collect();
            let b: Vec<f64> = (0..n).map(|i| ((i * 13 % 7) as f64 - 3.0) * 0.7).collect();
            let seq: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let scale: f64 = a.iter().zip(&b).map(|(x, y)| (x * y).abs()).sum();
            assert!(
                (dot(&a, &b) - seq).abs() <= 1e-15 * scale.max(1.0),
                "n = {n}"
            );
        }
        // Unequal lengths: the common prefix.
        assert_eq!(dot(&[1.0, 2.0, 3.0], &[1.0, 1.0]), 3.0);
    }
}
