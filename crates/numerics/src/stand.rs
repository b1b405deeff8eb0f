//! What a propulsion engineer reads off a stand record first, before any model: the figures of
//! every command step ([`crate::step_response`]) and the static map of every output
//! ([`crate::static_map`]), found with the one segmentation ([`crate::segment`]).
//!
//! - A record with clean steps (a staircase, a random-step sequence, steps up and down) gives
//!   one [`StepFigures`] per step, for the identified output, and the static map over its holds.
//! - A ramp gives no step; its static map is read over [`crate::segment::ramp_windows`]
//!   windows, each at its mean command and mean output (quasi-static: a ramp slow against the
//!   plant's time constants, which the record cannot check by itself).
//! - Anything else (pulses on one level, random or multisine input) gives neither.
//! - A record without its command, whose steps were found from the response (a load cell
//!   logged alone while a servo tester stepped the ESC): [`response_step_figures`] gives each
//!   step's time constant, rise, settling and overshoot, timed from when the response starts to
//!   move; no dead time (the command's time is not in the record), no command levels, no map.
//! - A record whose every sample outlasts the response (rules at a rate slower than a third of
//!   a second: [`SegmentRules::samples_are_steady`], a stand's table of steady averages) gives
//!   its static map and its steps without figures ([`SAMPLES_ARE_STEADY`]).

use std::collections::BTreeMap;

use serde::Serialize;

use crate::segment::{self, Command, SegmentRules};
use crate::static_map::{
    falls_with_command, fit_expo, fit_power_law, fit_thrust_coefficient, levels, repeats, shifted,
    window_levels, zero_offset, Expo, Level, PowerLaw, Repeat, ThrustCoefficient, ZeroOffset,
};
use crate::step_response::{step_figures, StepFigures};

/// One output channel of the record.
#[derive(Debug, Clone, Copy)]
pub struct OutputChannel<'a> {
    /// Key in the static map (`thrust`, `torque`, `rpm`, `current`).
    pub key: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// Samples (NaN = not measured).
    pub y: &'a [f64],
}

/// The static map of one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticMap {
    /// The output's unit.
    pub unit: &'static str,
    /// Steady level per held command.
    pub levels: Vec<Level>,
    /// `T = k·max(u − u0, 0)^exponent` (`null` with fewer than 3 levels), `T` the output
    /// above `zero_offset` when there is one.
    pub power: Option<PowerLaw>,
    /// `T/t_max = (1 − a)·x + a·x²` (`null` with fewer than 2 levels), `T` as for `power`.
    pub expo: Option<Expo>,
    /// The output's reading at zero command when the levels show one
    /// ([`crate::static_map::offset`]: a load cell not tared, an ESC's idle current): `power`,
    /// `expo` and `k_t` describe the output above it. Omitted when none is taken.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zero_offset: Option<ZeroOffset>,
    /// Thrust only, when the record has rotor speed too: `T = k_t·ω²`, ω in rad/s (`T`
    /// above the thrust's `zero_offset`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_t: Option<ThrustCoefficient>,
    /// The output falls as the command rises ([`falls_with_command`]: a load cell mounted
    /// reversed, a pusher): `power` and `expo` fit its magnitude, their `k` and `t_max`
    /// negative. Omitted when it rises.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub falls_with_command: bool,
    /// The commands held more than once, the mean of each visit and the last minus the first
    /// ([`repeats`]); omitted when none is.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub repeats: Vec<Repeat>,
}

/// Step figures and static maps of a record.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct StandFigures {
    /// `"steps"`, `"ramp"` or `"none"`: what the command was read as; `"response"` for steps
    /// found from the response ([`response_step_figures`]).
    pub command: &'static str,
    /// One per clean step, for the first output.
    pub steps: Vec<StepFigures>,
    /// Per output key.
    pub static_map: BTreeMap<&'static str, StaticMap>,
}

/// The note of a step whose samples are each a steady state ([`SegmentRules::samples_are_steady`]).
pub const SAMPLES_ARE_STEADY: &str =
    "a sample lasts longer than the response takes to settle: the step shows no dynamics";

/// Where the steady levels are read: over holds, or over a ramp's windows.
enum Over {
    Holds(Vec<segment::Run>),
    Windows(Vec<segment::Level>),
}

impl Over {
    fn levels(&self, y: &[f64]) -> Vec<Level> {
        match self {
            Over::Holds(h) => levels(y, h),
            Over::Windows(w) => window_levels(y, w),
        }
    }
}

