//! ERA on preallocated buffers, step by step: Hankel size and SVD path ([`crate::order`]),
//! `H(0) = U Σ Vᵀ`, the order, the realisation ([`crate::era`]) and the modal analysis
//! ([`Model`]).

use super::{IdentOptions, Limits, C64};
use crate::era::Era;
use crate::grouped::{input_matrix, InputScratch, MAX_GROUPS};
use crate::hankel::HankelDims;
use crate::model::Model;
use crate::order::hankel_size::{self, Span};
use crate::order::model_order;
use crate::statespace::AbcdMut;
use crate::svd::SvdPath;
use crate::{IdentError, MarkovSeq};

/// ERA's buffers ([`Era`]), the noise floor, the jackknife's estimates and the model (split
/// from the Markov storage of the workspace for borrowing).
#[derive(Debug)]
pub(super) struct Engine {
    pub(super) limits: Limits,
    pub(super) era: Era,
    /// Markov-parameter noise per output ([`crate::order::noise_floor`]).
    pub(super) noise: Vec<f64>,
    pub(super) lite: Lite,
    pub(super) theta_fn: Vec<f64>,
    pub(super) theta_zeta: Vec<f64>,
    pub(super) theta_dc: Vec<f64>,
    pub(super) model: Model,
}

/// A bare `(A, B, C, D)` with pole, input-matrix and DC-gain scratch, for jackknife
/// re-identifications.
#[derive(Debug, Clone)]
pub(super) struct Lite {
    pub(super) a: Vec<f64>,
    pub(super) b: Vec<f64>,
    pub(super) c: Vec<f64>,
    pub(super) d: Vec<f64>,
    pub(super) m: Vec<f64>,
    pub(super) s: Vec<f64>,
    pub(super) nrm: Vec<f64>,
    pub(super) b1: Vec<f64>,
    pub(super) x: Vec<f64>,
    pub(super) poles: Vec<C64>,
    pub(super) dc: Vec<f64>,
}

impl Engine {
    pub(super) fn new(l: &Limits) -> Self {
        let pmax = max_p(l);
        let max = HankelDims {
            q: l.max_outputs,
            p: pmax,
            r: l.max_block_rows,
            c: l.max_block_cols,
        };
        let wide = max.rows().min(max.cols());
        let n = l.max_order;
        Self {
            limits: *l,
            era: Era::new(max, n),
            noise: vec![0.0; l.max_outputs],
            lite: Lite {
                a: vec![0.0; n * n],
                b: vec![0.0; n * pmax],
                c: vec![0.0; l.max_outputs * n],
                d: vec![0.0; l.max_outputs * pmax],
                m: vec![0.0; n * n],
                s: vec![0.0; n * n],
                nrm: vec![0.0; n * n],
                b1: vec![0.0; n],
                x: vec![0.0; n * pmax],
                poles: vec![C64::new(0.0, 0.0); n],
                dc: vec![0.0; l.max_outputs * pmax],
            },
            theta_fn: vec![0.0; l.max_pulses],
            theta_zeta: vec![0.0; l.max_pulses],
            theta_dc: vec![0.0; l.max_pulses * l.max_outputs],
            model: Model::new(n, l.max_outputs, pmax, wide),
        }
    }

    /// Order checks, Hankel size and SVD path of `markov` (the first part of `run`); `pulse`
    /// stretches the automatic Hankel span past the noise crossing ([`Span::PulseTail`]).
    pub(super) fn plan(
        &self,
        markov: &MarkovSeq,
        growth: &[f64],
        pulse: bool,
        opts: &IdentOptions,
    ) -> Result<(HankelDims, SvdPath), IdentError> {
        let l = self.limits;
        let (q, p, len) = (markov.outputs(), markov.inputs(), markov.len());
        if let Some(n) = opts.order {
            if n == 0 {
                return Err(IdentError::InvalidInput("order must be >= 1"));
            }
            if n > l.max_order {
                return Err(IdentError::LimitsExceeded {
                    what: "order",
                    value: n,
                    limit: l.max_order,
                });
            }
        }
        let max = (l.max_block_rows, l.max_block_cols);
        let dims = match opts.hankel_blocks {
            Some(rc) => hankel_size::explicit_dims(q, p, rc, len.saturating_sub(1), max.0, max.1)?,
            None => {
                let span = if pulse {
                    Span::PulseTail
                } else {
                    Span::AboveNoise
                };
                hankel_size::auto_dims(markov, &self.noise[..q], growth, span, opts.order, max)?
            }
        };
        let wide = dims.rows().min(dims.cols());
        if let Some(n) = opts.order {
            if n > wide {
                return Err(IdentError::OrderTooHigh {
                    order: n,
                    max: wide,
                });
            }
        }
        let path = self.era.path(opts.svd, &dims)?;
        Ok((dims, path))
    }

