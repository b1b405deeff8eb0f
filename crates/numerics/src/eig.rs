//! Eigenvalues and eigenvectors of the small identified state matrix `A`, on caller-owned
//! storage (no allocation).
//!
//! Eigenvalues: reduction to upper Hessenberg form by stabilised elementary similarity
//! transforms, then the Francis double-shift QR iteration (the EISPACK `elmhes`/`hqr` pair;
//! Press et al., Numerical Recipes 3rd ed., §11.6–11.7). Eigenvectors: inverse iteration on
//! `A − μ I` with `μ` the eigenvalue nudged by a relative `1e-10` (two steps from a fixed start;
//! the solve with a near-singular matrix amplifies the eigen-direction by ~1e10 per step).

use nalgebra::Complex;

use super::linalg::solve_complex;
use super::IdentError;

/// Most QR iterations per eigenvalue.
const MAX_ITS: usize = 60;

/// Eigenvalues of `a` (`n × n`, column-major; destroyed). Complex pairs come out adjacent,
/// positive imaginary part first; `out[..n]` receives them.
pub fn eigenvalues(a: &mut [f64], n: usize, out: &mut [Complex<f64>]) -> Result<(), IdentError> {
    if a[..n * n].iter().any(|x| !x.is_finite()) {
        return Err(IdentError::EigenNotConverged);
    }
    elmhes(a, n);
    hqr(a, n, out)?;
    // Order: conjugate pairs with +im first, keep relative order otherwise.
    for k in 0..n.saturating_sub(1) {
        if out[k].im < 0.0 && (out[k + 1] - out[k].conj()).norm() <= 1e-12 * out[k].norm() {
            out.swap(k, k + 1);
        }
    }
    Ok(())
}

#[inline]
fn at(i: usize, j: usize, n: usize) -> usize {
    i + j * n
}

/// Reduction to Hessenberg form by Gaussian elimination with pivoting; clears below the
/// subdiagonal afterwards.
fn elmhes(a: &mut [f64], n: usize) {
    for m in 1..n.saturating_sub(1) {
        let mut x = 0.0f64;
        let mut i = m;
        for j in m..n {
            if a[at(j, m - 1, n)].abs() > x.abs() {
                x = a[at(j, m - 1, n)];
                i = j;
            }
        }
        if i != m {
            for j in (m - 1)..n {
                a.swap(at(i, j, n), at(m, j, n));
            }
            for j in 0..n {
                a.swap(at(j, i, n), at(j, m, n));
            }
        }
        if x != 0.0 {
            for i in (m + 1)..n {
                let mut y = a[at(i, m - 1, n)];
                if y != 0.0 {
                    y /= x;
                    a[at(i, m - 1, n)] = y;
                    for j in m..n {
                        a[at(i, j, n)] -= y * a[at(m, j, n)];
                    }
                    for j in 0..n {
                        a[at(j, m, n)] += y * a[at(j, i, n)];
                    }
                }
            }
        }
    }
    for j in 0..n {
        for i in (j + 2)..n {
            a[at(i, j, n)] = 0.0;
        }
    }
}

