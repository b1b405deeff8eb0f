//! What a record shows of the stand model ([`super::fit`]): each figure with its uncertainty
//! and the channel it came from, or `null` with the reason the data cannot show it
//! (`identify --json`'s `"stand"`).

use std::collections::BTreeMap;

use serde::Serialize;

use super::fit::{Estimate, StandFit, StandModelError};
use super::Quantity;

/// A figure whose standard deviation exceeds this many times its size is not reported (the
/// fit moved it freely: a single pulse does not show a rotor's lag apart from a 2nd-order
/// response, a thrust-only record its sensor's).
pub const UNDETERMINED_RATIO: f64 = 10.0;

/// One figure: a value with its standard deviation and the channel(s) it came from, or `null`
/// and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Figure {
    /// The value (`null`: the data cannot show it, see `reason`).
    pub value: Option<f64>,
    /// Its standard deviation (`null` with no value, or when the fit left the figure at a bound
    /// of its search or fixed: see `note`).
    pub uncertainty: Option<f64>,
    /// The channel(s) it came from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub from: Option<String>,
    /// Why there is no value.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// What the value includes or assumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

impl Figure {
    /// The fitted value with its standard deviation; a value whose standard deviation is over
    /// [`UNDETERMINED_RATIO`] times its size is one the data do not determine: `null` and why.
    fn of(e: Estimate, from: impl Into<String>) -> Figure {
        if let Some(u) = e.1 {
            if !(u.is_finite() && u <= UNDETERMINED_RATIO * e.0.abs()) {
                return Figure::refused(format!(
                    "not determined by the data: {:.3e} with a standard deviation of {u:.3e}",
                    e.0
                ));
            }
        }
        Figure {
            value: Some(e.0),
            uncertainty: e.1,
            from: Some(from.into()),
            reason: None,
            note: None,
        }
    }

    fn refused(reason: impl Into<String>) -> Figure {
        Figure {
            value: None,
            uncertainty: None,
            from: None,
            reason: Some(reason.into()),
            note: None,
        }
    }

    fn noted(mut self, note: impl Into<String>) -> Figure {
        self.note = Some(note.into());
        self
    }
}

/// One channel's sensor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensorFigures {
    /// Its delay against the reference channel, s.
    pub delay_s: Figure,
    /// Its first-order lag, s.
    pub tau_s: Figure,
    /// Its refresh interval (the spacing of its readings), s.
    pub refresh_s: Figure,
    /// RMS of the fit's residuals, the channel's unit.
    pub rms: f64,
    /// Readings fitted.
    pub readings: usize,
}

/// `identify --json`'s `"stand"`: the stand's physics as the record shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StandReport {
    /// The channel the rotor's figures are timed on (its sensor's delay and lag are counted in
    /// them; every other sensor is timed against it).
    pub reference_channel: &'static str,
    /// ESC dead time `θ`, s.
    pub esc_dead_time_s: Figure,
    /// Spin-up time constant at `reference_speed_rpm`, s.
    pub rotor_tau_up_s: Figure,
    /// Spin-down time constant at `reference_speed_rpm`, s.
    pub rotor_tau_down_s: Figure,
    /// `γ` of `τ ∝ (n_ref/n)^γ`.
    pub rotor_tau_speed_exponent: Figure,
    /// `k_T` of `T = k_T ωᵉ`, N per (rad/s)^e.
    pub k_t: Figure,
    /// `e`.
    pub thrust_exponent: Figure,
    /// `k_Q` of `Q = k_Q ωᵉ`, N·m per (rad/s)^e.
    pub k_q: Figure,
    /// The speed at the record's highest command, rev/min (where the τ are given).
    pub reference_speed_rpm: Figure,
    /// The ESC's dead band `u₀` (throttle 0..1).
    pub command_zero: Figure,
    /// The speed map's exponent `a`.
    pub speed_map_exponent: Figure,
    /// The supply's internal resistance, Ω.
    pub supply_resistance_ohm: Figure,
    /// Per channel key, its sensor.
    pub sensors: BTreeMap<&'static str, SensorFigures>,
    /// Jacobians the fit computed.
    pub iterations: usize,
    /// The span of the record fitted, s from its start (all of it up to 30 000 rows).
    pub fitted_span_s: [f64; 2],
}

/// `"stand"` when the record gives no model: the reason.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StandRefused {
    /// Why.
    pub refused: String,
}

/// `"stand"`: the report, or why there is none.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Stand {
    /// The stand's figures.
    Fitted(Box<StandReport>),
    /// Why there are none.
    Refused(StandRefused),
}

impl Stand {
    /// From the fit's result.
    pub fn of(fit: Result<StandFit, StandModelError>) -> Stand {
        match fit {
            Ok(f) => Stand::Fitted(Box::new(report(&f))),
            Err(e) => Stand::Refused(StandRefused {
                refused: e.to_string(),
            }),
        }
    }
}

/// The reason a channel's own lag is not given without a speed channel.
pub const NOT_SEPARABLE: &str = "no speed channel: the load cell's delay and lag cannot be told \
     from the ESC's and the rotor's (they are counted in the rotor's figures)";