/// Where the steady levels of `cmd` are read (see the module doc): `("steps", holds)`,
/// `("ramp", windows)`, or `None`.
fn over(
    cmd: Command<'_>,
    rules: &SegmentRules,
    steps: &[segment::Step],
) -> Option<(&'static str, Over)> {
    let holds: Vec<segment::Run> = segment::holds(cmd, rules).collect();
    if !steps.is_empty() || (holds.len() >= 2 && segment::is_piecewise_constant(cmd, rules)) {
        Some(("steps", Over::Holds(holds)))
    } else if segment::is_ramp(cmd, rules) {
        Some(("ramp", Over::Windows(segment::ramp_windows(cmd, rules))))
    } else {
        None
    }
}

/// The steady levels of output `y` under command `cmd`, read as [`stand_figures`] reads its
/// static maps (over the holds of steps, or a ramp's windows; empty for any other command):
/// what [`crate::quality::judge_gain`] holds a model's DC gain against.
pub fn steady_levels(cmd: Command<'_>, rules: &SegmentRules, y: &[f64]) -> Vec<Level> {
    let steps = segment::steps(cmd, rules);
    over(cmd, rules, &steps).map_or_else(Vec::new, |(_, o)| o.levels(y))
}

/// The figures of a record with command `cmd` sampled every `dt_s` (see the module doc): step
/// figures of `step_output` (the identified output), static maps of `outputs`.
pub fn stand_figures(
    cmd: Command<'_>,
    dt_s: f64,
    rules: &SegmentRules,
    step_output: &[f64],
    outputs: &[OutputChannel<'_>],
) -> StandFigures {
    let steps = segment::steps(cmd, rules);
    let Some((command, over)) = over(cmd, rules, &steps) else {
        return StandFigures {
            command: "none",
            ..StandFigures::default()
        };
    };
    let step_figs = figures_at(&steps, step_output, dt_s, rules);
    let mut maps: BTreeMap<&'static str, StaticMap> = outputs
        .iter()
        .map(|o| {
            let lv = over.levels(o.y);
            // Held commands only (a ramp's windows: `repeats`' module doc).
            let rep = match over {
                Over::Holds(_) => repeats(&lv, rules),
                Over::Windows(_) => Vec::new(),
            };
            (o.key, static_map(o.unit, lv, rep))
        })
        .collect();
    add_thrust_coefficient(&mut maps);
    StandFigures {
        command,
        steps: step_figs,
        static_map: maps,
    }
}

/// The static map of one output's steady levels `lv` (in `unit`), with the commands held more
/// than once `rep`: its zero offset, and the power law and expo of the output above it.
pub fn static_map(unit: &'static str, lv: Vec<Level>, rep: Vec<Repeat>) -> StaticMap {
    let zero = zero_offset(&lv);
    let above = shifted(&lv, zero.map_or(0.0, |z| z.value));
    StaticMap {
        unit,
        power: fit_power_law(&above),
        expo: fit_expo(&above),
        zero_offset: zero,
        falls_with_command: falls_with_command(&lv),
        repeats: rep,
        levels: lv,
        k_t: None,
    }
}

/// `k_t` of the `thrust` map from the `rpm` map's levels (`T = k_t·ω²`, [`StaticMap::k_t`])
/// when both have the same levels.
pub fn add_thrust_coefficient(maps: &mut BTreeMap<&'static str, StaticMap>) {
    if let (Some(rpm), Some(thrust)) = (maps.get("rpm").cloned(), maps.get_mut("thrust")) {
        let omega: Vec<Level> = rpm
            .levels
            .iter()
            .map(|l| Level {
                mean: l.mean * std::f64::consts::TAU / 60.0,
                std: l.std * std::f64::consts::TAU / 60.0,
                ..*l
            })
            .collect();
        if rpm.levels.len() == thrust.levels.len() {
            let above = shifted(&thrust.levels, thrust.zero_offset.map_or(0.0, |z| z.value));
            thrust.k_t = fit_thrust_coefficient(&above, &omega);
        }
    }
}

/// The step table `identify` prints (`steps` of `identify --json`): the figures of `y` at every
/// clean step of `cmd` ([`segment::steps`], [`step_figures`]), unsupported when a sample lasts
/// longer than the response takes to settle ([`SAMPLES_ARE_STEADY`]). The one place a step is
/// timed: `diagnose` reads from it whether a dead time can be seen, so that the two commands
/// cannot disagree on it.
pub fn step_table(
    cmd: Command<'_>,
    dt_s: f64,
    rules: &SegmentRules,
    y: &[f64],
) -> Vec<StepFigures> {
    figures_at(&segment::steps(cmd, rules), y, dt_s, rules)
}

/// The figures of `y` at `steps` ([`step_table`]).
fn figures_at(
    steps: &[segment::Step],
    y: &[f64],
    dt_s: f64,
    rules: &SegmentRules,
) -> Vec<StepFigures> {
    steps
        .iter()
        .map(|s| {
            let f = step_figures(y, dt_s, s);
            if rules.samples_are_steady() {
                f.unsupported(SAMPLES_ARE_STEADY)
            } else {
                f
            }
        })
        .collect()
}

/// One step's timing on one channel: its dead time and time constant (the figures of
/// [`step_figures`] on that channel's samples).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ChannelTiming {
    /// Dead time θ, s.
    pub dead_time_s: Option<f64>,
    /// Time constant τ, s.
    pub time_constant_s: Option<f64>,
}

