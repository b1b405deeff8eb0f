//! The published model: an allocating, serde-serialisable summary of one identification.
//!
//! The field names are a public interface (`propid identify --json`, the daemon's `"model"`
//! lines, `propid diagnose`): do not rename them. Non-finite numbers are written as `null`.

use serde::{Deserialize, Serialize};

use super::nullable;

/// A gain (or its uncertainty) for `q` outputs and `p` inputs: a number when `q = p = 1`, a list
/// over outputs when `p = 1`, otherwise a `q × p` row-major nested list.
#[derive(Debug, Clone, PartialEq)]
pub enum Gain {
    /// One output, one input.
    Scalar(f64),
    /// Several outputs, one input.
    List(Vec<f64>),
    /// Several inputs: `q` rows of `p`.
    Matrix(Vec<Vec<f64>>),
}

impl Gain {
    /// Builds the shape from a column-major `q × p` block.
    pub fn from_block(block: &[f64], q: usize, p: usize) -> Self {
        if q == 1 && p == 1 {
            Gain::Scalar(block[0])
        } else if p == 1 {
            Gain::List(block[..q].to_vec())
        } else {
            Gain::Matrix(
                (0..q)
                    .map(|i| (0..p).map(|j| block[i + j * q]).collect())
                    .collect(),
            )
        }
    }

    /// The gain from input 0 to output `i` (NaN when absent).
    pub fn get(&self, i: usize) -> f64 {
        match self {
            Gain::Scalar(g) if i == 0 => *g,
            Gain::Scalar(_) => f64::NAN,
            Gain::List(v) => v.get(i).copied().unwrap_or(f64::NAN),
            Gain::Matrix(m) => m
                .get(i)
                .and_then(|r| r.first())
                .copied()
                .unwrap_or(f64::NAN),
        }
    }
}

impl Serialize for Gain {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Gain::Scalar(g) => nullable::num::serialize(g, s),
            Gain::List(v) => nullable::vec::serialize(v, s),
            Gain::Matrix(m) => nullable::mat::serialize(m, s),
        }
    }
}

impl<'de> Deserialize<'de> for Gain {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Scalar(Option<f64>),
            List(Vec<Option<f64>>),
            Matrix(Vec<Vec<Option<f64>>>),
        }
        let nan = |x: Option<f64>| x.unwrap_or(f64::NAN);
        Ok(match Raw::deserialize(d)? {
            Raw::Scalar(x) => Gain::Scalar(nan(x)),
            Raw::List(v) => Gain::List(v.into_iter().map(nan).collect()),
            Raw::Matrix(m) => Gain::Matrix(
                m.into_iter()
                    .map(|r| r.into_iter().map(nan).collect())
                    .collect(),
            ),
        })
    }
}

/// Accuracy indicators of one mode (one pole; a complex pair appears twice with equal values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeIndicators {
    /// Mode singular value (Juang 1994): the mode's share of the Hankel matrix.
    #[serde(with = "nullable::num")]
    pub msv: f64,
    /// Modal amplitude coherence (Juang & Pappa 1985), 0..1.
    #[serde(with = "nullable::num")]
    pub mac: f64,
    /// Extended modal amplitude coherence from the SVD factors (Pappa et al. 1993), 0..1.
    #[serde(with = "nullable::num")]
    pub emac: f64,
    /// Modal phase collinearity, Pappa's form without mean-centring, 0..1.
    #[serde(with = "nullable::num")]
    pub mpc: f64,
    /// Consistent-mode indicator, `emac * mpc`.
    #[serde(with = "nullable::num")]
    pub cmi: f64,
}

/// Standard deviations from the jackknife over pulses (null when fewer than two pulses).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Uncertainty {
    /// Std of `fn_hz`.
    #[serde(with = "nullable::num")]
    pub fn_hz: f64,
    /// Std of `zeta`.
    #[serde(with = "nullable::num")]
    pub zeta: f64,
    /// Std of `dc_gain`, same shape as `dc_gain`.
    pub dc_gain: Gain,
}

