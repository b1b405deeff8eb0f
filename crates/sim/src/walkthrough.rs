//! The numbers of the walkthrough: the derivation of ERA on a simulated noisy
//! mass–spring–damper, step by step as in the seed article ("A deeper look into the
//! Eigensystem Realisation Algorithm", after Juang & Pappa 1985, J. Guidance 8(5)).
//!
//! 1. Plant `m ẍ + d ẋ + k x = F`, state `(x, ẋ)`, input the force `F`, output `x`,
//!    discretised exactly with a zero-order hold at `dt`: `A_d = e^{A dt}`,
//!    `B_d = ∫₀^dt e^{A s} ds B` (one augmented matrix exponential). Its Markov parameters
//!    `y_k = C A_d^{k−1} B_d` are the response to a unit force held for one sample (the
//!    project's convention, no `1/dt`), measured with white Gaussian noise.
//! 2. Hankel matrices `H_1` (`n × n`, entries `y_{i+j+1}`) and `H_2` (`y_{i+j+2}`).
//!    Exact full-order model: `Â = H_2 H_1⁻¹`, `b̂ = H_1 e`, `ĉ = e` — it reproduces the
//!    noisy samples it was built from and nothing else (its step response is wrong).
//! 3. SVD `H_1 = P D Qᵀ`; the Pareto chart of the singular values with their cumulative share.
//! 4. Cleaned full-order model with the rank-`r` pseudo-inverse
//!    `H̃_1* = Q̃ D̃⁻¹ P̃ᵀ`: `Ã = H_2 H̃_1*`, `b̃ = H̃_1 e`, `c̃ = e`.
//! 5. Reduced model of order `r` by the core's ERA ([`propid_numerics::workspace::Workspace`]):
//!    `A = D̃^{−½} P̃ᵀ H_2 Q̃ D̃^{−½}`, `b = D̃^{½} Q̃ᵀ e`, `cᵀ = eᵀ P̃ D̃^{½}`; its `m, d, k`
//!    (`k = 1/DC gain`, `m = k/ωn²`, `d = 2ζωn m`) against the true ones.

use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use propid_numerics::markov::MarkovSeq;
use propid_numerics::svd::dense::DenseSvd;
use propid_numerics::svd::{SvdChoice, Triplets};
use propid_numerics::workspace::{IdentOptions, Limits, Workspace};
use propid_numerics::ModelReport;

use propid_numerics::{IdentError, SvdError};

