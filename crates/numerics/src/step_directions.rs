//! The step figures by direction: spin-up and spin-down, side by side, as a propulsion
//! engineer compares them first (a motor driven up and coasting or braked down answers
//! differently; `diagnose`'s `asymmetric_dynamics` is the model of it).
//!
//! For each direction that has steps ([`crate::step_response::Direction`]), the median of each
//! figure over the steps that have it ([`crate::step_response::StepFigures`]: dead time, time
//! constant, 10–90 % rise, settling, overshoot), the upper of the two middle values for an even
//! count (a figure every step of the median carries, never an average of two). A dead time's
//! median that is a bound (`< dt`) stays one (`dead_time_below_sample`), and so does an
//! overshoot's within the noise (`overshoot_below_pct`). Steps the response's
//! change does not support count in `steps`, not in the medians.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::step_response::{Direction, StepFigures};

/// The median figures of one direction's steps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DirectionFigures {
    /// Steps in this direction.
    pub steps: usize,
    /// Steps with a time constant (resolvable and supported).
    pub timed: usize,
    /// Median dead time, s.
    pub dead_time_s: Option<f64>,
    /// The median dead time is a bound below one sample period (omitted when false).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub dead_time_below_sample: bool,
    /// Median time constant, s.
    pub time_constant_s: Option<f64>,
    /// Median 10–90 % rise time, s.
    pub rise_10_90_s: Option<f64>,
    /// Median settling time, s.
    pub settling_90_s: Option<f64>,
    /// Median overshoot, percent of the step (`None` when the median step's overshoot is
    /// within its noise: `overshoot_below_pct`).
    pub overshoot_pct: Option<f64>,
    /// The median step's overshoot is within its noise: below this, percent (omitted when
    /// not).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overshoot_below_pct: Option<f64>,
}

/// The median of `v` (the upper middle for an even count), `None` when empty.
fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

/// The figures of `steps` by direction (`"up"`, `"down"`; a direction without steps is absent).
pub fn by_direction(steps: &[StepFigures]) -> BTreeMap<&'static str, DirectionFigures> {
    [(Direction::Up, "up"), (Direction::Down, "down")]
        .into_iter()
        .filter_map(|(dir, name)| {
            let of: Vec<&StepFigures> = steps.iter().filter(|s| s.direction == dir).collect();
            if of.is_empty() {
                return None;
            }
            let all = |f: fn(&StepFigures) -> Option<f64>| -> Vec<f64> {
                of.iter().filter_map(|s| f(s)).collect()
            };
            let mut dead: Vec<(f64, bool)> = of
                .iter()
                .filter_map(|s| s.dead_time_s.map(|d| (d, s.dead_time_below_sample)))
                .collect();
            dead.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mid = dead.get(dead.len() / 2).copied();
            let taus = all(|s| s.time_constant_s);
            // An overshoot within the noise counts by its bound, and a median that falls on a
            // bound stays one (as the dead time's).
            let mut over: Vec<(f64, bool)> = of
                .iter()
                .filter_map(|s| match (s.overshoot_pct, s.overshoot_below_pct) {
                    (Some(o), _) => Some((o, false)),
                    (None, Some(b)) => Some((b, true)),
                    (None, None) => None,
                })
                .collect();
            over.sort_by(|a, b| a.0.total_cmp(&b.0));
            let over_mid = over.get(over.len() / 2).copied();
            Some((
                name,
                DirectionFigures {
                    steps: of.len(),
                    timed: taus.len(),
                    dead_time_s: mid.map(|d| d.0),
                    dead_time_below_sample: mid.is_some_and(|d| d.1),
                    time_constant_s: median(taus),
                    rise_10_90_s: median(all(|s| s.rise_10_90_s)),
                    settling_90_s: median(all(|s| s.settling_90_s)),
                    overshoot_pct: over_mid.filter(|o| !o.1).map(|o| o.0),
                    overshoot_below_pct: over_mid.filter(|o| o.1).map(|o| o.0),
                },
            ))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(from: f64, to: f64, dead: Option<f64>, tau: Option<f64>) -> StepFigures {
        StepFigures {
            dead_time_s: dead,
            dead_time_below_sample: dead.is_some_and(|d| d < 0.01),
            time_constant_s: tau,
            resolvable: tau.is_some(),
            rise_10_90_s: tau.map(|t| 2.2 * t),
            settling_90_s: tau.map(|t| 2.3 * t),
            overshoot_pct: tau.map(|_| 0.0),
            ..StepFigures::blank(0.0, from, to)
        }
    }

    #[test]
    fn each_direction_has_the_medians_of_its_own_steps() {
        let steps = [
            step(0.2, 0.4, Some(0.02), Some(0.040)),
            step(0.4, 0.6, Some(0.03), Some(0.050)),
            step(0.6, 0.8, Some(0.02), Some(0.045)),
            step(0.8, 0.5, Some(0.004), Some(0.090)),
            step(0.5, 0.3, Some(0.005), Some(0.110)),
            step(0.3, 0.2, None, None), // within the noise
        ];
        let d = by_direction(&steps);
        let up = d["up"];
        assert_eq!((up.steps, up.timed), (3, 3));
        assert_eq!(up.time_constant_s, Some(0.045));
        assert_eq!(up.dead_time_s, Some(0.02));
        assert!(!up.dead_time_below_sample);
        let down = d["down"];
        assert_eq!((down.steps, down.timed), (3, 2));
        // Even count: the upper middle, a figure one step carries.
        assert_eq!(down.time_constant_s, Some(0.110));
        assert_eq!(down.dead_time_s, Some(0.005));
        assert!(down.dead_time_below_sample);
        assert!((down.rise_10_90_s.unwrap() - 0.242).abs() < 1e-12);
    }

    #[test]
    fn a_direction_without_steps_is_absent() {
        let d = by_direction(&[step(0.2, 0.4, None, Some(0.04))]);
        assert!(d.contains_key("up") && !d.contains_key("down"));
        assert!(by_direction(&[]).is_empty());
    }

    /// Overshoots within the noise count by their bounds: a median on a bound stays a bound,
    /// a median on a measured overshoot is a number.
    #[test]
    fn an_overshoot_median_on_a_bound_stays_a_bound() {
        let with = |o: Option<f64>, below: Option<f64>| StepFigures {
            overshoot_pct: o,
            overshoot_below_pct: below,
            ..step(0.2, 0.4, None, Some(0.04))
        };
        let d = by_direction(&[
            with(None, Some(6.0)),
            with(Some(2.0), None),
            with(None, Some(7.0)),
        ]);
        assert_eq!(d["up"].overshoot_pct, None);
        assert_eq!(d["up"].overshoot_below_pct, Some(6.0));
        let d = by_direction(&[
            with(Some(12.0), None),
            with(None, Some(5.0)),
            with(Some(15.0), None),
        ]);
        assert_eq!(d["up"].overshoot_pct, Some(12.0));
        assert_eq!(d["up"].overshoot_below_pct, None);
    }
}
