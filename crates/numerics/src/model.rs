//! The identified model as it lives in the workspace: fixed-capacity storage, filled without
//! allocation; [`Model::to_report`] and [`Model::state_space`] build allocating copies.

use nalgebra::{Complex, DMatrix};

use super::eig::{eigenvalues, eigenvectors};
use super::hankel::HankelDims;
use super::indicators::{self, Indicators, ModalInputs};
use super::linalg::solve_complex;
use super::modal::{self, continuous, fn_zeta, is_real};
use super::report::{Gain, MassSpringDamper, ModeIndicators, ModelReport, Uncertainty};
use super::statespace::Abcd;
use super::svd::SvdPath;
use super::{IdentError, StateSpace};

type C64 = Complex<f64>;

/// Most singular values a report lists.
pub const REPORTED_SINGULAR_VALUES: usize = 32;

/// One identified model (fixed capacity; values valid up to the current order and shape).
#[derive(Debug, Clone)]
pub struct Model {
    pub(crate) n: usize,
    pub(crate) q: usize,
    pub(crate) p: usize,
    pub(crate) dt_s: f64,
    pub(crate) a: Vec<f64>,
    pub(crate) b: Vec<f64>,
    pub(crate) c: Vec<f64>,
    pub(crate) d: Vec<f64>,
    poles_z: Vec<C64>,
    poles_s: Vec<C64>,
    psi: Vec<C64>,
    psi_inv: Vec<C64>,
    cscratch: Vec<C64>,
    rscratch: Vec<f64>,
    xscratch: Vec<f64>,
    dc: Vec<f64>,
    fn_hz: f64,
    zeta: f64,
    pair: Option<(usize, usize)>,
    tau: Vec<f64>,
    n_tau: usize,
    indicators: Vec<Indicators>,
    pub(crate) sigma: Vec<f64>,
    pub(crate) n_sigma: usize,
    pub(crate) dims: HankelDims,
    pub(crate) path: SvdPath,
    pub(crate) pulses: usize,
    pub(crate) skipped: usize,
    pub(crate) missing_samples: usize,
    pub(crate) noise_rms: f64,
    pub(crate) std_fn: f64,
    pub(crate) std_zeta: f64,
    pub(crate) std_dc: Vec<f64>,
    /// The automatic order's count above the noise when it stepped down from it.
    pub(crate) stepped_down_from: Option<usize>,
}

impl Model {
    /// Storage for order `max_n`, `max_q` outputs, `max_p` inputs, `max_sv` singular values.
    pub fn new(max_n: usize, max_q: usize, max_p: usize, max_sv: usize) -> Self {
        let z = C64::new(0.0, 0.0);
        Self {
            n: 0,
            q: 0,
            p: 0,
            dt_s: f64::NAN,
            a: vec![0.0; max_n * max_n],
            b: vec![0.0; max_n * max_p],
            c: vec![0.0; max_q * max_n],
            d: vec![0.0; max_q * max_p],
            poles_z: vec![z; max_n],
            poles_s: vec![z; max_n],
            psi: vec![z; max_n * max_n],
            psi_inv: vec![z; max_n * max_n],
            cscratch: vec![z; max_n * max_n],
            rscratch: vec![0.0; max_n * max_n],
            xscratch: vec![0.0; max_n * max_p.max(1)],
            dc: vec![0.0; max_q * max_p],
            fn_hz: f64::NAN,
            zeta: f64::NAN,
            pair: None,
            tau: vec![0.0; max_n],
            n_tau: 0,
            indicators: vec![Indicators::default(); max_n],
            sigma: vec![0.0; max_sv],
            n_sigma: 0,
            dims: HankelDims::default(),
            path: SvdPath::Dense,
            pulses: 0,
            skipped: 0,
            missing_samples: 0,
            noise_rms: f64::NAN,
            std_fn: f64::NAN,
            std_zeta: f64::NAN,
            std_dc: vec![f64::NAN; max_q * max_p],
            stepped_down_from: None,
        }
    }

    /// Order `n`.
    pub fn order(&self) -> usize {
        self.n
    }

    /// Sample period, seconds.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// Natural frequency of the (dominant) 2nd-order mode, Hz (NaN for order 1).
    pub fn fn_hz(&self) -> f64 {
        self.fn_hz
    }

    /// Damping ratio of that mode (NaN for order 1).
    pub fn zeta(&self) -> f64 {
        self.zeta
    }

    /// DC gain from input `j` to output `i`.
    pub fn dc_gain(&self, i: usize, j: usize) -> f64 {
        self.dc[i + j * self.q]
    }

    /// Discrete poles.
    pub fn poles_z(&self) -> &[C64] {
        &self.poles_z[..self.n]
    }

    /// Continuous poles, rad/s.
    pub fn poles_s(&self) -> &[C64] {
        &self.poles_s[..self.n]
    }

