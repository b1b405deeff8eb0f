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

/// True when `u` is a ramped staircase with pulses up to `max_pulse_width` samples wide
/// ([`crate::segment::is_ramped_staircase`]).
pub fn is_ramped_staircase(u: &[f64], max_pulse_width: usize) -> bool {
    let rules = crate::segment::SegmentRules {
        max_pulse_samples: max_pulse_width,
        ..crate::segment::SegmentRules::DEFAULT
    };
    crate::segment::is_ramped_staircase(crate::segment::Command::new(u), &rules)
}

/// True when `u` is piecewise constant ([`crate::segment::is_piecewise_constant`]).
pub fn is_piecewise_constant(u: &[f64]) -> bool {
    crate::segment::is_piecewise_constant(
        crate::segment::Command::new(u),
        &crate::segment::SegmentRules::DEFAULT,
    )
}
