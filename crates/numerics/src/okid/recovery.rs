//! Recovery of the system Markov parameters from the observer ones.
//!
//! JPHL eqs. 11–13, with `Ȳ_i⁽¹⁾ = C Ā^(i−1) (B + G D)` and `Ȳ_i⁽²⁾ = C Ā^(i−1) G`:
//!
//! ```text
//! Y_0 = D
//! Y_k = Ȳ_k⁽¹⁾ − Σ_{i=1..k} Ȳ_i⁽²⁾ Y_{k−i}          k = 1 .. ℓ
//! Y_k =        − Σ_{i=1..ℓ} Ȳ_i⁽²⁾ Y_{k−i}          k > ℓ
//! ```
//!
//! i.e. the pulse response of the fitted ARX model `y_k = Σ M_i^y y_{k−i} + Σ M_i^u u_{k−i}` with
//! `M_i^u = Ȳ_i⁽¹⁾`, `M_i^y = −Ȳ_i⁽²⁾`. The result follows the project's Markov convention
//! (`docs/ARCHITECTURE.md`): response to a unit input held for one sample, no `1/dt` scaling,
//! block `k` at `data[k·q·p ..]`, column-major inside the block.

/// `Y_0 = M_0^u`, `Y_k = M_k^u + Σ_{i=1..min(k,ℓ)} M_i^y Y_{k−i}` (`M_k^u = 0` for `k > ℓ`):
/// JPHL eqs. 11–13 written with the regression's own coefficients (`M_i^y = −Ȳ_i⁽²⁾`).
pub(super) fn recover_markov(
    theta: &(Vec<f64>, Vec<f64>),
    p: usize,
    q: usize,
    ell: usize,
    len: usize,
) -> Vec<f64> {
    let (mu, my) = theta;
    let qp = q * p;
    let mut out = vec![0.0; len * qp];
    for k in 0..len {
        let (done, rest) = out.split_at_mut(k * qp);
        let yk = &mut rest[..qp];
        if k <= ell {
            yk.copy_from_slice(&mu[k * qp..(k + 1) * qp]);
        }
        for i in 1..=k.min(ell) {
            let m = &my[i * q * q..(i + 1) * q * q];
            let prev = &done[(k - i) * qp..(k - i + 1) * qp];
            for j in 0..p {
                for r in 0..q {
                    let mut acc = 0.0;
                    for c in 0..q {
                        acc += m[r + c * q] * prev[c + j * q];
                    }
                    yk[r + j * q] += acc;
                }
            }
        }
    }
    out
}
