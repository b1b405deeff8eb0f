//! The identification core: from pulse experiments (or given Markov parameters) to a
//! discrete-time state-space model, its modal summary, accuracy indicators and uncertainty.
//! No I/O; every identification through a [`workspace::Workspace`] is allocation-free.
//!
//! Pipeline (Juang & Pappa 1985, "An Eigensystem Realization Algorithm for Modal Parameter
//! Identification and Model Reduction", J. Guidance 8(5), 620–627):
//!
//! 1. [`pulses`]: segment throttle pulses, reference each to its own pre-pulse baseline, scale
//!    by amplitude, ensemble-average, undo the pulse width → Markov parameters [`markov`]
//!    (`Y_0 = D`, `Y_k = C A^(k-1) B`, response to a unit input held for one sample; no `1/dt`).
//! 2. [`grouped`]: what ERA actually runs on for pulse records: the averaged responses per
//!    pulse width, whose tails are Markov sequences of the same `(A, C)` with input matrix
//!    `B̃_w = Σ_{i<w} A^i B` (identical to `Y` for one-sample pulses; no deconvolution noise
//!    for wider ones). `B` then follows by least squares, `D = P_0`.
//! 3. [`order`]: noise floor, Hankel size (near-square, up to where the response sinks into
//!    the noise), order from the singular values against the noise floor.
//! 4. [`era`] on [`hankel`] + [`svd`]: `H(0) = U Σ Vᵀ` (block (a, b) of `H(s)` is
//!    `Y_{a+b+1+s}`), `A = Σ^-½ Uᵀ H(1) V Σ^-½`, `B` = first p columns of `Σ^½ Vᵀ`, `C` =
//!    first q rows of `U Σ^½`, `D = Y_0`.
//! 5. [`okid`]: Markov parameters from any other excitation (Juang, Phan, Horta & Longman
//!    1993); [`identify`] chooses the pulse path or OKID + ERA for a record.
//! 6. [`modal`], [`indicators`], [`uncertainty`]: poles, fn, ζ, DC gain, m-d-k; MSV, MAC,
//!    EMAC, MPC, CMI; jackknife over pulses.
//! 7. [`workspace`] runs it all on preallocated buffers ([`model::Model`] holds the result);
//!    [`report`] is the published, serde-serialisable [`report::ModelReport`].
//! 8. [`stabilization`]: the stabilization diagram, the poles of every order `1..n_max`
//!    realised from the model's own Hankel SVD, stable ones marked.
//! 9. [`stand_model`]: the physical model of a motor–propeller stand (ESC dead time, rotor lag
//!    per direction and speed, loads ∝ speedᵉ, supply sag, a sensor per channel), the simulated
//!    stand's equations and their joint fit ([`levenberg_marquardt`]) to a record's channels.
//!
//! Measured accuracy with noise and timings: `docs/core.md`.

// Index loops mirror the formulas (A[i][l] x[l]) in this numerical code; iterator chains over
// several matrices at once would hide them.
#![allow(clippy::needless_range_loop)]

pub mod discretise;
pub mod effect_name;
pub mod eig;
pub mod era;
pub mod error;
pub mod frequency_response;
pub mod grouped;
pub mod hankel;
pub mod identify;
pub mod indicators;
pub mod levenberg_marquardt;
pub mod linalg;
pub mod markov;
pub mod modal;
pub mod model;
pub mod nonlinear_core;
pub mod nullable;
pub mod okid;
pub mod operating_points;
pub mod order;
pub mod outliers;
pub mod output_error;
pub mod pulses;
pub mod quality;
pub mod report;
pub mod segment;
pub mod stabilization;
pub mod stand;
pub mod stand_model;
pub mod startup;
pub mod statespace;
pub mod static_map;
pub mod step_directions;
pub mod step_response;
pub mod svd;
pub mod uncertainty;
pub mod workspace;

pub use effect_name::EffectName;
pub use error::IdentError;
pub use markov::MarkovSeq;
pub use model::Model;
pub use pulses::PulseInput;
pub use report::ModelReport;
pub use statespace::StateSpace;
pub use svd::{SvdChoice, SvdError};
pub use workspace::{IdentOptions, Limits, Workspace};
