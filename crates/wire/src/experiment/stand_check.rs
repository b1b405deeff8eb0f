//! What the samples have shown of the commands so far ([`StandCheck`]), and the bounds the
//! plan holds them to (`verify.rs`: a stand that lies).

/// How far (throttle fraction) the applied throttle may lie outside the commanded envelope:
/// the device's quantisation and an ESC's rounding, far below any pulse amplitude the plan uses
/// (0.001..0.5; the defaults 0.05, 0.1).
pub const THROTTLE_TOLERANCE: f64 = 0.02;

/// How long (host clock, ms) the applied throttle may stay outside the envelope: a sample or
/// two read late around a command's boundary, a ramp's last step, never a runaway motor for
/// long.
pub const THROTTLE_MISMATCH_MS: u64 = 200;

/// Acknowledged pulses in a row without a sign in the samples before the stand is said not to
/// execute them.
pub const PULSES_UNSEEN_LIMIT: u32 = 3;

/// Samples that must have arrived since a pulse before its spacing's end judges it (a stand
/// sampled too slowly for the spacing says nothing either way).
pub const MIN_SAMPLES_TO_JUDGE: u32 = 2;

/// What the samples have shown of the commands so far.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct StandCheck {
    /// Since when (host µs) the applied throttle is outside the envelope.
    pub(super) off_since: Option<u64>,
    /// A sample showed the current operating point (off pulse, within the tolerance).
    pub(super) level_seen: bool,
    /// A sign of the last pulse fired arrived (IMPULSE_ACTIVE, EVENT IMPULSE_START).
    pub(super) pulse_shown: bool,
    /// Samples since the last pulse fired.
    pub(super) samples_since_pulse: u32,
    /// Pulses in a row that showed no sign.
    pub(super) unseen_pulses: u32,
}

impl StandCheck {
    /// A new operating point is commanded.
    pub(super) fn new_level(&mut self) {
        *self = StandCheck::default();
    }

    /// A pulse was fired (acknowledged, or its EVENT IMPULSE_START came).
    pub(super) fn pulse_fired(&mut self) {
        self.samples_since_pulse = 0;
    }
}