    /// Time constants of the real stable poles, seconds, descending.
    pub fn time_constants_s(&self) -> &[f64] {
        &self.tau[..self.n_tau]
    }

    /// Indicators per pole.
    pub fn indicators(&self) -> &[Indicators] {
        &self.indicators[..self.n]
    }

    /// Singular values of `H(0)` the SVD computed, descending.
    pub fn singular_values(&self) -> &[f64] {
        &self.sigma[..self.n_sigma]
    }

    /// Hankel shape used.
    pub fn hankel(&self) -> HankelDims {
        self.dims
    }

    /// SVD path taken.
    pub fn svd_path(&self) -> SvdPath {
        self.path
    }

    /// Pulses averaged and pulses left out.
    pub fn pulses(&self) -> (usize, usize) {
        (self.pulses, self.skipped)
    }

    /// Output noise RMS.
    pub fn noise_rms(&self) -> f64 {
        self.noise_rms
    }

    /// Jackknife std of (fn_hz, zeta, dc_gain of output `i`, input 0).
    pub fn uncertainty(&self, i: usize) -> (f64, f64, f64) {
        (self.std_fn, self.std_zeta, self.std_dc[i])
    }

    /// The pole pair behind `fn_hz`/`zeta`, as continuous poles.
    pub(crate) fn pair_s(&self) -> Option<(C64, C64)> {
        self.pair.map(|(i, j)| (self.poles_s[i], self.poles_s[j]))
    }

    /// The model as a [`StateSpace`] (allocates).
    pub fn state_space(&self) -> StateSpace {
        let (n, q, p) = (self.n, self.q, self.p);
        StateSpace {
            a: DMatrix::from_column_slice(n, n, &self.a[..n * n]),
            b: DMatrix::from_column_slice(n, p, &self.b[..n * p]),
            c: DMatrix::from_column_slice(q, n, &self.c[..q * n]),
            d: DMatrix::from_column_slice(q, p, &self.d[..q * p]),
            dt_s: self.dt_s,
        }
    }

    /// True when every continuous pole settles (`Re(s) < 0`, finite): the rule of
    /// [`crate::quality`]'s `unstable_pole`, asked of the automatic order
    /// ([`crate::order::model_order::settled_order`]).
    pub(crate) fn poles_settle(&self) -> bool {
        self.poles_s[..self.n]
            .iter()
            .all(|s| s.re.is_finite() && s.re < 0.0)
    }

    /// Poles, eigenvectors, fn/ζ, time constants and indicators of the realised `A` (with
    /// `B`, `C` as realised, `u`, `v` the SVD factors). The DC gain follows in
    /// [`Model::finish_gain`], after the input matrix is final.
    pub(crate) fn analyse_modes(&mut self, u: &[f64], v: &[f64]) -> Result<(), IdentError> {
        let n = self.n;
        self.rscratch[..n * n].copy_from_slice(&self.a[..n * n]);
        eigenvalues(&mut self.rscratch, n, &mut self.poles_z)?;
        for k in 0..n {
            self.poles_s[k] = continuous(self.poles_z[k], self.dt_s);
        }
        self.time_constants();
        self.eigenvectors_and_indicators(u, v);
        self.pair = self.select_pair();
        (self.fn_hz, self.zeta) = match self.pair_s() {
            Some((s1, s2)) => fn_zeta(s1, s2),
            None => (f64::NAN, f64::NAN),
        };
        Ok(())
    }

    /// Replaces the realised input matrix by the single-input `b` (`n`) and feed-through `d`
    /// (`q`): the pulse path realises one column per pulse width ([`crate::grouped`]).
    pub(crate) fn set_single_input(&mut self, b: &[f64], d: &[f64]) {
        let (n, q) = (self.n, self.q);
        self.b[..n].copy_from_slice(&b[..n]);
        self.d[..q].copy_from_slice(&d[..q]);
        self.p = 1;
    }

    /// DC gain `D + C (I − A)^-1 B`.
    pub(crate) fn finish_gain(&mut self) -> Result<(), IdentError> {
        let (n, q, p) = (self.n, self.q, self.p);
        let sys = Abcd {
            a: &self.a,
            b: &self.b,
            c: &self.c,
            d: &self.d,
            n,
            q,
            p,
        };
        let ok = modal::dc_gain(sys, &mut self.rscratch, &mut self.xscratch, &mut self.dc);
        if ok {
            Ok(())
        } else {
            Err(IdentError::SingularDcGain)
        }
    }

    fn time_constants(&mut self) {
        self.n_tau = 0;
        for k in 0..self.n {
            let (z, s) = (self.poles_z[k], self.poles_s[k]);
            if is_real(z) && z.re > 0.0 && s.re < 0.0 {
                self.tau[self.n_tau] = -1.0 / s.re;
                self.n_tau += 1;
            }
        }
        let t = &mut self.tau[..self.n_tau];
        t.sort_unstable_by(|a, b| b.total_cmp(a));
    }