/// The timing of every clean step of `cmd` on every channel of `outputs` (one map per step,
/// by channel key, in the order of [`stand_figures`]' steps): the rotor's and the load
/// cell's timing side by side. Empty when the command has no step.
pub fn channel_step_timing(
    cmd: Command<'_>,
    dt_s: f64,
    rules: &SegmentRules,
    outputs: &[OutputChannel<'_>],
) -> Vec<BTreeMap<&'static str, ChannelTiming>> {
    if rules.samples_are_steady() {
        return Vec::new();
    }
    segment::steps(cmd, rules)
        .iter()
        .map(|s| {
            outputs
                .iter()
                .map(|o| {
                    let f = step_figures(o.y, dt_s, s);
                    let timing = ChannelTiming {
                        dead_time_s: f.dead_time_s,
                        time_constant_s: f.time_constant_s,
                    };
                    (o.key, timing)
                })
                .collect()
        })
        .collect()
}

/// Why a step found from the response has no dead time and no command levels.
pub const NO_COMMAND: &str = "no command in the record: the step was found from the \
    response; timed from when it starts to move (no dead time), `from`/`to` unknown";

/// The figures of the steps of `y` found from the response alone, `levels` the input built
/// from them (the level sequence, output units: [`crate::segment::steps`] reads its steps as a
/// command's): each step's figures with `from`, `to` null (NaN), the direction the response's,
/// and no dead time ([`NO_COMMAND`]: the step is placed one sample before the response moves,
/// so any delay from the command is not in the record). The time constant (`1.5 (t₆₃ − t₂₈)`)
/// and the rise are differences of crossing times and need no command time; settling is
/// counted from the found step.
///
/// The finder places a step within a sample or two of the response's start, later on a sparse
/// or noisy response ([`crate::segment::ResponseStepRules`]); a response already past 28 % at
/// the step would lose its `t₂₈` (a time constant 26 % short on a load cell read every third
/// row). The figures are therefore taken from `smooth_samples` samples earlier (at most half
/// the level before, where the response still sits on it), and the settling time given back
/// that lead.
pub fn response_step_figures(
    levels: &[f64],
    dt_s: f64,
    rules: &SegmentRules,
    y: &[f64],
) -> Vec<StepFigures> {
    segment::steps(Command::new(levels), rules)
        .iter()
        .map(|s| {
            let lead = rules
                .response
                .smooth_samples
                .min(s.at.saturating_sub(s.before_start) / 2);
            let early = segment::Step {
                at: s.at - lead,
                ..*s
            };
            let f = step_figures(y, dt_s, &early);
            let lead_s = lead as f64 * dt_s;
            StepFigures {
                t_s: s.at as f64 * dt_s,
                from: f64::NAN,
                to: f64::NAN,
                dead_time_s: None,
                dead_time_below_sample: false,
                settling_90_s: f.settling_90_s.map(|t| (t - lead_s).max(0.0)),
                note: f.note.or(Some(NO_COMMAND)),
                ..f
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A staircase 0.2 → 0.4 → 0.6 → 0.8 → 0.5 at 100 Hz into a first-order thrust with a
    /// quadratic static map and 20 ms dead time; rpm linear in the command.
    fn staircase() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let dt = 0.01;
        let u: Vec<f64> = [0.2, 0.4, 0.6, 0.8, 0.5]
            .iter()
            .flat_map(|&v| std::iter::repeat(v).take(200))
            .collect();
        let (tau, delay) = (0.05f64, 2);
        let mut t = vec![0.0; u.len()];
        let mut x = 10.0 * 0.2f64.powi(2);
        for k in 0..u.len() {
            let target = 10.0 * u[k.saturating_sub(delay)].powi(2);
            x += (target - x) * (1.0 - (-dt / tau).exp());
            t[k] = x;
        }
        let rpm: Vec<f64> = t
            .iter()
            .map(|v| (v / 2e-5).sqrt() * 60.0 / std::f64::consts::TAU)
            .collect();
        (u, t, rpm)
    }

    #[test]
    fn a_staircase_gives_its_steps_and_its_quadratic_map() {
        let (u, t, rpm) = staircase();
        let f = stand_figures(
            Command::new(&u),
            0.01,
            &SegmentRules::DEFAULT,
            &t,
            &[
                OutputChannel {
                    key: "thrust",
                    unit: "N",
                    y: &t,
                },
                OutputChannel {
                    key: "rpm",
                    unit: "rev/min",
                    y: &rpm,
                },
            ],
        );
        assert_eq!(f.command, "steps");
        assert_eq!(f.steps.len(), 4);
        for s in &f.steps {
            assert!((s.time_constant_s.unwrap() - 0.05).abs() < 0.01, "{s:?}");
            assert!((s.dead_time_s.unwrap() - 0.02).abs() <= 0.011, "{s:?}");
        }
        let thrust = &f.static_map["thrust"];
        assert_eq!(thrust.levels.len(), 5);
        for l in &thrust.levels {
            assert!(
                (l.mean - 10.0 * l.throttle * l.throttle).abs() < 1e-3,
                "{l:?}"
            );
        }
        let p = thrust.power.unwrap();
        assert!(
            (p.exponent - 2.0).abs() < 1e-3 && p.u0.abs() < 1e-3,
            "{p:?}"
        );
        let e = thrust.expo.unwrap();
        assert!(
            (e.a - 1.0).abs() < 1e-3 && (e.t_max - 10.0).abs() < 1e-2,
            "{e:?}"
        );
        assert!((thrust.k_t.unwrap().k_t - 2e-5).abs() < 1e-9);
        assert!(f.static_map["rpm"].k_t.is_none());
    }

    #[test]
    fn steps_found_from_the_response_give_their_time_constants_and_no_dead_time() {
        let (_, t, _) = staircase();
        // The level sequence a finder builds: each hold's final thrust, switching one sample
        // before the response moves (the 2-sample delay after each command step at 200·i).
        let levels: Vec<f64> = (0..t.len())
            .map(|k| {
                let hold = ((k + 1).saturating_sub(2) / 200).min(4);
                t[200 * hold + 199]
            })
            .collect();
        let f = response_step_figures(&levels, 0.01, &SegmentRules::DEFAULT, &t);
        assert_eq!(f.len(), 4);
        for s in &f {
            assert!((s.time_constant_s.unwrap() - 0.05).abs() < 0.01, "{s:?}");
            assert!(
                s.rise_10_90_s.is_some() && s.overshoot_pct.is_some(),
                "{s:?}"
            );
            assert_eq!(s.dead_time_s, None);
            assert!(s.from.is_nan() && s.to.is_nan());
            assert_eq!(s.note, Some(NO_COMMAND));
        }
        assert_eq!(f[3].direction, crate::step_response::Direction::Down);
    }

    #[test]
    fn a_ramp_has_a_map_and_no_steps_and_noise_has_neither() {
        let u: Vec<f64> = (0..1000).map(|k| 0.1 + 0.8 * k as f64 / 1000.0).collect();
        let y: Vec<f64> = u.iter().map(|v| 5.0 * v * v).collect();
        let out = [OutputChannel {
            key: "thrust",
            unit: "N",
            y: &y,
        }];
        let f = stand_figures(Command::new(&u), 0.01, &SegmentRules::DEFAULT, &y, &out);
        assert_eq!(f.command, "ramp");
        assert!(f.steps.is_empty());
        assert_eq!(
            f.static_map["thrust"].levels.len(),
            SegmentRules::DEFAULT.ramp_windows
        );
        let r: Vec<f64> = (0..1000)
            .map(|k| ((k * 7919) % 1000) as f64 / 1000.0)
            .collect();
        let f = stand_figures(Command::new(&r), 0.01, &SegmentRules::DEFAULT, &y, &out);
        assert_eq!(f.command, "none");
        assert!(f.static_map.is_empty());
    }

    #[test]
    fn a_table_of_steady_averages_has_its_map_and_steps_without_figures() {
        // A row every 5 s, each a steady thrust (T = 12·u²), the output lagging a sample.
        let u = [0.15, 0.2, 0.25, 0.3, 0.35, 0.4];
        let y: Vec<f64> = u.iter().map(|v| 12.0 * v * v).collect();
        let out = [OutputChannel {
            key: "thrust",
            unit: "N",
            y: &y,
        }];
        let steady = SegmentRules::DEFAULT.at_rate(5.0);
        let f = stand_figures(Command::new(&u), 5.0, &steady, &y, &out);
        assert_eq!(f.static_map["thrust"].levels.len(), u.len());
        assert_eq!(f.steps.len(), u.len() - 1);
        for s in &f.steps {
            assert_eq!((s.dead_time_s, s.time_constant_s), (None, None), "{s:?}");
            assert_eq!(s.rise_10_90_s, None);
            assert_eq!(s.note, Some(SAMPLES_ARE_STEADY));
        }
    }
}
