//! Input checks before a build: sample period, channel count and lengths, limits, finite
//! values (missing samples excepted), and no constant output.

use super::{missing, PulseInput};
use crate::IdentError;

pub(super) fn validate(
    input: &PulseInput<'_>,
    max_samples: usize,
    max_outputs: usize,
) -> Result<(), IdentError> {
    let n = input.u.len();
    if !(input.dt_s.is_finite() && input.dt_s > 0.0) {
        return Err(IdentError::InvalidInput("dt_s must be finite and > 0"));
    }
    if input.y.is_empty() {
        return Err(IdentError::InvalidInput(
            "at least one output channel is needed",
        ));
    }
    if input.y.len() > max_outputs {
        return Err(IdentError::LimitsExceeded {
            what: "outputs",
            value: input.y.len(),
            limit: max_outputs,
        });
    }
    if n > max_samples {
        return Err(IdentError::LimitsExceeded {
            what: "samples",
            value: n,
            limit: max_samples,
        });
    }
    if input.y.iter().any(|c| c.len() != n)
        || !(input.missing.is_empty() || input.missing.len() == n)
    {
        return Err(IdentError::InvalidInput(
            "input, outputs and missing mask must have the same length",
        ));
    }
    for k in 0..n {
        if !missing(input, k) && !input.u[k].is_finite() {
            return Err(IdentError::NonFinite {
                signal: "input",
                channel: 0,
                sample: k,
            });
        }
    }
    for (c, ch) in input.y.iter().enumerate() {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, v) in ch.iter().enumerate() {
            if missing(input, k) {
                continue;
            }
            if !v.is_finite() {
                return Err(IdentError::NonFinite {
                    signal: "output",
                    channel: c,
                    sample: k,
                });
            }
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        if hi <= lo {
            return Err(IdentError::ConstantOutput { channel: c });
        }
    }
    Ok(())
}
