//! Safety limits (`[limits]`): what the stand's samples may never show, checked on every
//! sample, and the commanded throttle a plan may never leave.
//!
//! - **Per sample** ([`Limits::breach`]): current above `max_current_a`, thrust above
//!   `max_thrust_n`, rotor speed above `max_rpm`, supply voltage below `min_voltage_v`, the
//!   applied throttle above `max_throttle` (by more than the device's rounding,
//!   [`THROTTLE_TOLERANCE`]). A measurement counts when its VALID flag is set and it is a finite
//!   number. Values are SI: a TSP/1 SAMPLE carries newtons, and a CSV bench's columns are
//!   converted from their units (`Thrust (gf)`, `thrust_lbf`, …) by the wire's CSV decoder
//!   before a SAMPLE is made of them, so a limit in N holds whatever unit the bench writes. One
//!   sample over a limit is a breach: the plan ([`Experiment::set_limits`](super::Experiment::set_limits), `verify.rs`) is over at once
//!   ([`Notice::LimitTripped`](super::Notice::LimitTripped), a STOP sent; the daemon exits 8) and never re-arms, whatever
//!   `rearm_on_reset` says.
//! - **Unchecked** ([`LimitGuard`]): a limit on a quantity the stand never reports cannot hold.
//!   After the first [`JUDGE_SAMPLES`] samples each such limit is named once
//!   ([`Notice::LimitUnchecked`](super::Notice::LimitUnchecked)); it is still checked should the quantity appear later.
//!   `max_temperature_c` is always named: neither a TSP/1 SAMPLE nor a CSV row carries a
//!   temperature.
//! - **The plan** ([`Limits::refuse_plan`]): every throttle the plan commands
//!   ([`ExperimentConfig::commanded`]) must lie in `0..=max_throttle`; the first that does not is
//!   refused by its keys (`levels[i] + pulse_amplitudes[j]`) before anything is sent.

use serde::Deserialize;

use super::config::ExperimentConfig;
use super::stand_check::THROTTLE_TOLERANCE;
use crate::protocol::{Sample, SampleFlags};

/// `[limits]`: every key optional (absent = no limit). Units are in the names.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Limits {
    /// Most current, A (> 0).
    pub max_current_a: Option<f64>,
    /// Most thrust, N (> 0).
    pub max_thrust_n: Option<f64>,
    /// Most rotor speed, rev/min (> 0).
    pub max_rpm: Option<f64>,
    /// Least supply voltage, V (> 0).
    pub min_voltage_v: Option<f64>,
    /// Most temperature, °C (−50..=500); no stand reports one today (named at the start).
    pub max_temperature_c: Option<f64>,
    /// Most throttle, fraction in 0..=1: the plan may command no more, the stand apply no more.
    pub max_throttle: Option<f64>,
}

/// A refused `[limits]` table, or a plan that leaves its `max_throttle`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LimitsError {
    /// A limit that is not a number in its range.
    #[error("limits key `{key}` = {value}: {expected}")]
    OutOfRange {
        /// The key, e.g. `max_current_a`.
        key: &'static str,
        /// The value as read.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// A throttle the plan commands above `max_throttle`.
    #[error(
        "experiment `{key}` = {value} leaves 0..=max_throttle ({limit}): the plan is refused, \
         nothing is sent"
    )]
    PlanExceeds {
        /// The experiment keys that make it, e.g. `levels[1] + pulse_amplitudes[0]`.
        key: String,
        /// How it is made, e.g. `0.6 + 0.1 = 0.7`.
        value: String,
        /// `max_throttle`.
        limit: f64,
    },
}

/// A sample over a limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimitTrip {
    /// The limit's key (`max_current_a`, …).
    pub which: &'static str,
    /// What the sample showed (SI units, throttle as a fraction).
    pub value: f64,
    /// The limit.
    pub limit: f64,
}

/// Samples after which a limit on a quantity none of them carried is named
/// ([`Notice::LimitUnchecked`](super::Notice::LimitUnchecked)): 50 ms at 1 kHz, one second at 50 Hz.
pub const JUDGE_SAMPLES: u32 = 50;

/// A measured limit: key, limit, the SAMPLE flag of its quantity, a most (else a least), the
/// sample's value.
type Measured = (
    &'static str,
    Option<f64>,
    SampleFlags,
    bool,
    fn(&Sample) -> f32,
);

/// Is `v` above (`max`) or below (`!max`) `limit`?
fn over(v: f64, limit: f64, max: bool) -> bool {
    if max {
        v > limit
    } else {
        v < limit
    }
}

