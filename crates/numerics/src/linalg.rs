//! Small dense linear algebra on caller-owned storage (no allocation): LU with partial
//! pivoting for real and complex square systems, used for `(I − A)^-1 B` (DC gain) and the
//! inverse of the eigenvector matrix. Matrices are column-major, element (i, j) at `i + j*n`.

use nalgebra::Complex;

/// Solves `M X = R` in place: `m` (`n × n`) is overwritten by its LU factors, `rhs`
/// (`n × k`) by `X`. Returns false when `M` is singular to working precision.
pub fn solve_real(m: &mut [f64], n: usize, rhs: &mut [f64], k: usize) -> bool {
    let scale = m[..n * n].iter().fold(0.0f64, |s, x| s.max(x.abs()));
    if !(scale.is_finite() && scale > 0.0) {
        return false;
    }
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&a, &b| m[a + col * n].abs().total_cmp(&m[b + col * n].abs()))
            .unwrap_or(col);
        if m[piv + col * n].abs() <= 1e-14 * scale {
            return false;
        }
        if piv != col {
            for j in 0..n {
                m.swap(piv + j * n, col + j * n);
            }
            for j in 0..k {
                rhs.swap(piv + j * n, col + j * n);
            }
        }
        let p = m[col + col * n];
        for i in col + 1..n {
            let f = m[i + col * n] / p;
            if f == 0.0 {
                continue;
            }
            for j in col..n {
                m[i + j * n] -= f * m[col + j * n];
            }
            for j in 0..k {
                rhs[i + j * n] -= f * rhs[col + j * n];
            }
        }
    }
    for j in 0..k {
        for i in (0..n).rev() {
            let mut acc = rhs[i + j * n];
            for l in i + 1..n {
                acc -= m[i + l * n] * rhs[l + j * n];
            }
            rhs[i + j * n] = acc / m[i + i * n];
        }
    }
    true
}

/// Complex version of [`solve_real`]. Returns false when `M` is singular to working precision.
pub fn solve_complex(m: &mut [Complex<f64>], n: usize, rhs: &mut [Complex<f64>], k: usize) -> bool {
    let scale = m[..n * n].iter().fold(0.0f64, |s, x| s.max(x.norm()));
    if !(scale.is_finite() && scale > 0.0) {
        return false;
    }
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&a, &b| m[a + col * n].norm().total_cmp(&m[b + col * n].norm()))
            .unwrap_or(col);
        if m[piv + col * n].norm() <= 1e-14 * scale {
            return false;
        }
        if piv != col {
            for j in 0..n {
                m.swap(piv + j * n, col + j * n);
            }
            for j in 0..k {
                rhs.swap(piv + j * n, col + j * n);
            }
        }
        let p = m[col + col * n];
        for i in col + 1..n {
            let f = m[i + col * n] / p;
            for j in col..n {
                let t = m[col + j * n];
                m[i + j * n] -= f * t;
            }
            for j in 0..k {
                let t = rhs[col + j * n];
                rhs[i + j * n] -= f * t;
            }
        }
    }
    for j in 0..k {
        for i in (0..n).rev() {
            let mut acc = rhs[i + j * n];
            for l in i + 1..n {
                acc -= m[i + l * n] * rhs[l + j * n];
            }
            rhs[i + j * n] = acc / m[i + i * n];
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn real_and_complex_solves() {
        let mut m = [0.0, 2.0, 1.0, 1.0]; // [[0, 1], [2, 1]] needs pivoting
        let mut r = [1.0, 4.0];
        assert!(solve_real(&mut m, 2, &mut r, 1));
        assert!((r[0] - 1.5).abs() < 1e-15 && (r[1] - 1.0).abs() < 1e-15);
        let mut s = [1.0, 2.0, 2.0, 4.0];
        assert!(!solve_real(&mut s, 2, &mut [1.0, 1.0], 1));
        let i = Complex::new(0.0, 1.0);
        let one = Complex::new(1.0, 0.0);
        let mut mc = [i, one, one, i]; // [[i, 1], [1, i]], det = -2
        let mut rc = [one, one];
        assert!(solve_complex(&mut mc, 2, &mut rc, 1));
        // x = y = 1/(1+i)
        let want = one / (one + i);
        assert!((rc[0] - want).norm() < 1e-15 && (rc[1] - want).norm() < 1e-15);
    }
}
