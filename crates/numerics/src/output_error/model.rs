//! The modal output-error model ([`super`]): its poles, output map and offsets, its free-run
//! simulation and its `(A, B, C, D, u₀, y₀)` for a model file.

use nalgebra::Complex;

/// A modal model about `(u0, y0)`; states ordered integrator (if any), real poles, pairs.
#[derive(Debug, Clone, PartialEq)]
pub struct OeModel {
    /// Whether the model has the pole at `z = 1`.
    pub integrator: bool,
    /// Real poles (stable).
    pub real: Vec<f64>,
    /// Complex pairs `(σ, ω)`, poles `σ ± jω`.
    pub pairs: Vec<(f64, f64)>,
    /// Output map, `q` rows of `n`.
    pub c: Vec<Vec<f64>>,
    /// Feedthrough, one per output.
    pub d: Vec<f64>,
    /// Input operating point `u₀` (`v = u − u₀`).
    pub u0: f64,
    /// Output offsets `y₀`.
    pub y0: Vec<f64>,
}

impl OeModel {
    /// Model order.
    pub fn order(&self) -> usize {
        usize::from(self.integrator) + self.real.len() + 2 * self.pairs.len()
    }

    /// Outputs.
    pub fn outputs(&self) -> usize {
        self.c.len()
    }

    /// The discrete poles.
    pub fn poles(&self) -> Vec<Complex<f64>> {
        let mut p = Vec::with_capacity(self.order());
        if self.integrator {
            p.push(Complex::new(1.0, 0.0));
        }
        p.extend(self.real.iter().map(|&r| Complex::new(r, 0.0)));
        for &(s, w) in &self.pairs {
            p.push(Complex::new(s, w));
            p.push(Complex::new(s, -w));
        }
        p
    }

    /// `A` (rows), `B` (rows of one column), `C`, `D` (rows of one column).
    #[allow(clippy::type_complexity)]
    pub fn abcd(&self) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let n = self.order();
        let mut a = vec![vec![0.0; n]; n];
        let mut b = vec![vec![0.0]; n];
        let mut s = 0;
        if self.integrator {
            a[0][0] = 1.0;
            b[0][0] = 1.0;
            s = 1;
        }
        for &p in &self.real {
            a[s][s] = p;
            b[s][0] = 1.0;
            s += 1;
        }
        for &(sg, w) in &self.pairs {
            a[s][s] = sg;
            a[s][s + 1] = w;
            a[s + 1][s] = -w;
            a[s + 1][s + 1] = sg;
            b[s][0] = 1.0;
            s += 2;
        }
        let d = self.d.iter().map(|&v| vec![v]).collect();
        (a, b, self.c.clone(), d)
    }

    /// Free-run simulation on `u` from the state `x0` (zero when `None`): one vector per
    /// output, `ŷ = y₀ + C x + D (u − u₀)`.
    pub fn simulate(&self, u: &[f64], x0: Option<&[f64]>) -> Vec<Vec<f64>> {
        let (a, b, c, _) = self.abcd();
        let n = self.order();
        let mut x: Vec<f64> = x0.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
        let mut xn = vec![0.0; n];
        let mut out = vec![Vec::with_capacity(u.len()); self.outputs()];
        for &uk in u {
            let v = uk - self.u0;
            for (i, o) in out.iter_mut().enumerate() {
                let cx: f64 = c[i].iter().zip(&x).map(|(c, x)| c * x).sum();
                o.push(self.y0[i] + cx + self.d[i] * v);
            }
            for r in 0..n {
                xn[r] = a[r].iter().zip(&x).map(|(a, x)| a * x).sum::<f64>() + b[r][0] * v;
            }
            std::mem::swap(&mut x, &mut xn);
        }
        out
    }

    /// DC gain per output (`C (I − A)⁻¹ B + D`); `None` with the integrator (no finite gain).
    pub fn dc_gain(&self) -> Option<Vec<f64>> {
        if self.integrator {
            return None;
        }
        let mut g = self.d.clone();
        for (i, gi) in g.iter_mut().enumerate() {
            let mut s = 0;
            for &p in &self.real {
                *gi += self.c[i][s] / (1.0 - p);
                s += 1;
            }
            for &(sg, w) in &self.pairs {
                // (I − A_m)⁻¹ e₁ = [1 − σ, −ω] / ((1 − σ)² + ω²).
                let den = (1.0 - sg).powi(2) + w * w;
                *gi += (self.c[i][s] * (1.0 - sg) - self.c[i][s + 1] * w) / den;
                s += 2;
            }
        }
        Some(g)
    }
}
