//! How big a model: the noise floor, the Hankel size and the model order, with one named set
//! of thresholds ([`THRESHOLDS`]). Three separate questions, one file each, in the order ERA
//! asks them:
//!
//! 1. [`noise_floor`]: how large is the noise of the Markov parameters `σ_i` (per output), and
//!    up to which index does the response stand above it?
//! 2. [`hankel_size`]: how many block rows `r` and columns `c` the Hankel matrix `H(0)` gets
//!    (near-square over the above-noise length), or how an explicit or square size is checked.
//! 3. [`model_order`]: how many singular values of `H(0)` carry signal: those above the
//!    random-matrix noise level `NOISE_SV_FACTOR · σ (√rows + √cols)` and rounding.
//!
//! OKID adds a fourth count, [`observer`]: the number `ℓ` of observer Markov parameters of its
//! regression, chosen by simulation error (a regression order, not the model order).
//!
//! The pulse path ([`crate::workspace::Workspace::identify`]), given Markov parameters
//! ([`crate::workspace::Workspace::identify_markov`]) and the OKID path
//! ([`crate::identify::identify_okid`]) all use these rules; they differ only in where `σ`
//! comes from (pre-pulse baselines, the sequence's tail, OKID split halves or regression) and
//! in how far the Hankel span reaches past the noise crossing ([`hankel_size::Span`]).

pub mod hankel_size;
pub mod model_order;
pub mod noise_floor;
pub mod observer;

pub use hankel_size::HankelSize;

/// Every threshold of the size and order rules, named (one set: [`THRESHOLDS`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// Moving window (samples) of the above-noise test ([`noise_floor::signal_length`]).
    pub window: usize,
    /// Mean of `(Y_k/σ)²` over the window above which the response counts as signal: 4, i.e.
    /// RMS above 2σ (a false alarm needs a ~6σ excursion of the windowed mean).
    pub above_noise_energy: f64,
    /// On the pulse path the Hankel matrix spans this multiple of the above-noise length
    /// ([`noise_floor::pulse_span`]).
    pub tail_factor: usize,
    /// Relative floor (of the peak) replacing a zero noise estimate.
    pub relative_floor: f64,
    /// Least Markov blocks the OKID path's Hankel spans, however early the sequence sinks
    /// into its noise floor.
    pub okid_min_span: usize,
    /// Least scalar rows and columns of `H(0)` when the order is chosen automatically (a
    /// given order `n` needs `n + 1`).
    pub min_hankel_size: usize,
    /// Margin on the random-matrix noise singular value `σ(√m + √n)`.
    pub noise_sv_factor: f64,
    /// Singular values below this fraction of `σ_1` are rounding.
    pub rank_tol: f64,
    /// Candidate numbers `ℓ` of observer Markov parameters ([`observer`]).
    pub observer_candidates: [usize; 16],
    /// Relative tolerance for ties of the observer-order score (a smaller `ℓ` within 2 % of
    /// the best wins).
    pub observer_tie: f64,
}

/// The thresholds in use.
pub const THRESHOLDS: Thresholds = Thresholds {
    window: 8,
    above_noise_energy: 4.0,
    tail_factor: 2,
    relative_floor: 1e-8,
    okid_min_span: 8,
    min_hankel_size: 3,
    noise_sv_factor: 1.5,
    rank_tol: 1e-9,
    observer_candidates: [1, 2, 3, 4, 5, 6, 8, 10, 12, 14, 16, 20, 24, 28, 32, 40],
    observer_tie: 0.02,
};