/// Francis double-shift QR on an upper Hessenberg matrix (Numerical Recipes `hqr`).
fn hqr(a: &mut [f64], n: usize, w: &mut [Complex<f64>]) -> Result<(), IdentError> {
    let eps = f64::EPSILON;
    let idx = |i: isize, j: isize| at(i as usize, j as usize, n);
    let mut anorm = 0.0;
    for i in 0..n {
        for j in i.saturating_sub(1)..n {
            anorm += a[at(i, j, n)].abs();
        }
    }
    let mut nn = n as isize - 1;
    let mut t = 0.0;
    let (mut p, mut q, mut r, mut s, mut x, mut y, mut z, mut ww);
    (p, q, r) = (0.0, 0.0, 0.0);
    while nn >= 0 {
        let mut its = 0;
        loop {
            let mut l = nn;
            while l > 0 {
                s = a[idx(l - 1, l - 1)].abs() + a[idx(l, l)].abs();
                if s == 0.0 {
                    s = anorm;
                }
                if a[idx(l, l - 1)].abs() <= eps * s {
                    a[idx(l, l - 1)] = 0.0;
                    break;
                }
                l -= 1;
            }
            x = a[idx(nn, nn)];
            if l == nn {
                w[nn as usize] = Complex::new(x + t, 0.0);
                nn -= 1;
            } else {
                y = a[idx(nn - 1, nn - 1)];
                ww = a[idx(nn, nn - 1)] * a[idx(nn - 1, nn)];
                if l == nn - 1 {
                    p = 0.5 * (y - x);
                    q = p * p + ww;
                    z = q.abs().sqrt();
                    x += t;
                    if q >= 0.0 {
                        z = p + z.copysign(p);
                        w[(nn - 1) as usize] = Complex::new(x + z, 0.0);
                        w[nn as usize] = Complex::new(x + z, 0.0);
                        if z != 0.0 {
                            w[nn as usize] = Complex::new(x - ww / z, 0.0);
                        }
                    } else {
                        w[nn as usize] = Complex::new(x + p, -z);
                        w[(nn - 1) as usize] = Complex::new(x + p, z);
                    }
                    nn -= 2;
                } else {
                    if its == MAX_ITS {
                        return Err(IdentError::EigenNotConverged);
                    }
                    if its == 10 || its == 20 {
                        t += x;
                        for i in 0..=nn {
                            a[idx(i, i)] -= x;
                        }
                        s = a[idx(nn, nn - 1)].abs() + a[idx(nn - 1, nn - 2)].abs();
                        x = 0.75 * s;
                        y = x;
                        ww = -0.4375 * s * s;
                    }
                    its += 1;
                    let mut m = nn - 2;
                    while m >= l {
                        z = a[idx(m, m)];
                        r = x - z;
                        s = y - z;
                        p = (r * s - ww) / a[idx(m + 1, m)] + a[idx(m, m + 1)];
                        q = a[idx(m + 1, m + 1)] - z - r - s;
                        r = a[idx(m + 2, m + 1)];
                        s = p.abs() + q.abs() + r.abs();
                        p /= s;
                        q /= s;
                        r /= s;
                        if m == l {
                            break;
                        }
                        let u = a[idx(m, m - 1)].abs() * (q.abs() + r.abs());
                        let v = p.abs()
                            * (a[idx(m - 1, m - 1)].abs() + z.abs() + a[idx(m + 1, m + 1)].abs());
                        if u <= eps * v {
                            break;
                        }
                        m -= 1;
                    }
                    for i in m..(nn - 1) {
                        a[idx(i + 2, i)] = 0.0;
                        if i != m {
                            a[idx(i + 2, i - 1)] = 0.0;
                        }
                    }
                    let mut k = m;
                    while k < nn {
                        if k != m {
                            p = a[idx(k, k - 1)];
                            q = a[idx(k + 1, k - 1)];
                            r = 0.0;
                            if k + 1 != nn {
                                r = a[idx(k + 2, k - 1)];
                            }
                            x = p.abs() + q.abs() + r.abs();
                            if x != 0.0 {
                                p /= x;
                                q /= x;
                                r /= x;
                            }
                        }
                        s = (p * p + q * q + r * r).sqrt().copysign(p);
                        if s != 0.0 {
                            if k == m {
                                if l != m {
                                    a[idx(k, k - 1)] = -a[idx(k, k - 1)];
                                }
                            } else {
                                a[idx(k, k - 1)] = -s * x;
                            }
                            p += s;
                            x = p / s;
                            y = q / s;
                            z = r / s;
                            q /= p;
                            r /= p;
                            for j in k..=nn {
                                p = a[idx(k, j)] + q * a[idx(k + 1, j)];
                                if k + 1 != nn {
                                    p += r * a[idx(k + 2, j)];
                                    a[idx(k + 2, j)] -= p * z;
                                }
                                a[idx(k + 1, j)] -= p * y;
                                a[idx(k, j)] -= p * x;
                            }
                            let mmin = if nn < k + 3 { nn } else { k + 3 };
                            for i in l..=mmin {
                                p = x * a[idx(i, k)] + y * a[idx(i, k + 1)];
                                if k + 1 != nn {
                                    p += z * a[idx(i, k + 2)];
                                    a[idx(i, k + 2)] -= p * r;
                                }
                                a[idx(i, k + 1)] -= p * q;
                                a[idx(i, k)] -= p;
                            }
                        }
                        k += 1;
                    }
                }
            }
            if l >= nn - 1 {
                break;
            }
        }
    }
    Ok(())
}