/// Mass–spring–damper equivalent `m ÿ + d ẏ + k y = u` of the 2nd-order model from input 0 to
/// output 0, with the input in throttle units: `k = 1/dc_gain`, `m = k/ωn²`, `d = 2 ζ ωn m`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MassSpringDamper {
    /// Equivalent mass (throttle · s² per output unit).
    #[serde(with = "nullable::num")]
    pub m: f64,
    /// Equivalent damping (throttle · s per output unit).
    #[serde(with = "nullable::num")]
    pub d: f64,
    /// Equivalent stiffness (throttle per output unit).
    #[serde(with = "nullable::num")]
    pub k: f64,
}

/// One identified model, as published.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelReport {
    /// Model order `n`.
    pub order: usize,
    /// Sample period, seconds.
    #[serde(with = "nullable::num")]
    pub dt_s: f64,
    /// Natural frequency of the (dominant) 2nd-order mode, Hz.
    #[serde(with = "nullable::num")]
    pub fn_hz: f64,
    /// Damping ratio of that mode (> 1 for two real poles).
    #[serde(with = "nullable::num")]
    pub zeta: f64,
    /// `D + C (I − A)^-1 B`, output units per unit throttle.
    pub dc_gain: Gain,
    /// `−1/s` of every real stable pole, seconds, descending.
    #[serde(with = "nullable::vec")]
    pub time_constants_s: Vec<f64>,
    /// Continuous poles `s = ln(z)/dt`, `[re, im]`, rad/s.
    #[serde(with = "nullable::pairs")]
    pub poles_s: Vec<[f64; 2]>,
    /// Discrete poles `z`, `[re, im]`.
    #[serde(with = "nullable::pairs")]
    pub poles_z: Vec<[f64; 2]>,
    /// `A`, row-major.
    #[serde(with = "nullable::mat")]
    pub a: Vec<Vec<f64>>,
    /// `B`, row-major.
    #[serde(with = "nullable::mat")]
    pub b: Vec<Vec<f64>>,
    /// `C`, row-major.
    #[serde(with = "nullable::mat")]
    pub c: Vec<Vec<f64>>,
    /// `D`, row-major.
    #[serde(with = "nullable::mat")]
    pub d: Vec<Vec<f64>>,
    /// Leading singular values of `H(0)`, descending (all the SVD knows).
    #[serde(with = "nullable::vec")]
    pub singular_values: Vec<f64>,
    /// Accuracy indicators, one entry per pole in `poles_z` order.
    pub indicators: Vec<ModeIndicators>,
    /// Jackknife standard deviations.
    pub uncertainty: Uncertainty,
    /// Pulses averaged (0 for a model from given Markov parameters).
    pub pulses: usize,
    /// Pulses found but left out (missing samples, short window).
    pub pulses_skipped: usize,
    /// Samples marked missing in the samples the model was identified from (a record, a
    /// daemon window); they are left out, never interpolated (pulse path: the average per lag
    /// over the pulses measured there; OKID: their regression rows are left out). Absent in
    /// JSON written before it existed: 0.
    #[serde(default)]
    pub missing_samples: usize,
    /// Output noise RMS estimated from the pre-pulse baselines (output units; for given
    /// Markov parameters: the RMS of the sequence's noise tail; on the OKID path of
    /// `identify_any`: the one-step residual RMS of the OKID regression).
    #[serde(with = "nullable::num")]
    pub noise_rms: f64,
    /// Mass–spring–damper equivalent.
    pub mass_spring_damper: MassSpringDamper,
    /// Block rows `r` of the Hankel matrix used.
    pub hankel_block_rows: usize,
    /// Block columns `c` of the Hankel matrix used.
    pub hankel_block_cols: usize,
    /// SVD path taken: "dense" or "truncated".
    pub svd: String,
    /// The count of singular values above the noise when the automatic order stepped down
    /// from it to `order`, the largest whose poles all settle
    /// ([`crate::order::model_order::settled_order`]); absent when it did not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order_stepped_down_from: Option<usize>,
}
