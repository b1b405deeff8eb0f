//! How many samples a window holds: enough for the experiment plan's windows at the fastest
//! rate a stand runs, so that no window fills before its K pulses (at 20 kHz the 16 384
//! samples of `max_window_samples` hold 3.3 pulse spacings of 250 ms, and every window was
//! discarded with `window_full`).
//!
//! A window opens when the operating point is reached (after the ramp), waits `settle_ms`,
//! then holds K pulses spaced `pulse_spacing_ms` apart and is identified at the start of pulse
//! K + 1 (a later window starts with the second half of the last response instead of the
//! settling). It therefore holds at most
//!
//! $$ N = (t_\text{settle} + (K + 1)\, t_\text{spacing})\; f_\text{max} $$
//!
//! samples, one spacing of margin included, at the fastest rate [`PLAN_RATE_HZ`]; the
//! buffers (window, workspace, the jackknife helper's copy) are allocated once at start-up
//! for the larger of `N` (at most [`PLAN_MAX_SAMPLES`]) and `identify.max_window_samples`.
//! Every pulse response the window holds is whole: the window still identifies only at the
//! next pulse start or the level's end.

use crate::daemon::config::Config;
use propid_wire::experiment::ExperimentConfig;

/// The fastest sample rate the windows are sized for, Hz (the simulated stand's highest).
pub const PLAN_RATE_HZ: u64 = 20_000;

/// Most samples a window is sized to from the plan (2¹⁸: 13 s at 20 kHz); a larger
/// `identify.max_window_samples` is taken as given.
pub const PLAN_MAX_SAMPLES: usize = 1 << 18;

/// Samples the plan's windows need at `rate_hz` (0 for a plan that does not parse: the
/// plan's own check reports it).
pub fn plan_samples(plan: &ExperimentConfig, pulses_per_model: u32, rate_hz: u64) -> usize {
    let ms = u64::from(plan.settle_ms)
        + (u64::from(pulses_per_model) + 1) * u64::from(plan.pulse_spacing_ms);
    let samples = ms.saturating_mul(rate_hz) / 1000;
    usize::try_from(samples).unwrap_or(usize::MAX)
}

/// The window capacity for `cfg`: `identify.max_window_samples`, or more when the
/// experiment plan needs it at [`PLAN_RATE_HZ`] (up to [`PLAN_MAX_SAMPLES`]).
pub fn window_capacity(cfg: &Config) -> usize {
    let plan: Option<ExperimentConfig> = cfg.experiment.clone().try_into().ok();
    let need = plan.map_or(0, |p| {
        plan_samples(&p, cfg.identify.pulses_per_model, PLAN_RATE_HZ).min(PLAN_MAX_SAMPLES)
    });
    cfg.identify.max_window_samples.max(need)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_plan_fits_at_20_khz() {
        let cfg = Config::default();
        let plan = ExperimentConfig::default();
        // settle 500 ms, K = 4 pulses 250 ms apart, one spacing of margin
        assert_eq!(plan_samples(&plan, 4, 20_000), 35_000);
        assert_eq!(plan_samples(&plan, 4, 1_000), 1_750);
        assert_eq!(window_capacity(&cfg), 35_000);
        // what a window at 20 kHz holds when identified: settling + K spacings
        let held = (500 + 4 * 250) * 20;
        assert!(window_capacity(&cfg) >= held);
    }

    #[test]
    fn a_larger_configured_window_is_kept_and_huge_plans_are_capped() {
        let mut cfg = Config::default();
        cfg.identify.max_window_samples = 500_000;
        assert_eq!(window_capacity(&cfg), 500_000);
        cfg.identify.max_window_samples = 16_384;
        cfg.identify.pulses_per_model = 1000;
        assert_eq!(window_capacity(&cfg), PLAN_MAX_SAMPLES);
        // an unparsable plan: the configured size
        cfg.experiment = toml::from_str("levels = \"x\"").unwrap();
        assert_eq!(window_capacity(&cfg), 16_384);
    }
}
