//! The identification core's own 2nd-order model of the estimation part (ERA on pulse-averaged
//! Markov parameters for a clean pulse experiment, OKID + ERA otherwise:
//! [`propid_numerics::identify::identify_any`]). It is what `propid identify` and the daemon
//! publish; `diagnose` reports its validation fit beside the baseline and uses it as one more
//! starting point of the baseline's output-error fit, and `diagnose --report` draws the
//! stabilization diagram of its Hankel SVD ([`propid_numerics::stabilization`]).

use serde::Serialize;

use super::ctx::Ctx;
use super::model::{simulate, Model};
use super::signals::Core;
use propid_numerics::identify::{identify_any_with, AnyError, AnyInput, PathTaken};
use propid_numerics::okid::OkidOptions;
use propid_numerics::order::HankelSize;
use propid_numerics::stabilization::{StabOptions, Stabilization};
use propid_numerics::{IdentOptions, ModelReport};

/// The core's model and how well it predicts the validation part.
#[derive(Debug, Clone, Serialize)]
pub struct EraBaseline {
    /// `"pulse"` or `"okid"`.
    pub path: PathTaken,
    /// Natural frequency, Hz.
    pub fn_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// DC gain, output units per unit throttle.
    pub dc_gain: f64,
    /// Validation fit of its simulation (offset by least squares on the estimation part), %.
    pub fit_percent: f64,
}

/// Why the core's model is not a start for the baseline.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoreRefusal {
    /// The identification core (ERA on pulse averages, or OKID + ERA) refused the estimation
    /// part.
    #[error("the identification core refused the estimation part")]
    Refused(#[from] AnyError),
    /// The core returned a model that is not a 2nd-order low-pass with a finite gain.
    #[error("the identification core's model (fn {fn_hz} Hz, zeta {zeta}, gain {gain}) is not a usable start")]
    Unusable {
        /// Natural frequency, Hz.
        fn_hz: f64,
        /// Damping ratio.
        zeta: f64,
        /// DC gain.
        gain: f64,
    },
}

/// The core's order-2 model of the estimation part.
#[derive(Debug, Clone)]
pub struct EraStart {
    /// `fn`, `ζ`, `K` as the output-error model's core (offset 0).
    pub core: Core,
    /// Which path the core took.
    pub path: PathTaken,
    /// The core's published model (what `propid identify --json` prints for this data).
    pub report: ModelReport,
    /// The stabilization diagram of the core's Hankel SVD (for the report).
    pub stabilization: Option<Stabilization>,
}

/// Runs the core on the estimation part with order 2; an error when it refuses the data or its
/// model is not usable as a start.
pub fn era_start(ctx: &Ctx) -> Result<EraStart, CoreRefusal> {
    let est = ctx.est.clone();
    let u = &ctx.sig.u[est.clone()];
    let y = &ctx.sig.y[est];
    let missing: Vec<bool> = y.iter().map(|v| !v.is_finite()).collect();
    let us = [u];
    let ys = [y];
    let input = AnyInput {
        dt_s: ctx.sig.dt_s,
        u: &us,
        y: &ys,
        missing: &missing,
        pulse_starts: None,
    };
    let opts = IdentOptions {
        order: Some(2),
        jackknife: false,
        max_pulse_width: ctx.rules.max_pulse_samples,
        ..IdentOptions::default()
    };
    let (okid, stab) = (OkidOptions::default(), StabOptions::default());
    let m = identify_any_with(&input, &opts, &okid, HankelSize::Auto, Some(&stab))?;
    let r = &m.report;
    let k = r.dc_gain.get(0);
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if !(ok(r.fn_hz) && ok(r.zeta) && k.is_finite()) {
        return Err(CoreRefusal::Unusable {
            fn_hz: r.fn_hz,
            zeta: r.zeta,
            gain: k,
        });
    }
    let core = Core {
        fn_hz: r.fn_hz,
        zeta: r.zeta,
        gain: k,
        ..Core::default()
    };
    Ok(EraStart {
        core,
        path: m.path,
        report: m.report,
        stabilization: m.stabilization,
    })
}

/// The core's model with only the output offset fitted (least squares on the estimation part).
pub fn with_offset(ctx: &Ctx, core: &Core) -> Core {
    let mut q = *core;
    let mut buf = vec![0.0; ctx.sig.u.len()];
    simulate(&Model::new(q), &ctx.sig, &mut buf);
    let (mut s, mut n) = (0.0, 0usize);
    for k in ctx.est.clone() {
        let e = ctx.sig.y[k] - buf[k];
        if e.is_finite() {
            s += e;
            n += 1;
        }
    }
    q.offset = if n > 0 { s / n as f64 } else { 0.0 };
    q
}

/// The published summary of the core's model given its validation fit.
pub fn summary(core: &Core, path: PathTaken, fit_percent: f64) -> EraBaseline {
    EraBaseline {
        path,
        fn_hz: core.fn_hz,
        zeta: core.zeta,
        dc_gain: core.gain,
        fit_percent,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signals::Signals;

    #[test]
    fn a_refusal_of_the_core_is_a_typed_cause() {
        let u: Vec<f64> = (0..400)
            .map(|k| if k % 40 < 3 { 0.6 } else { 0.5 })
            .collect();
        let y = vec![f64::NAN; 400];
        let ctx = Ctx {
            sig: Signals {
                dt_s: 0.01,
                u: &u,
                y: &y,
                voltage: None,
                u_ref: 0.5,
                v_ref: 0.0,
            },
            est: 0..280,
            val: 280..400,
            rules: propid_numerics::segment::SegmentRules::DEFAULT,
            gate: Default::default(),
        };
        let e = era_start(&ctx).unwrap_err();
        assert!(matches!(e, CoreRefusal::Refused(_)), "{e:?}");
        assert!(std::error::Error::source(&e).is_some());
    }
}