    /// Sizing ([`plan`](Self::plan)), SVD, order, realisation and modal analysis of `markov`.
    pub(super) fn run(
        &mut self,
        markov: &MarkovSeq,
        dt_s: f64,
        growth: &[f64],
        pulse: bool,
        opts: &IdentOptions,
    ) -> Result<(), IdentError> {
        let l = self.limits;
        let (q, p) = (markov.outputs(), markov.inputs());
        let (dims, path) = self.plan(markov, growth, pulse, opts)?;
        let k = self.era.kmax().min(dims.rows().min(dims.cols()));
        let m = &mut self.model;
        let need = opts.order.unwrap_or(1);
        let svd = self
            .era
            .decompose(markov, dims, path, (k, need), &mut m.sigma)?;
        m.n_sigma = svd.n_sigma;
        let sig = &m.sigma[..m.n_sigma];
        let cap = l.max_order.min(k);
        // `growth` (the per-lag noise of missing samples) sizes the Hankel matrix only: the
        // noise stays white, and its singular-value bound is the white one (the Frobenius
        // bound of `noise_singular_value` is for the deconvolution's random walk).
        let n = model_order::choose(sig, &self.noise[..q], &dims, &[], opts.order, cap)?;
        if n > svd.converged {
            // The automatic order reached past the triplets that had converged: ask for them.
            self.era
                .decompose(markov, dims, path, (k, n), &mut m.sigma)?;
        }
        m.n = n;
        m.q = q;
        m.p = p;
        m.dt_s = dt_s;
        m.dims = dims;
        m.path = path;
        m.std_fn = f64::NAN;
        m.std_zeta = f64::NAN;
        m.std_dc.fill(f64::NAN);
        m.stepped_down_from = None;
        if opts.order.is_some() && !opts.order_is_a_ceiling {
            return self.realize_order(markov, n);
        }
        let settled = model_order::settled_order(n, |k| {
            self.realize_order(markov, k)?;
            Ok::<bool, IdentError>(self.model.poles_settle())
        })?;
        if settled < n {
            self.model.stepped_down_from = Some(n);
        }
        Ok(())
    }

    /// Realises order `n` from the SVD of the last [`run`](Self::run) and analyses its modes.
    fn realize_order(&mut self, markov: &MarkovSeq, n: usize) -> Result<(), IdentError> {
        let m = &mut self.model;
        m.n = n;
        let out = AbcdMut {
            a: &mut m.a,
            b: &mut m.b,
            c: &mut m.c,
            d: &mut m.d,
        };
        self.era
            .realize(markov, m.dims, (n, m.path), &m.sigma, out)?;
        m.analyse_modes(self.era.u(), self.era.v())
    }

    /// Converts the realised per-width input matrices `B̃_g` into the single input `B` and
    /// sets `D` ([`crate::grouped`]).
    pub(super) fn single_input(
        &mut self,
        widths: &[usize],
        weights: &[f64],
        d: &[f64],
    ) -> Result<(), IdentError> {
        let m = &mut self.model;
        let n = m.n;
        let lt = &mut self.lite;
        let scratch = InputScratch {
            s: &mut lt.m,
            t: &mut lt.s,
            nrm: &mut lt.nrm,
        };
        if !input_matrix(&m.a, n, &m.b, (widths, weights), scratch, &mut lt.b1) {
            return Err(IdentError::InvalidInput(
                "the pulse widths cannot excite a pole of the model: B is not identifiable",
            ));
        }
        m.set_single_input(&lt.b1, d);
        Ok(())
    }
}

/// Most input columns the engine handles: the inputs of given Markov parameters, or one
/// column per pulse width on the pulse path.
pub(super) fn max_p(l: &Limits) -> usize {
    l.max_inputs.max(MAX_GROUPS)
}
