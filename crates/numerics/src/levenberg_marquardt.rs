//! Levenberg–Marquardt for a residual vector of fixed length over box-bounded parameters, and
//! the covariance of the parameters it finds: the one nonlinear least-squares optimiser of the
//! numerics layer (the stand model's joint fit, [`crate::stand_model`]; the output-error
//! refinement of the linear core, [`crate::output_error`], through [`minimise_normal`]).
//!
//! Minimises `C(z) = Σ r_i(z)²` (Marquardt 1963, "An algorithm for least-squares estimation of
//! nonlinear parameters", J. SIAM 11(2), 431–441): with the forward-difference Jacobian
//! `J_ij = ∂r_i/∂z_j` a step solves
//!
//! ```text
//!   (JᵀJ + λ diag(JᵀJ)) δ = −Jᵀ r
//! ```
//!
//! and is taken (`λ ← 0.3 λ`) when the cost falls, else `λ ← 10 λ` and tried again. Each
//! parameter stays within its bounds `[lo_j, hi_j]`: a step is clipped to them (projected
//! Levenberg–Marquardt, Kanzow, Yamashita & Fukushima 2004), and the difference quotient at the
//! upper bound is taken backwards.
//!
//! [`minimise_normal`] is the same iteration, unbounded, for a model that supplies its own
//! normal equations `JᵀJ`, `Jᵀr` with an analytic Jacobian (accumulated sample by sample, so
//! that no `N × p` matrix is stored); a point it cannot evaluate (e.g. a pole outside the unit
//! circle) refuses the step, which is then retried shorter (`λ ← 10 λ`).
//!
//! **Covariance** ([`covariance`]): at the minimum, `Cov(z) ≈ s² (JᵀJ)⁻¹` with
//! `s² = C / (N − p)` the residual variance (Seber & Wild 2003, *Nonlinear Regression*, §2.1):
//! exact for a model linear near the optimum with white residuals of one variance; residuals
//! that are correlated from sample to sample (a model error that lasts a step) make it
//! optimistic. A parameter at a bound, or one the residuals do not depend on, gets none.

use nalgebra::{DMatrix, DVector};

/// How far the search goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmOptions {
    /// Most Jacobians computed (outer iterations).
    pub max_iter: usize,
    /// Stop when an accepted step lowers the cost by less than this share of it.
    pub rel_tol: f64,
    /// Relative step of the difference quotient (times `max(|z_j|, 1)`).
    pub diff_step: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iter: 60,
            rel_tol: 1e-9,
            diff_step: 1e-6,
        }
    }
}

/// The parameters found and what the search saw there.
#[derive(Debug, Clone, PartialEq)]
pub struct LmResult {
    /// The parameters (within their bounds).
    pub z: Vec<f64>,
    /// `Σ r²` there.
    pub cost: f64,
    /// Jacobians computed.
    pub iterations: usize,
}

/// The residuals at `z` into `r` (always the same length); `false` when `z` cannot be
/// evaluated (the step is then refused). The Jacobian is the forward difference ([`jacobian`])
/// unless the residuals give their own.
pub trait Residuals {
    /// Fills `r` with the residuals at `z`.
    fn residuals(&mut self, z: &[f64], r: &mut Vec<f64>) -> bool;

    /// `∂r/∂z` at `z` (residuals `r` there); `None` when it cannot be evaluated.
    fn jacobian(
        &mut self,
        z: &[f64],
        r: &[f64],
        bounds: &[(f64, f64)],
        diff_step: f64,
    ) -> Option<DMatrix<f64>>
    where
        Self: Sized,
    {
        jacobian(self, z, r, bounds, diff_step)
    }
}

impl<F: FnMut(&[f64], &mut Vec<f64>) -> bool> Residuals for F {
    fn residuals(&mut self, z: &[f64], r: &mut Vec<f64>) -> bool {
        self(z, r)
    }
}

fn cost_of(r: &[f64]) -> f64 {
    let c: f64 = r.iter().map(|e| e * e).sum();
    if c.is_finite() {
        c
    } else {
        f64::INFINITY
    }
}

/// The forward-difference Jacobian of `f` at `z` (residuals `r` there), column by column
/// (backwards at the upper bound); `None` when an evaluation fails.
pub fn jacobian(
    f: &mut impl Residuals,
    z: &[f64],
    r: &[f64],
    bounds: &[(f64, f64)],
    diff_step: f64,
) -> Option<DMatrix<f64>> {
    let (n, p) = (r.len(), z.len());
    let mut jac = DMatrix::<f64>::zeros(n, p);
    let mut rj = Vec::with_capacity(n);
    let mut zj = z.to_vec();
    for j in 0..p {
        let mut h = diff_step * z[j].abs().max(1.0);
        if z[j] + h > bounds[j].1 {
            h = -h;
        }
        zj[j] = z[j] + h;
        let ok = f.residuals(&zj, &mut rj);
        zj[j] = z[j];
        if !ok || rj.len() != n {
            return None;
        }
        for i in 0..n {
            jac[(i, j)] = (rj[i] - r[i]) / h;
        }
    }
    Some(jac)
}

