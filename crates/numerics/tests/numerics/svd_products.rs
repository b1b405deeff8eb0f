//! Property test: the FFT block-Hankel products equal the dense products for arbitrary block
//! sizes, channel counts, shifts and data (relative to the size of the terms summed).

use propid_numerics::hankel::{Hankel, HankelDims};
use propid_numerics::svd::hankel_op::HankelOp;
use proptest::prelude::*;

fn dense_apply(m: &[f64], q: usize, p: usize, r: usize, c: usize, s: usize, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; r * q];
    for a in 0..r {
        for i in 0..q {
            let mut acc = 0.0;
            for b in 0..c {
                for j in 0..p {
                    acc += m[(a + b + 1 + s) * q * p + i + j * q] * x[b * p + j];
                }
            }
            y[a * q + i] = acc;
        }
    }
    y
}

fn dense_apply_t(
    m: &[f64],
    q: usize,
    p: usize,
    r: usize,
    c: usize,
    s: usize,
    x: &[f64],
) -> Vec<f64> {
    let mut z = vec![0.0; c * p];
    for b in 0..c {
        for j in 0..p {
            let mut acc = 0.0;
            for a in 0..r {
                for i in 0..q {
                    acc += m[(a + b + 1 + s) * q * p + i + j * q] * x[a * q + i];
                }
            }
            z[b * p + j] = acc;
        }
    }
    z
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn fft_products_equal_dense(
        q in 1usize..4, p in 1usize..3, r in 1usize..40, c in 1usize..40, s in 0usize..3,
        seed in any::<u64>(),
    ) {
        let len = (r + c + s) * q * p;
        let mut state = seed | 1;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let m: Vec<f64> = (0..len).map(|_| next()).collect();
        let x: Vec<f64> = (0..c * p).map(|_| next()).collect();
        let xt: Vec<f64> = (0..r * q).map(|_| next()).collect();
        let mut op = HankelOp::new(r, c, q, p);
        let mut y = vec![0.0; r * q];
        let mut z = vec![0.0; c * p];
        op.apply(Hankel::new(&m, HankelDims { q, p, r, c }, s), &x, &mut y).unwrap();
        op.apply_t(Hankel::new(&m, HankelDims { q, p, r, c }, s), &xt, &mut z).unwrap();
        // Each entry sums at most c p (or r q) terms of size <= 1/4.
        let tol = 1e-13 * (r + c) as f64 * (q * p) as f64;
        for (a, b) in y.iter().zip(dense_apply(&m, q, p, r, c, s, &x)) {
            prop_assert!((a - b).abs() <= tol, "H x: {} vs {}", a, b);
        }
        for (a, b) in z.iter().zip(dense_apply_t(&m, q, p, r, c, s, &xt)) {
            prop_assert!((a - b).abs() <= tol, "Hᵀ x: {} vs {}", a, b);
        }
    }
}