    fn eigenvectors_and_indicators(&mut self, u: &[f64], v: &[f64]) {
        let n = self.n;
        eigenvectors(&self.a, n, &self.poles_z, &mut self.psi, &mut self.cscratch);
        self.cscratch[..n * n].copy_from_slice(&self.psi[..n * n]);
        let inv = &mut self.psi_inv[..n * n];
        inv.fill(C64::new(0.0, 0.0));
        for i in 0..n {
            inv[i + i * n] = C64::new(1.0, 0.0);
        }
        if !solve_complex(&mut self.cscratch, n, inv, n) {
            let nan = Indicators {
                msv: f64::NAN,
                mac: f64::NAN,
                emac: f64::NAN,
                mpc: f64::NAN,
                cmi: f64::NAN,
            };
            self.indicators[..n].fill(nan);
            return;
        }
        let inputs = ModalInputs {
            lambda: &self.poles_z[..n],
            psi: &self.psi[..n * n],
            psi_inv: &self.psi_inv[..n * n],
            b: &self.b,
            c: &self.c,
            sigma: &self.sigma,
            u,
            v,
            dims: self.dims,
            n,
        };
        for i in 0..n {
            self.indicators[i] = indicators::mode(&inputs, i);
        }
    }

    /// Order 2: both poles. Higher: the pole with the largest MSV and its conjugate (or, if
    /// real, the real pole with the next largest MSV). Order 1: none.
    fn select_pair(&self) -> Option<(usize, usize)> {
        let n = self.n;
        match n {
            0 | 1 => None,
            2 => Some((0, 1)),
            _ => {
                let msv = |k: usize| {
                    let m = self.indicators[k].msv;
                    if m.is_finite() {
                        m
                    } else {
                        0.0
                    }
                };
                let best = (0..n).max_by(|&a, &b| msv(a).total_cmp(&msv(b)))?;
                let z = self.poles_z[best];
                if !is_real(z) {
                    let conj = (0..n).filter(|&k| k != best).min_by(|&a, &b| {
                        (self.poles_z[a] - z.conj())
                            .norm()
                            .total_cmp(&(self.poles_z[b] - z.conj()).norm())
                    })?;
                    return Some((best, conj));
                }
                let other = (0..n)
                    .filter(|&k| k != best && is_real(self.poles_z[k]))
                    .max_by(|&a, &b| msv(a).total_cmp(&msv(b)))?;
                Some((best, other))
            }
        }
    }

    /// The allocating, serde-serialisable report.
    pub fn to_report(&self) -> ModelReport {
        let (n, q, p) = (self.n, self.q, self.p);
        let rows = |m: &[f64], r: usize, c: usize| -> Vec<Vec<f64>> {
            (0..r)
                .map(|i| (0..c).map(|j| m[i + j * r]).collect())
                .collect()
        };
        let pair = |z: &C64| [z.re, z.im];
        let gain0 = self.dc[0];
        let (mm, dd, kk) = if self.fn_hz.is_finite() {
            modal::mass_spring_damper(self.fn_hz, self.zeta, gain0)
        } else {
            (f64::NAN, f64::NAN, 1.0 / gain0)
        };
        ModelReport {
            order: n,
            dt_s: self.dt_s,
            fn_hz: self.fn_hz,
            zeta: self.zeta,
            dc_gain: Gain::from_block(&self.dc[..q * p], q, p),
            time_constants_s: self.time_constants_s().to_vec(),
            poles_s: self.poles_s().iter().map(pair).collect(),
            poles_z: self.poles_z().iter().map(pair).collect(),
            a: rows(&self.a, n, n),
            b: rows(&self.b, n, p),
            c: rows(&self.c, q, n),
            d: rows(&self.d, q, p),
            singular_values: self
                .singular_values()
                .iter()
                .take(REPORTED_SINGULAR_VALUES)
                .copied()
                .collect(),
            indicators: self
                .indicators()
                .iter()
                .map(|i| ModeIndicators {
                    msv: i.msv,
                    mac: i.mac,
                    emac: i.emac,
                    mpc: i.mpc,
                    cmi: i.cmi,
                })
                .collect(),
            uncertainty: Uncertainty {
                fn_hz: self.std_fn,
                zeta: self.std_zeta,
                dc_gain: Gain::from_block(&self.std_dc[..q * p], q, p),
            },
            pulses: self.pulses,
            pulses_skipped: self.skipped,
            missing_samples: self.missing_samples,
            noise_rms: self.noise_rms,
            mass_spring_damper: MassSpringDamper {
                m: mm,
                d: dd,
                k: kk,
            },
            hankel_block_rows: self.dims.r,
            hankel_block_cols: self.dims.c,
            svd: self.path.as_str().to_string(),
            order_stepped_down_from: self.stepped_down_from,
        }
    }
}
