//! The identification core's own 2nd-order model of the estimation part (ERA on pulse-averaged
//! Markov parameters for a clean pulse experiment, OKID + ERA otherwise:
//! [`propid_numerics::okid::select::identify_any`]). It is what `propid identify` and the daemon
//! publish; `diagnose` reports its validation fit beside the baseline and uses it as one more
//! starting point of the baseline's output-error fit.

use serde::Serialize;

use super::ctx::Ctx;
use super::model::{simulate, Core, Model};
use propid_numerics::okid::select::{identify_any, AnyInput, PathTaken};
use propid_numerics::okid::OkidOptions;
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

/// The core's order-2 model of the estimation part.
#[derive(Debug, Clone)]
pub struct EraStart {
    /// `fn`, `ζ`, `K` as the output-error model's core (offset 0).
    pub core: Core,
    /// Which path the core took.
    pub path: PathTaken,
    /// The core's published model (what `propid identify --json` prints for this data).
    pub report: ModelReport,
}

/// Runs the core on the estimation part with order 2; `None` when it refuses the data.
pub fn era_start(ctx: &Ctx) -> Option<EraStart> {
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
        ..IdentOptions::default()
    };
    let m = identify_any(&input, &opts, &OkidOptions::default()).ok()?;
    let r = &m.report;
    let k = r.dc_gain.get(0);
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if !(ok(r.fn_hz) && ok(r.zeta) && k.is_finite()) {
        return None;
    }
    let core = Core {
        fn_hz: r.fn_hz,
        zeta: r.zeta,
        gain: k,
        ..Core::default()
    };
    Some(EraStart {
        core,
        path: m.path,
        report: m.report,
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
