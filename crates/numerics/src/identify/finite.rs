//! A model with non-finite parts is refused, never published.

use super::AnyError;
use crate::report::Gain;
use crate::ModelReport;

/// OKID regression condition above which an order-2 model without a pole pair (`fn_hz` NaN) is
/// refused rather than published: a short or poorly exciting record (the audit's 119 samples
/// gave 4.5e15).
pub const ILL_CONDITIONED: f64 = 1e12;

/// Refuses a model with non-finite matrices, poles or DC gain, or (order 2, from an OKID
/// regression whose condition exceeds [`ILL_CONDITIONED`]) non-finite `fn_hz`/`zeta`: a short
/// or poorly exciting record can produce one without any step failing. An order-2 model of a
/// first-order plant from well-conditioned data legitimately has no pole pair (`fn_hz` null).
pub fn check_finite(r: &ModelReport, condition: Option<f64>) -> Result<(), AnyError> {
    let bad = |m: &[Vec<f64>]| m.iter().flatten().any(|v| !v.is_finite());
    let gain_bad = match &r.dc_gain {
        Gain::Scalar(g) => !g.is_finite(),
        Gain::List(v) => v.iter().any(|g| !g.is_finite()),
        Gain::Matrix(m) => bad(m),
    };
    let what = if bad(&r.a) || bad(&r.b) || bad(&r.c) || bad(&r.d) {
        "state-space matrices"
    } else if r.poles_z.iter().flatten().any(|v| !v.is_finite()) {
        "poles"
    } else if r.order == 2
        && !(r.fn_hz.is_finite() && r.zeta.is_finite())
        && condition.is_some_and(|c| c.is_nan() || c > ILL_CONDITIONED)
    {
        "fn_hz/zeta"
    } else if gain_bad {
        "dc_gain"
    } else {
        return Ok(());
    };
    Err(AnyError::NonFiniteModel { what, condition })
}
