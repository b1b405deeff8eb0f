//! The truncated Hankel SVD allocates nothing per call: a counting global allocator (this test
//! binary only) checks `compute`, `compute_at_least`, `apply`, `apply_t` and `project` after
//! the workspace was built by `TruncatedSvd::new`.

use crate::counting_alloc;

use counting_alloc::allocations;
use propid_numerics::hankel::{Hankel, HankelDims};
use propid_numerics::svd::truncated::TruncatedSvd;
use propid_numerics::svd::Triplets;

/// Damped two-output response with a little deterministic "noise".
fn markov(q: usize, len: usize) -> Vec<f64> {
    let mut m = vec![0.0; len * q];
    for k in 1..len {
        for i in 0..q {
            let t = (k - 1) as f64;
            let wiggle = ((k * 7919 + i * 104_729) % 1000) as f64 * 1e-6;
            m[k * q + i] = 0.95f64.powf(t) * (0.3 * t + i as f64).cos() + wiggle;
        }
    }
    m
}

#[test]
fn compute_and_products_allocate_nothing() {
    let (q, p, rmax, cmax, k) = (2, 1, 120, 140, 4);
    let data = markov(q, rmax + cmax + 2);
    let mut svd = TruncatedSvd::new(rmax, cmax, q, p, k);
    let mut sigma = vec![0.0; k];
    let mut u = vec![0.0; rmax * q * k];
    let mut v = vec![0.0; cmax * p * k];
    let mut out = vec![0.0; k * k];
    let mut y = vec![0.0; rmax * q];
    let mut z = vec![0.0; cmax * p];
    let (n, error_path_refused) = allocations(|| {
        for &(r, c) in &[(120, 140), (50, 60), (120, 140), (7, 9)] {
            let k = k.min(r * q).min(c * p);
            svd.compute(
                Hankel::new(&data, HankelDims { q, p, r, c }, 0),
                k,
                Triplets::new(&mut sigma, &mut u, &mut v),
            )
            .unwrap();
            svd.compute_at_least(
                Hankel::new(&data, HankelDims { q, p, r, c }, 0),
                k,
                1,
                Triplets::new(&mut sigma, &mut u, &mut v),
            )
            .unwrap();
            svd.project(
                Hankel::new(&data, HankelDims { q, p, r, c }, 1),
                k,
                &u,
                &v,
                &mut out,
            )
            .unwrap();
            svd.apply(
                Hankel::new(&data, HankelDims { q, p, r, c }, 1),
                &v[..c * p],
                &mut y,
            )
            .unwrap();
            svd.apply_t(
                Hankel::new(&data, HankelDims { q, p, r, c }, 0),
                &u[..r * q],
                &mut z,
            )
            .unwrap();
        }
        // Error paths allocate nothing either.
        svd.compute(
            Hankel::new(
                &data,
                HankelDims {
                    q,
                    p,
                    r: rmax + 1,
                    c: cmax,
                },
                0,
            ),
            k,
            Triplets::new(&mut sigma, &mut u, &mut v),
        )
        .is_err()
    });
    assert!(error_path_refused);
    assert_eq!(n, 0, "heap allocations during compute/apply");
    // The counter does see this thread's allocations.
    let (n, probe) = allocations(|| Vec::<u8>::with_capacity(16));
    assert_eq!(n, 1);
    drop(probe);
    assert!(sigma[0] > 0.0);
}
