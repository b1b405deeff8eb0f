//! The one set of thresholds of the segmentation (see [`super`] for the rules they serve).

/// Every threshold that decides where the levels, steps, ramps and pulses of a command are.
///
/// [`SegmentRules::DEFAULT`] is for a *logged* command: the value a stand applied, repeated
/// exactly while it holds a level. Callers change a field only for a reason they can name: the
/// daemon's CSV link passes its configured `identify.level_tolerance` and
/// `csv.max_pulse_samples` (a bench's throttle column, [`SegmentRules::CSV_BENCH`] by default),
/// the identification core its `IdentOptions::max_pulse_width`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentRules {
    /// Two command values at most this far apart are the same level (command units: a
    /// throttle fraction 0..1, or the input's own unit). `1e-9`: a logged command repeats its
    /// value exactly, so this only absorbs decimal-to-binary rounding of a text log (TSP/1
    /// carries throttle in steps of `1e-4`, a CSV log with a few decimals), while any real
    /// change of the command (the smallest is one TSP/1 step) is a change.
    pub level_tolerance: f64,
    /// Longest pulse, samples: a run of at most this many samples between two samples at the
    /// same level is a pulse; a longer run is a level. `32`: the stand's pulses are one to a
    /// few samples wide, a level lasts far longer than the response settles (hundreds of
    /// samples), and a ramp's steps between levels hold each value for fewer samples than this.
    pub max_pulse_samples: usize,
    /// Piecewise constant: at most this fraction of the samples start a new run. `0.5`: a
    /// staircase with pulses and ramps changes on a few percent of its samples, random, chirp
    /// and multisine inputs on nearly all.
    pub max_change_fraction: f64,
    /// Ramped staircase: at least this fraction of the samples lie in levels (runs longer than
    /// [`max_pulse_samples`](Self::max_pulse_samples)). `0.5`: flat levels joined by ramps
    /// still hold most of the record; random, chirp and multisine inputs have no such runs.
    pub min_level_fraction: f64,
    /// Ramp: the command follows time with a Pearson correlation `|r|` above this. `0.9`.
    pub ramp_min_correlation: f64,
    /// Ramp: fewest measured samples to call anything a ramp. `8`.
    pub ramp_min_samples: usize,
    /// A ramp is cut into this many windows of equal length, one operating point each. `4`.
    pub ramp_windows: usize,
    /// A step between two holds may pass through this many samples between the two levels
    /// (each strictly between them, in order): a logged command resampled onto a uniform grid
    /// by interpolation, or an ESC that slews over a sample or two. `3`.
    pub max_step_transition_samples: usize,
    /// Steps found from the response when the command was not logged.
    pub response: ResponseStepRules,
}

/// Longest pulse in time, s ([`SegmentRules::at_rate`]): a third of a second. A
/// motor–propeller settles within 0.1–0.3 s (time constants of 20–100 ms), so a command held
/// longer is a level the response settles on, not a pulse, whatever the log's rate.
pub const MAX_PULSE_S: f64 = 1.0 / 3.0;

/// Thresholds of the steps found from a response alone (the method is documented where it
/// runs: the application's `ingest::steps`). `σ` is the noise of the smoothed response, `R`
/// its 1st-to-99th percentile range, `thr = max(noise_sigmas·σ, range_fraction·R)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResponseStepRules {
    /// Running median first, samples (odd): removes spikes. `3`.
    pub median_samples: usize,
    /// Centred moving mean after the median, samples (even, so ripple at the Nyquist frequency
    /// cancels exactly). `6`.
    pub smooth_samples: usize,
    /// Samples that must stay within `settle_fraction·thr` for a level to count as settled.
    /// `10`; a record needs twice this many measured samples.
    pub settle_samples: usize,
    /// Detection threshold in noise standard deviations. `6`: no false step in noise.
    pub noise_sigmas: f64,
    /// Detection threshold as a fraction of the range `R`. `0.05`: a noiseless record still
    /// needs a change of 5 % of its range.
    pub range_fraction: f64,
    /// Onset: walk back while the response is more than this many `σ` from the level. `3`.
    pub onset_sigmas: f64,
    /// Onset: … or more than this fraction of `thr`. `0.25`.
    pub onset_fraction: f64,
    /// Settled: the smoothed range of a window is below this fraction of `thr`. `0.5`.
    pub settle_fraction: f64,
}