/// Why the walkthrough's derivation could not be made.
#[derive(Debug, thiserror::Error)]
pub enum WalkthroughError {
    /// The simulated set-up is out of range.
    #[error("{0}")]
    Setup(&'static str),
    /// The exact full-order model does not exist.
    #[error("H_1 is singular: no exact full-order model")]
    SingularH1,
    /// The SVD of the Hankel matrix failed.
    #[error("SVD of H_1: {0}")]
    Svd(#[source] SvdError),
    /// The noise distribution refused its standard deviation.
    #[error("noise: {0}")]
    Noise(#[source] rand_distr::NormalError),
    /// The identification core refused its set-up.
    #[error(transparent)]
    Core(IdentError),
    /// ERA failed on the measured Markov parameters.
    #[error("ERA: {0}")]
    Era(#[source] IdentError),
    /// The core's report does not hold a consistent `(A, B, C, D)`.
    #[error("the ERA report has inconsistent matrix sizes")]
    InconsistentReport,
}

/// What the walkthrough simulates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// Mass (kg).
    pub m: f64,
    /// Damping (N·s/m).
    pub d: f64,
    /// Stiffness (N/m).
    pub k: f64,
    /// Sample time (s).
    pub dt_s: f64,
    /// Hankel size `n` (`H_1` is `n × n`; the measurement has `2n + 1` samples).
    pub hankel: usize,
    /// Standard deviation of the measurement noise (m).
    pub noise: f64,
    /// Order of the cleaned and reduced models.
    pub order: usize,
    /// Samples simulated for the response plots (beyond the measurement).
    pub horizon: usize,
    /// Noise seed.
    pub seed: u64,
}

impl Default for Setup {
    fn default() -> Self {
        Self {
            m: 1.0,
            d: 0.6,
            k: 100.0,
            dt_s: 0.02,
            hankel: 150,
            noise: 2e-5,
            order: 2,
            horizon: 600,
            seed: 7,
        }
    }
}

/// Impulse and step responses of one model over the plot horizon.
#[derive(Debug, Clone)]
pub struct Responses {
    /// `y_k`, `k = 0 .. horizon` (response to a unit force held for one sample at `k = 0`).
    pub impulse: Vec<f64>,
    /// Response to a unit force step at `k = 0`.
    pub step: Vec<f64>,
}

/// Everything the page and the plots show.
#[derive(Debug, Clone)]
pub struct Derivation {
    /// The inputs.
    pub setup: Setup,
    /// Noise-free impulse and step responses.
    pub truth: Responses,
    /// The measured (noisy) impulse response, `2n + 1` samples, `y_0 = 0`.
    pub measured: Vec<f64>,
    /// Exact full-order model `Â = H_2 H_1⁻¹`.
    pub exact: Responses,
    /// Largest eigenvalue magnitude of `Â`.
    pub exact_spectral_radius: f64,
    /// All singular values of `H_1`, descending.
    pub singular_values: Vec<f64>,
    /// SVD-cleaned full-order model.
    pub cleaned: Responses,
    /// Reduced model by ERA.
    pub reduced: Responses,
    /// The core's report of the reduced model.
    pub report: ModelReport,
    /// True natural frequency (Hz) and damping ratio.
    pub true_fn_zeta: (f64, f64),
}

impl Derivation {
    /// Runs the derivation.
    pub fn run(setup: Setup) -> Result<Self, WalkthroughError> {
        check_setup(&setup)?;
        let (ad, bd) = discretise(&setup);
        let truth = responses_ss(&ad, &bd, &DVector::from_vec(vec![1.0, 0.0]), setup.horizon);
        let n = setup.hankel;
        let measured = measure(&truth.impulse[..2 * n + 1], setup.noise, setup.seed)?;
        let h1 = hankel(&measured, n, 1);
        let h2 = hankel(&measured, n, 2);

        // Exact full-order model: Â H_1 = H_2  ⇔  H_1ᵀ Âᵀ = H_2ᵀ.
        let a_exact = h1
            .transpose()
            .lu()
            .solve(&h2.transpose())
            .ok_or(WalkthroughError::SingularH1)?
            .transpose();
        let b_exact = h1.column(0).into_owned();
        let c_exact = unit(n);
        let exact = responses_ss(&a_exact, &b_exact, &c_exact, setup.horizon);
        let exact_spectral_radius = a_exact
            .complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max);

        // SVD of H_1 (the core's one-sided Jacobi: every singular value, accurate).
        let r = setup.order;
        let mut svd = DenseSvd::new(n, n);
        let mut sigma = vec![0.0; n];
        let (mut p, mut q) = (vec![0.0; n * r], vec![0.0; n * r]);
        svd.compute(
            h1.as_slice(),
            n,
            n,
            r,
            Triplets::new(&mut sigma, &mut p, &mut q),
        )
        .map_err(WalkthroughError::Svd)?;
        let p = DMatrix::from_column_slice(n, r, &p);
        let q = DMatrix::from_column_slice(n, r, &q);
        let d_inv = DMatrix::from_diagonal(&DVector::from_iterator(
            r,
            sigma[..r].iter().map(|s| 1.0 / s),
        ));
        let d = DMatrix::from_diagonal(&DVector::from_column_slice(&sigma[..r]));

        // Cleaned full-order model with the rank-r pseudo-inverse.
        let h1_pinv = &q * &d_inv * p.transpose();
        let h1_clean = &p * &d * q.transpose();
        let a_clean = &h2 * h1_pinv;
        let b_clean = h1_clean.column(0).into_owned();
        let cleaned = responses_ss(&a_clean, &b_clean, &unit(n), setup.horizon);

        // Reduced model: the core's ERA on the same Markov parameters and Hankel size.
        let report = era(&setup, &measured)?;
        let reduced = responses_report(&report, setup.horizon)?;

        let wn = (setup.k / setup.m).sqrt();
        let zeta = setup.d / (2.0 * (setup.k * setup.m).sqrt());
        Ok(Self {
            setup,
            truth,
            measured,
            exact,
            exact_spectral_radius,
            singular_values: sigma,
            cleaned,
            reduced,
            report,
            true_fn_zeta: (wn / (2.0 * std::f64::consts::PI), zeta),
        })
    }
}

fn check_setup(s: &Setup) -> Result<(), WalkthroughError> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !(positive(s.m) && positive(s.k) && s.d.is_finite() && s.d >= 0.0) {
        return Err(WalkthroughError::Setup(
            "m and k must be finite and > 0, d finite and >= 0",
        ));
    }
    if !(positive(s.dt_s) && s.noise.is_finite() && s.noise >= 0.0) {
        return Err(WalkthroughError::Setup(
            "dt must be finite and > 0, noise finite and >= 0",
        ));
    }
    if s.order == 0 || s.hankel < s.order + 2 || s.hankel > 1000 {
        return Err(WalkthroughError::Setup(
            "need order >= 1 and order + 2 <= Hankel size <= 1000",
        ));
    }
    if s.horizon < 2 * s.hankel + 1 {
        return Err(WalkthroughError::Setup(
            "the plot horizon must cover the measurement (2n + 1 samples)",
        ));
    }
    Ok(())
}

/// Zero-order-hold discretisation by the augmented exponential
/// `exp([[A, B], [0, 0]] dt) = [[A_d, B_d], [0, I]]`.
fn discretise(s: &Setup) -> (DMatrix<f64>, DVector<f64>) {
    let mut aug = DMatrix::<f64>::zeros(3, 3);
    aug[(0, 1)] = 1.0;
    aug[(1, 0)] = -s.k / s.m;
    aug[(1, 1)] = -s.d / s.m;
    aug[(1, 2)] = 1.0 / s.m;
    let e = (aug * s.dt_s).exp();
    let ad = e.view((0, 0), (2, 2)).into_owned();
    let bd = DVector::from_vec(vec![e[(0, 2)], e[(1, 2)]]);
    (ad, bd)
}

/// `e₁` of length `n`.
fn unit(n: usize) -> DVector<f64> {
    let mut e = DVector::zeros(n);
    e[0] = 1.0;
    e
}

/// Impulse (`y_0 = 0`, `y_k = cᵀ A^{k−1} b`) and step responses over `len` samples.
fn responses_ss(a: &DMatrix<f64>, b: &DVector<f64>, c: &DVector<f64>, len: usize) -> Responses {
    let mut impulse = vec![0.0; len];
    let mut x = b.clone();
    for y in impulse.iter_mut().skip(1) {
        *y = c.dot(&x);
        x = a * &x;
    }
    Responses {
        step: cumulative(&impulse),
        impulse,
    }
}

/// Step response as the running sum of the impulse response (saturating at ±f64::MAX).
fn cumulative(impulse: &[f64]) -> Vec<f64> {
    let mut acc = 0.0f64;
    impulse
        .iter()
        .map(|y| {
            acc += y;
            acc
        })
        .collect()
}

/// Adds seeded white Gaussian noise to the samples after `y_0` (which stays the known `D = 0`).
fn measure(clean: &[f64], sigma: f64, seed: u64) -> Result<Vec<f64>, WalkthroughError> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let normal = Normal::new(0.0, sigma).map_err(WalkthroughError::Noise)?;
    Ok(clean
        .iter()
        .enumerate()
        .map(|(k, y)| {
            if k == 0 {
                0.0
            } else {
                y + normal.sample(&mut rng)
            }
        })
        .collect())
}