impl Limits {
    /// The measured limits: key, limit, the SAMPLE flag of its quantity, whether it is a
    /// most (else a least), and the sample's value.
    fn measured(&self) -> [Measured; 4] {
        [
            (
                "max_current_a",
                self.max_current_a,
                SampleFlags::CURRENT_VALID,
                true,
                |s| s.current_a,
            ),
            (
                "max_thrust_n",
                self.max_thrust_n,
                SampleFlags::THRUST_VALID,
                true,
                |s| s.thrust_n,
            ),
            ("max_rpm", self.max_rpm, SampleFlags::RPM_VALID, true, |s| {
                s.rpm
            }),
            (
                "min_voltage_v",
                self.min_voltage_v,
                SampleFlags::VOLTAGE_VALID,
                false,
                |s| s.voltage_v,
            ),
        ]
    }

    /// Refuses a limit that is not a finite number in its range, naming it.
    pub fn validate(&self) -> Result<(), LimitsError> {
        let checks: [(&'static str, Option<f64>, f64, f64, &'static str); 6] = [
            (
                "max_current_a",
                self.max_current_a,
                0.0,
                1e4,
                "0 < A <= 10000",
            ),
            (
                "max_thrust_n",
                self.max_thrust_n,
                0.0,
                1e5,
                "0 < N <= 100000",
            ),
            ("max_rpm", self.max_rpm, 0.0, 1e6, "0 < rev/min <= 1000000"),
            (
                "min_voltage_v",
                self.min_voltage_v,
                0.0,
                1e3,
                "0 < V <= 1000",
            ),
            (
                "max_temperature_c",
                self.max_temperature_c,
                -50.0,
                500.0,
                "-50 < °C <= 500",
            ),
            (
                "max_throttle",
                self.max_throttle,
                0.0,
                1.0,
                "a throttle fraction, 0 < x <= 1",
            ),
        ];
        for (key, v, lo, hi, expected) in checks {
            match v {
                Some(x) if !(x.is_finite() && x > lo && x <= hi) => {
                    return Err(LimitsError::OutOfRange {
                        key,
                        value: x,
                        expected,
                    })
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// True when no limit is set.
    pub fn is_empty(&self) -> bool {
        *self == Limits::default()
    }

    /// The first limit `s` breaches, if any (see the [module documentation](self)): current,
    /// thrust, rpm, voltage, then the applied throttle.
    pub fn breach(&self, s: &Sample) -> Option<LimitTrip> {
        for (which, limit, flag, max, get) in self.measured() {
            let Some(limit) = limit else { continue };
            let v = get(s) as f64;
            if s.flags.contains(flag) && v.is_finite() && over(v, limit, max) {
                return Some(LimitTrip {
                    which,
                    value: v,
                    limit,
                });
            }
        }
        let limit = self.max_throttle?;
        let u = s.throttle_fraction();
        (u > limit + THROTTLE_TOLERANCE).then_some(LimitTrip {
            which: "max_throttle",
            value: u,
            limit,
        })
    }

    /// The plan against `max_throttle`: the first throttle it commands above it is refused
    /// by its keys ([`LimitsError::PlanExceeds`]).
    pub fn refuse_plan(&self, plan: &ExperimentConfig) -> Result<(), LimitsError> {
        let Some(limit) = self.max_throttle else {
            return Ok(());
        };
        match plan
            .commanded()
            .into_iter()
            .find(|c| c.throttle > limit + 1e-9)
        {
            Some(c) => Err(LimitsError::PlanExceeds {
                key: c.key,
                value: c.value,
                limit,
            }),
            None => Ok(()),
        }
    }
}

/// The limits as the plan holds them: the breach of every sample, and, once, the limits the
/// stand's first [`JUDGE_SAMPLES`] samples could not be held against.
#[derive(Debug, Clone, Copy, Default)]
pub struct LimitGuard {
    limits: Limits,
    /// SAMPLE flags seen so far (OR).
    seen: u16,
    /// Samples seen, up to the judgement.
    samples: u32,
}

impl LimitGuard {
    /// A guard of `limits`.
    pub fn new(limits: Limits) -> LimitGuard {
        LimitGuard {
            limits,
            ..LimitGuard::default()
        }
    }

    /// The limits.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// One sample: its breach, if any; and, at the [`JUDGE_SAMPLES`]th sample, every limit
    /// none of the samples so far could be held against (key and why), handed to `unchecked`.
    pub fn sample(
        &mut self,
        s: &Sample,
        unchecked: &mut dyn FnMut(&'static str, &'static str),
    ) -> Option<LimitTrip> {
        if self.samples < JUDGE_SAMPLES {
            self.samples += 1;
            for (_, _, flag, _, get) in self.limits.measured() {
                if s.flags.contains(flag) && get(s).is_finite() {
                    self.seen |= flag.0;
                }
            }
            if self.samples == JUDGE_SAMPLES {
                for (which, limit, flag, _, _) in self.limits.measured() {
                    if limit.is_some() && self.seen & flag.0 == 0 {
                        unchecked(which, "the stand has not reported this quantity");
                    }
                }
                if self.limits.max_temperature_c.is_some() {
                    unchecked(
                        "max_temperature_c",
                        "no SAMPLE (nor CSV row) carries a temperature",
                    );
                }
            }
        }
        self.limits.breach(s)
    }
}

#[cfg(test)]
mod tests;