impl SegmentRules {
    /// The rules for a logged command (see the field docs for each value and why).
    pub const DEFAULT: SegmentRules = SegmentRules {
        level_tolerance: 1e-9,
        max_pulse_samples: 32,
        max_change_fraction: 0.5,
        min_level_fraction: 0.5,
        ramp_min_correlation: 0.9,
        ramp_min_samples: 8,
        ramp_windows: 4,
        max_step_transition_samples: 3,
        response: ResponseStepRules::DEFAULT,
    };

    /// The daemon's defaults for a CSV bench's throttle column (its config keys
    /// `identify.level_tolerance` and `csv.max_pulse_samples`; the other fields as
    /// [`DEFAULT`](Self::DEFAULT)): `0.005`, half a percent of throttle, because a bench's
    /// column is rounded text and may wobble by a step while the plan's pulses are several
    /// percent; `64` samples, the daemon's long-standing limit (it decides live, sample by
    /// sample, so a pulse held a little longer at a fast bench rate is still a pulse).
    pub const CSV_BENCH: SegmentRules = SegmentRules {
        level_tolerance: 0.005,
        max_pulse_samples: 64,
        ..SegmentRules::DEFAULT
    };

    /// These rules for a record sampled every `dt_s` seconds: a pulse also lasts at most
    /// [`MAX_PULSE_S`] (`n` samples last `n·dt_s`), so that a slow log's levels are levels. At
    /// 100 Hz and faster `max_pulse_samples` (32) is the shorter and nothing changes; a 10 Hz
    /// bench log holding each level 3 s (30 samples) had no level at all under 32 samples, and
    /// so no steps, no static map and no operating points. A sample longer than a pulse (a
    /// stand's table of steady averages, one row per command) makes every run a level
    /// (`max_pulse_samples` 0). A `dt_s` that is not a finite positive number leaves the rules
    /// as they are.
    pub fn at_rate(self, dt_s: f64) -> SegmentRules {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return self;
        }
        // A hair over the quotient, so that 1/30 s samples give 10, not 9.
        let in_time = (MAX_PULSE_S / dt_s * (1.0 + 1e-9)).floor();
        let in_time = if in_time < self.max_pulse_samples as f64 {
            in_time as usize
        } else {
            self.max_pulse_samples
        };
        SegmentRules {
            max_pulse_samples: in_time,
            ..self
        }
    }

    /// The rules for a record sampled every `dt_s` whose input is a stand's command
    /// (`command`: [`at_rate`](Self::at_rate), the motor–propeller's time scale) or a signal
    /// in its own units (the defaults, by the sample count alone: a benchmark's pump voltage
    /// drives a plant that may settle over minutes). The one choice identify, diagnose and the
    /// real-data table make.
    pub fn for_record(dt_s: f64, command: bool) -> SegmentRules {
        match command {
            true => SegmentRules::DEFAULT.at_rate(dt_s),
            false => SegmentRules::DEFAULT,
        }
    }

    /// True when a single sample outlasts a pulse (`max_pulse_samples` 0: rules
    /// [`at_rate`](Self::at_rate) of a record sampled more slowly than [`MAX_PULSE_S`]): every
    /// sample of a held command is a steady state, and the response to a step is complete by
    /// the next sample, so a step shows no dynamics.
    pub fn samples_are_steady(&self) -> bool {
        self.max_pulse_samples == 0
    }

    /// Whether `a` and `b` are the same level: `|a − b| ≤ level_tolerance` (false when either
    /// is NaN).
    pub fn same(&self, a: f64, b: f64) -> bool {
        (a - b).abs() <= self.level_tolerance
    }
}

impl Default for SegmentRules {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl ResponseStepRules {
    /// The values documented on each field.
    pub const DEFAULT: ResponseStepRules = ResponseStepRules {
        median_samples: 3,
        smooth_samples: 6,
        settle_samples: 10,
        noise_sigmas: 6.0,
        range_fraction: 0.05,
        onset_sigmas: 3.0,
        onset_fraction: 0.25,
        settle_fraction: 0.5,
    };
}

impl Default for ResponseStepRules {
    fn default() -> Self {
        Self::DEFAULT
    }
}
