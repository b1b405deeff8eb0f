//! Does a record look like a pulse experiment? (the pulse path is tried first when it does)

use super::AnyInput;

/// True when the pulse path should be tried first: the record has device pulse starts
/// (EVENT IMPULSE_START), or its input is piecewise constant, or it is a ramped staircase
/// ([`is_ramped_staircase`]). The pulse path itself decides whether there are pulses
/// ([`crate::IdentError::NoPulse`] falls back to OKID); ramps between levels do not disqualify it,
/// because every pulse window ends at the next level change and each pulse is referenced to
/// its own pre-pulse baseline ([`crate::pulses`]).
pub fn looks_like_pulses(input: &AnyInput<'_>, max_pulse_width: usize) -> bool {
    let Some(u) = input.u.first() else {
        return false;
    };
    input.pulse_starts.is_some_and(|s| !s.is_empty())
        || is_piecewise_constant(u)
        || is_ramped_staircase(u, max_pulse_width)
}

/// True when at least half of the samples of `u` lie in runs of constant value longer than
/// `max_pulse_width` samples: flat levels joined by ramps (or steps), possibly with pulses on
/// them. Random, chirp and multisine inputs have no such runs.
pub fn is_ramped_staircase(u: &[f64], max_pulse_width: usize) -> bool {
    let mut flat = 0;
    let mut start = 0;
    for k in 1..=u.len() {
        if k == u.len() || !(u[k] - u[start]).abs().le(&1e-9) {
            if k - start > max_pulse_width {
                flat += k - start;
            }
            start = k;
        }
    }
    flat * 2 >= u.len() && !u.is_empty()
}

/// True when `u` changes (by more than 1e-9) on at most half of its samples.
pub fn is_piecewise_constant(u: &[f64]) -> bool {
    let changes = u
        .windows(2)
        .filter(|w| w[0].is_finite() && w[1].is_finite() && (w[1] - w[0]).abs() > 1e-9)
        .count();
    changes * 2 <= u.len()
}