/// `n × n` Hankel matrix with entries `y_{i + j + first}`.
fn hankel(y: &[f64], n: usize, first: usize) -> DMatrix<f64> {
    DMatrix::from_fn(n, n, |i, j| y[i + j + first])
}

/// The core's ERA at the walkthrough's order on its Hankel size.
fn era(s: &Setup, measured: &[f64]) -> Result<ModelReport, WalkthroughError> {
    let n = s.hankel;
    let limits = Limits {
        max_samples: measured.len(),
        max_outputs: 1,
        max_inputs: 1,
        max_order: s.order,
        max_block_rows: n,
        max_block_cols: n,
        max_pulses: 1,
    };
    let mut ws = Workspace::new(&limits).map_err(WalkthroughError::Core)?;
    let markov = MarkovSeq::from_data(1, 1, measured.to_vec()).map_err(WalkthroughError::Core)?;
    let opts = IdentOptions {
        order: Some(s.order),
        svd: SvdChoice::Dense,
        hankel_blocks: Some((n, n)),
        jackknife: false,
        ..IdentOptions::default()
    };
    ws.identify_markov(&markov, s.dt_s, &opts)
        .map_err(WalkthroughError::Era)?;
    Ok(ws.to_report())
}

/// Responses of the reported `(A, B, C, D)` (single input, first output).
fn responses_report(r: &ModelReport, len: usize) -> Result<Responses, WalkthroughError> {
    let n = r.order;
    let bad = || WalkthroughError::InconsistentReport;
    if r.a.len() != n || r.b.len() != n || r.c.is_empty() || r.d.is_empty() {
        return Err(bad());
    }
    let a = DMatrix::from_fn(n, n, |i, j| r.a[i].get(j).copied().unwrap_or(f64::NAN));
    let b = DVector::from_fn(n, |i, _| r.b[i].first().copied().unwrap_or(f64::NAN));
    let c = DVector::from_fn(n, |j, _| r.c[0].get(j).copied().unwrap_or(f64::NAN));
    let d = r.d[0].first().copied().ok_or_else(bad)?;
    let mut out = responses_ss(&a, &b, &c, len);
    out.impulse[0] += d;
    out.step = cumulative(&out.impulse);
    Ok(out)
}