/// Right eigenvectors of `a` (`n × n`, column-major, not modified) for the eigenvalues
/// `lambda[..n]`, by inverse iteration; column `i` of `vecs` (`n × n`) is normalised to unit
/// length. `scratch` needs `n*n` entries, `x` needs `n`.
pub fn eigenvectors(
    a: &[f64],
    n: usize,
    lambda: &[Complex<f64>],
    vecs: &mut [Complex<f64>],
    scratch: &mut [Complex<f64>],
) {
    let anorm = a[..n * n]
        .iter()
        .fold(0.0f64, |s, v| s.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    for (i, &l) in lambda[..n].iter().enumerate() {
        let mu = l + Complex::new(1e-10 * anorm, 1e-11 * anorm);
        let col = &mut vecs[i * n..(i + 1) * n];
        for (k, c) in col.iter_mut().enumerate() {
            *c = Complex::new(1.0 + 0.1 * k as f64, 0.05 * k as f64);
        }
        for _ in 0..3 {
            for r in 0..n {
                for c in 0..n {
                    let diag = if r == c { mu } else { Complex::new(0.0, 0.0) };
                    scratch[r + c * n] = Complex::new(a[r + c * n], 0.0) - diag;
                }
            }
            if !solve_complex(scratch, n, col, 1) {
                break;
            }
            let norm = col.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                break;
            }
            col.iter_mut().for_each(|c| *c /= norm);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eig(a: &[f64], n: usize) -> Vec<Complex<f64>> {
        let mut m = a.to_vec();
        let mut w = vec![Complex::new(0.0, 0.0); n];
        eigenvalues(&mut m, n, &mut w).unwrap();
        w
    }

    #[test]
    fn rotation_and_triangular() {
        // Column-major [[0.9, -0.2], [0.2, 0.9]]: eigenvalues 0.9 ± 0.2i.
        let w = eig(&[0.9, 0.2, -0.2, 0.9], 2);
        assert!((w[0] - Complex::new(0.9, 0.2)).norm() < 1e-14);
        assert!((w[1] - Complex::new(0.9, -0.2)).norm() < 1e-14);
        // Upper triangular 3 × 3.
        let mut w = eig(&[0.5, 0.0, 0.0, 1.0, -0.3, 0.0, 2.0, 1.0, 0.8], 3);
        w.sort_by(|a, b| a.re.total_cmp(&b.re));
        for (got, want) in w.iter().zip([-0.3, 0.5, 0.8]) {
            assert!((got - Complex::new(want, 0.0)).norm() < 1e-13);
        }
    }

    #[test]
    fn companion_matrix_and_eigenvectors() {
        // Roots 0.5, -0.4, 0.3 ± 0.6i of (z-0.5)(z+0.4)(z²-0.6z+0.45).
        // Expand: (z² - 0.1z - 0.2)(z² - 0.6z + 0.45)
        let c = [1.0, -0.7, 0.31, 0.075, -0.09];
        let n = 4;
        let mut a = vec![0.0; 16];
        for j in 0..n {
            a[j * n] = -c[j + 1];
        }
        for i in 1..n {
            a[i + (i - 1) * n] = 1.0;
        }
        let w = eig(&a, n);
        for want in [
            Complex::new(0.5, 0.0),
            Complex::new(-0.4, 0.0),
            Complex::new(0.3, 0.6),
            Complex::new(0.3, -0.6),
        ] {
            assert!(
                w.iter().any(|g| (g - want).norm() < 1e-12),
                "{want} in {w:?}"
            );
        }
        let mut v = vec![Complex::new(0.0, 0.0); 16];
        let mut s = vec![Complex::new(0.0, 0.0); 16];
        eigenvectors(&a, n, &w, &mut v, &mut s);
        for i in 0..n {
            for r in 0..n {
                let av: Complex<f64> = (0..n).map(|c| a[r + c * n] * v[c + i * n]).sum();
                assert!((av - w[i] * v[r + i * n]).norm() < 1e-9);
            }
        }
    }
}