/// What the fit `f` shows, each figure with its channel or its reason (module doc).
pub fn report(f: &StandFit) -> StandReport {
    let s = &f.shows;
    let reference = f.channels.first().map_or("", |c| c.key);
    let key_of = |q: Quantity| f.channels.iter().find(|c| c.quantity == q).map(|c| c.key);
    let rotor_note = (!s.speed).then(|| {
        format!("timed on the {reference}: includes its sensor's delay and lag (no speed channel)")
    });
    let with_note = |fig: Figure| match &rotor_note {
        Some(n) => fig.noted(n.clone()),
        None => fig,
    };
    let esc_dead_time_s = with_note(Figure::of(f.dead_time_s, reference));
    let rotor_tau_up_s = match s.rises {
        true => with_note(Figure::of(f.tau_up_s, reference)),
        false => Figure::refused("the command never rises: no spin-up to time"),
    };
    let rotor_tau_down_s = match s.falls {
        true => with_note(Figure::of(f.tau_down_s, reference)),
        false => Figure::refused("the command never falls: no spin-down to time"),
    };
    let rotor_tau_speed_exponent = match s.several_levels {
        true => Figure::of(f.tau_speed_exponent, reference),
        false => Figure::refused(
            "the command moves to one level only: the time constant's change with speed cannot show",
        ),
    };
    let no_speed_unit = "no speed channel: the coefficient needs the speed in rad/s";
    let k_t = match (key_of(Quantity::Thrust), f.k_t_rad) {
        (None, _) => Figure::refused("no thrust channel"),
        (Some(_), None) => Figure::refused(no_speed_unit),
        (Some(t), Some(e)) => {
            Figure::of(e, format!("{t}, {reference}")).noted("N per (rad/s)^e, e = thrust_exponent")
        }
    };
    let k_q = match (key_of(Quantity::Torque), f.k_q_rad) {
        (None, _) => Figure::refused("no torque channel"),
        (Some(_), None) => Figure::refused(no_speed_unit),
        (Some(t), Some(e)) => Figure::of(e, format!("{t}, {reference}"))
            .noted("N·m per (rad/s)^e, e = thrust_exponent"),
    };
    let loads: Vec<&str> = [Quantity::Thrust, Quantity::Torque, Quantity::Current]
        .into_iter()
        .filter_map(key_of)
        .collect();
    let thrust_exponent = match (s.exponent, s.speed) {
        (false, _) => Figure::refused("no thrust, torque or current channel"),
        (true, true) => Figure::of(f.thrust_exponent, loads.join(", ")),
        (true, false) => Figure::of(f.thrust_exponent, loads.join(", ")).noted(
            "on the speed taken ∝ (command − u0)·V: no speed channel to show the speed map's own exponent",
        ),
    };
    let reference_speed_rpm = match f.speed_ref_rpm {
        Some(e) => Figure::of(e, reference),
        None => Figure::refused("no speed channel"),
    };
    let command_zero = Figure::of(f.command_zero, reference);
    let speed_map_exponent = match s.speed {
        true => Figure::of(f.map_exponent, reference),
        false => Figure::refused(
            "no speed channel: the map's exponent cannot be told from the thrust's (taken as 1)",
        ),
    };
    let supply_resistance_ohm = match f.supply_resistance_ohm {
        Some(e) => Figure::of(e, "voltage, current"),
        None => Figure::refused("needs a voltage and a current channel"),
    };
    let sensors = f
        .channels
        .iter()
        .map(|c| {
            let own = |e: Option<Estimate>| match (c.reference, e) {
                (true, _) if s.speed => Figure::refused(
                    "the reference channel: its sensor's delay and lag are counted in the rotor's",
                ),
                (true, _) => Figure::refused(NOT_SEPARABLE),
                (false, Some(e)) => {
                    let fig = Figure::of(e, format!("{} against {reference}", c.key));
                    match e.1 {
                        None => fig.noted("at a bound of its search range"),
                        Some(_) => fig,
                    }
                }
                (false, None) => Figure::refused("not fitted"),
            };
            let refresh = Figure::of((c.refresh_s.0, Some(c.refresh_s.1)), c.key).noted(
                "the median spacing of its readings (a held channel's repeats are no readings)",
            );
            (
                c.key,
                SensorFigures {
                    delay_s: own(c.delay_s),
                    tau_s: own(c.tau_s),
                    refresh_s: refresh,
                    rms: c.rms,
                    readings: c.readings,
                },
            )
        })
        .collect();
    StandReport {
        reference_channel: reference,
        esc_dead_time_s,
        rotor_tau_up_s,
        rotor_tau_down_s,
        rotor_tau_speed_exponent,
        k_t,
        thrust_exponent,
        k_q,
        reference_speed_rpm,
        command_zero,
        speed_map_exponent,
        supply_resistance_ohm,
        sensors,
        iterations: f.iterations,
        fitted_span_s: [f.window_s.0, f.window_s.1],
    }
}