/// Levenberg–Marquardt from `z0` within `bounds` (module doc). Never returns a worse point
/// than `z0` (clipped to its bounds); `None` when `z0` itself cannot be evaluated.
pub fn minimise(
    f: &mut impl Residuals,
    z0: &[f64],
    bounds: &[(f64, f64)],
    opts: &LmOptions,
) -> Option<LmResult> {
    let clip = |z: &mut [f64]| {
        for (v, &(lo, hi)) in z.iter_mut().zip(bounds) {
            *v = v.clamp(lo, hi);
        }
    };
    let mut z = z0.to_vec();
    clip(&mut z);
    let mut r = Vec::new();
    if !f.residuals(&z, &mut r) {
        return None;
    }
    let mut cost = cost_of(&r);
    let p = z.len();
    let mut lambda = 1e-3;
    let mut rt = Vec::with_capacity(r.len());
    let mut iterations = 0;
    while iterations < opts.max_iter && cost.is_finite() && cost > 0.0 && p > 0 {
        iterations += 1;
        let Some(jac) = f.jacobian(&z, &r, bounds, opts.diff_step) else {
            break;
        };
        let jtj = jac.transpose() * &jac;
        let jtr = jac.transpose() * DVector::from_column_slice(&r);
        let mut accepted = false;
        let mut small = false;
        for _ in 0..10 {
            let mut lhs = jtj.clone();
            for a in 0..p {
                lhs[(a, a)] += lambda * jtj[(a, a)].max(1e-12);
            }
            let Some(delta) = lhs.lu().solve(&(-&jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let mut zt: Vec<f64> = z.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
            clip(&mut zt);
            if zt == z {
                lambda *= 10.0;
                continue;
            }
            if f.residuals(&zt, &mut rt) && rt.len() == r.len() {
                let ct = cost_of(&rt);
                if ct < cost {
                    small = (cost - ct) <= opts.rel_tol * cost;
                    z = zt;
                    cost = ct;
                    std::mem::swap(&mut r, &mut rt);
                    lambda = (lambda * 0.3).max(1e-12);
                    accepted = true;
                    break;
                }
            }
            lambda *= 10.0;
        }
        if !accepted || small {
            break;
        }
    }
    Some(LmResult {
        z,
        cost,
        iterations,
    })
}

/// A least-squares problem that supplies its own normal equations ([`minimise_normal`]).
pub trait NormalEquations {
    /// `Σ r²` at `z`; `None` when `z` is not admissible (the step is refused).
    fn cost(&mut self, z: &[f64]) -> Option<f64>;
    /// `(JᵀJ, Jᵀr, Σ r²)` at `z`; `None` when `z` is not admissible.
    fn normal(&mut self, z: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>, f64)>;
}

/// Levenberg–Marquardt from `z0` on a problem with analytic normal equations (module doc):
/// never returns a worse point than `z0`; `None` when `z0` cannot be evaluated.
pub fn minimise_normal(
    f: &mut impl NormalEquations,
    z0: &[f64],
    opts: &LmOptions,
) -> Option<LmResult> {
    let mut z = z0.to_vec();
    let p = z.len();
    let (mut jtj, mut jtr, mut cost) = f.normal(&z)?;
    let mut lambda = 1e-3;
    let mut iterations = 1;
    while iterations < opts.max_iter && cost.is_finite() && cost > 0.0 && p > 0 {
        let mut accepted = false;
        let mut small = false;
        for _ in 0..12 {
            let mut lhs = jtj.clone();
            for a in 0..p {
                lhs[(a, a)] += lambda * jtj[(a, a)].max(1e-300);
            }
            let Some(delta) = lhs.lu().solve(&(-&jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let zt: Vec<f64> = z.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
            if zt.iter().any(|v| !v.is_finite()) {
                lambda *= 10.0;
                continue;
            }
            if let Some(ct) = f.cost(&zt) {
                if ct < cost {
                    small = (cost - ct) <= opts.rel_tol * cost;
                    z = zt;
                    lambda = (lambda * 0.3).max(1e-12);
                    accepted = true;
                    break;
                }
            }
            lambda *= 10.0;
        }
        if !accepted || small {
            if accepted {
                cost = f.cost(&z).unwrap_or(cost);
            }
            break;
        }
        iterations += 1;
        match f.normal(&z) {
            Some((a, b, c)) => {
                jtj = a;
                jtr = b;
                cost = c;
            }
            None => break,
        }
    }
    Some(LmResult {
        z,
        cost,
        iterations,
    })
}

/// `s² (JᵀJ)⁻¹` with `s² = cost / (N − p)` (module doc); `None` when `N ≤ p` or `JᵀJ` is
/// singular. Columns listed in `fixed` (a parameter at a bound) are left out: their rows and
/// columns of the result are zero.
pub fn covariance(jac: &DMatrix<f64>, cost: f64, fixed: &[bool]) -> Option<DMatrix<f64>> {
    let (n, p) = jac.shape();
    let free: Vec<usize> = (0..p)
        .filter(|&j| !fixed.get(j).copied().unwrap_or(false))
        .collect();
    let q = free.len();
    if n <= q || q == 0 {
        return None;
    }
    let mut a = DMatrix::<f64>::zeros(q, q);
    for (x, &i) in free.iter().enumerate() {
        for (y, &j) in free.iter().enumerate() {
            a[(x, y)] = jac.column(i).dot(&jac.column(j));
        }
    }
    // Scaled to a unit diagonal before the inversion (columns of very different sizes).
    let d: Vec<f64> = (0..q).map(|i| a[(i, i)].sqrt()).collect();
    if d.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return None;
    }
    for x in 0..q {
        for y in 0..q {
            a[(x, y)] /= d[x] * d[y];
        }
    }
    let inv = a.try_inverse()?;
    let s2 = cost / (n - q) as f64;
    let mut out = DMatrix::<f64>::zeros(p, p);
    for (x, &i) in free.iter().enumerate() {
        for (y, &j) in free.iter().enumerate() {
            out[(i, j)] = s2 * inv[(x, y)] / (d[x] * d[y]);
        }
    }
    out.iter().all(|v| v.is_finite()).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = a·exp(−b·t) + c sampled with a deterministic ±σ pattern.
    fn data() -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.01).collect();
        let y = t
            .iter()
            .enumerate()
            .map(|(k, &t)| 2.0 * (-3.0 * t).exp() + 0.5 + if k % 2 == 0 { 0.01 } else { -0.01 })
            .collect();
        (t, y)
    }

    #[test]
    fn an_exponential_is_found_from_far_and_its_covariance_is_the_residuals() {
        let (t, y) = data();
        let mut f = |z: &[f64], r: &mut Vec<f64>| {
            r.clear();
            r.extend(
                t.iter()
                    .zip(&y)
                    .map(|(&t, &y)| y - (z[0] * (-z[1] * t).exp() + z[2])),
            );
            true
        };
        let bounds = [(0.0, 10.0), (0.0, 50.0), (-5.0, 5.0)];
        let res = minimise(&mut f, &[1.0, 0.5, 0.0], &bounds, &LmOptions::default()).unwrap();
        assert!((res.z[0] - 2.0).abs() < 1e-2, "{res:?}");
        assert!((res.z[1] - 3.0).abs() < 2e-2, "{res:?}");
        assert!((res.z[2] - 0.5).abs() < 1e-2, "{res:?}");
        // The cost is the ±0.01 pattern's: 200 × 1e-4.
        assert!((res.cost - 0.02).abs() < 1e-3, "{res:?}");
        let mut r = Vec::new();
        f(&res.z, &mut r);
        let jac = jacobian(&mut f, &res.z, &r, &bounds, 1e-6).unwrap();
        let cov = covariance(&jac, res.cost, &[false; 3]).unwrap();
        // The offset's standard error is about σ/√N·(a few): small, positive.
        let sd_c = cov[(2, 2)].sqrt();
        assert!(sd_c > 1e-4 && sd_c < 5e-3, "{sd_c}");
        // A parameter left out gets none.
        let cov = covariance(&jac, res.cost, &[false, false, true]).unwrap();
        assert_eq!(cov[(2, 2)], 0.0);
    }

    #[test]
    fn a_bound_holds_and_a_parameter_the_residuals_ignore_has_no_covariance() {
        let mut f = |z: &[f64], r: &mut Vec<f64>| {
            r.clear();
            r.extend((0..10).map(|k| k as f64 - z[0]));
            true
        };
        let res = minimise(
            &mut f,
            &[0.0, 1.0],
            &[(0.0, 2.0), (0.0, 2.0)],
            &LmOptions::default(),
        )
        .unwrap();
        assert_eq!(res.z[0], 2.0, "{res:?}");
        let mut r = Vec::new();
        f(&res.z, &mut r);
        let jac = jacobian(&mut f, &res.z, &r, &[(0.0, 2.0), (0.0, 2.0)], 1e-6).unwrap();
        assert!(covariance(&jac, res.cost, &[false, false]).is_none());
    }
}
