//! The stand catalogue: each effect as the part of the stand model it frees
//! ([`propid_numerics::stand_model::fit::Structure`]) on top of diagnose's stand baseline, and
//! what its finding publishes.
//!
//! | effect | frees | published |
//! |---|---|---|
//! | `dead_time` | the ESC's dead time `θ` | `delay_s`, `delay_samples` |
//! | `sensor_lag` | one non-reference channel's delay `δ` and first-order lag `τ_s` | `channel`, `delay_s`, `tau_s` |
//! | `asymmetric_dynamics` | `τ_down` apart from `τ_up` | `tau_up_s`, `tau_down_s`, `down_over_up` |
//! | `speed_dependent_tau` | `γ` of `τ ∝ (n_ref/n)^γ` | `tau_speed_exponent` |
//! | `static_nonlinearity` | the speed map's exponent `a` and each load's exponent (the thrust curve: `e`; torque and current their own) | `exponent` (the output's), `speed_map_exponent` (`a`), `exponents` per channel |
//! | `supply_sag` | the measured voltage drives the speed map (`n ∝ V^b`, `b` fitted: a loaded motor's winding takes part of a sag) | `gain_per_volt` (`e b / V̄`: the thrust's relative change per volt), `voltage_exponent` (`b`) |
//! | `saturation` | the command clipped at a fitted level | `level`, `signal` (`throttle`) |
//! | `baseline_drift` | a creep on every load and current channel | `rate_per_s` (the output's), `rates_per_s` per channel |
//! | `extra_mode` | a resonance of the stand between the rotor and the load cell | `fn_hz`, `zeta` |
//! | `periodic_disturbance` | a sinusoid on every load and current channel | `freq_hz`, `amplitude` (the output's) |
//!
//! A spring (`stiffness_nonlinearity`) is no part of a stand: a thrust that rings is the rotor
//! plus a resonance of the stand (`extra_mode`).

use propid_numerics::stand_model::fit::{Structure, StructuredFit};
use propid_numerics::stand_model::Quantity;
use propid_numerics::EffectName;
use serde_json::{json, Map, Value};

/// One candidate of the catalogue: the effect, and the channel for a sensor's lag.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Candidate {
    /// The effect.
    pub effect: EffectName,
    /// The channel (key) of a `sensor_lag`.
    pub channel: Option<&'static str>,
}

/// What the record can show, for the catalogue's list of candidates.
#[derive(Debug, Clone)]
pub struct Record {
    /// Non-reference channel keys (a sensor lag is timed against the reference).
    pub timed: Vec<&'static str>,
    /// The record has a supply voltage.
    pub voltage: bool,
    /// The command both rises and falls.
    pub both_directions: bool,
    /// The command moves to two levels or more.
    pub several_levels: bool,
    /// A frequency to start a sinusoid and a resonance from (the residual spectrum's peak).
    pub peak_hz: Option<f64>,
}

/// Every candidate not yet in `st` that `rec` can show.
pub fn candidates(st: &Structure, rec: &Record) -> Vec<Candidate> {
    let mut out = Vec::new();
    let mut add = |effect, channel, ok: bool| {
        if ok {
            out.push(Candidate { effect, channel });
        }
    };
    add(EffectName::DeadTime, None, !st.dead_time);
    add(EffectName::StaticNonlinearity, None, !st.static_map);
    add(
        EffectName::ExtraMode,
        None,
        st.mode.is_none() && rec.peak_hz.is_some(),
    );
    add(EffectName::BaselineDrift, None, !st.creep);
    add(
        EffectName::PeriodicDisturbance,
        None,
        st.sinusoid_hz.is_none() && rec.peak_hz.is_some(),
    );
    add(EffectName::SupplySag, None, !st.voltage && rec.voltage);
    add(EffectName::Saturation, None, !st.command_limit);
    add(
        EffectName::AsymmetricDynamics,
        None,
        !st.asymmetric && rec.both_directions,
    );
    add(
        EffectName::SpeedDependentTau,
        None,
        !st.speed_dependent_tau && rec.several_levels,
    );
    for &c in &rec.timed {
        add(EffectName::SensorLag, Some(c), !st.lagged.contains(&c));
    }
    out
}

/// `st` with candidate `c` freed (`peak_hz`: the start of a sinusoid's or a resonance's
/// frequency).
pub fn with(st: &Structure, c: Candidate, peak_hz: Option<f64>) -> Structure {
    let mut s = st.clone();
    match c.effect {
        EffectName::DeadTime => s.dead_time = true,
        EffectName::StaticNonlinearity => {
            s.static_map = true;
            s.exponent_per_load = true;
        }
        EffectName::ExtraMode => s.mode = peak_hz.map(|f| (f, 0.1)),
        EffectName::BaselineDrift => s.creep = true,
        EffectName::PeriodicDisturbance => s.sinusoid_hz = peak_hz,
        EffectName::SupplySag => {
            s.voltage = true;
            s.voltage_exponent = true;
        }
        EffectName::Saturation => s.command_limit = true,
        EffectName::AsymmetricDynamics => s.asymmetric = true,
        EffectName::SpeedDependentTau => s.speed_dependent_tau = true,
        EffectName::SensorLag => s.lagged.extend(c.channel),
        EffectName::StiffnessNonlinearity => {}
    }
    s
}

/// Whether the figures of `c` fitted in `f` are ones the rows can show: a sensor's lag whose
/// delay and time constant both stay within half a row period `dt_s` of zero reads with the
/// reference at this row rate (its lag at the fit's floor, its delay a fraction of a row):
/// no lag the data show.
pub fn resolved(c: Candidate, f: &StructuredFit, dt_s: f64) -> bool {
    if c.effect != EffectName::SensorLag {
        return true;
    }
    let Some(ch) = f.fit.channels.iter().find(|ch| Some(ch.key) == c.channel) else {
        return true;
    };
    let delay = ch.delay_s.map_or(0.0, |d| d.0);
    let tau = ch.tau_s.map_or(0.0, |t| t.0);
    delay.abs() >= 0.5 * dt_s || tau >= 0.5 * dt_s
}

/// Parameters freed (for the evidence): a sensor's lag and a sinusoid count two per channel.
pub fn parameter_count(c: Candidate) -> usize {
    match c.effect {
        EffectName::SensorLag | EffectName::AsymmetricDynamics => 2,
        EffectName::ExtraMode => 2,
        EffectName::StaticNonlinearity => 2,
        _ => 1,
    }
}

/// The finding's parameters of `c` in the fitted model `f` (`output`: the diagnosed channel's
/// key, `dt_s` the row period, `v_ref` the mean supply voltage).
pub fn params(
    c: Candidate,
    f: &StructuredFit,
    output: &str,
    dt_s: f64,
    v_ref: f64,
) -> Map<String, Value> {
    let s = &f.fit;
    let v = match c.effect {
        EffectName::DeadTime => json!({
            "delay_s": s.dead_time_s.0,
            "delay_samples": s.dead_time_s.0 / dt_s,
        }),
        EffectName::SensorLag => {
            let ch = s.channels.iter().find(|ch| Some(ch.key) == c.channel);
            json!({
                "channel": c.channel,
                "delay_s": ch.and_then(|ch| ch.delay_s).map(|d| d.0),
                "tau_s": ch.and_then(|ch| ch.tau_s).map(|t| t.0),
            })
        }
        EffectName::AsymmetricDynamics => json!({
            "tau_up_s": s.tau_up_s.0,
            "tau_down_s": s.tau_down_s.0,
            "down_over_up": s.tau_down_s.0 / s.tau_up_s.0,
        }),
        EffectName::SpeedDependentTau => json!({
            "tau_speed_exponent": s.tau_speed_exponent.0,
        }),
        EffectName::StaticNonlinearity => {
            let own: Map<String, Value> = s
                .channels
                .iter()
                .filter_map(|ch| Some((ch.key.to_string(), json!(ch.exponent?))))
                .collect();
            json!({
                "exponent": s
                    .channels
                    .iter()
                    .find(|ch| ch.key == output)
                    .and_then(|ch| ch.exponent)
                    .unwrap_or(s.thrust_exponent.0),
                "speed_map_exponent": s.map_exponent.0,
                "exponents": own,
            })
        }
        EffectName::SupplySag => json!({
            "gain_per_volt": s.thrust_exponent.0 * f.voltage_exponent.unwrap_or(1.0)
                / v_ref.max(1e-9),
            "voltage_exponent": f.voltage_exponent.unwrap_or(1.0),
            "supply_resistance_ohm": s.supply_resistance_ohm.map(|r| r.0),
        }),
        EffectName::Saturation => json!({
            "level": f.command_limit,
            "signal": "throttle",
        }),
        EffectName::BaselineDrift => {
            let rates: Map<String, Value> = s
                .channels
                .iter()
                .filter(|ch| ch.quantity != Quantity::Speed)
                .map(|ch| (ch.key.to_string(), json!(creep(ch))))
                .collect();
            json!({
                "rate_per_s": rates.get(output).cloned().unwrap_or(Value::Null),
                "rates_per_s": rates,
            })
        }
        EffectName::ExtraMode => json!({
            "fn_hz": f.mode.map(|m| m.0),
            "zeta": f.mode.map(|m| m.1),
        }),
        EffectName::PeriodicDisturbance => {
            let amp = s
                .channels
                .iter()
                .find(|ch| ch.key == output)
                .and_then(|ch| {
                    let n = ch.amplitudes.len();
                    (n >= 2).then(|| ch.amplitudes[n - 2].hypot(ch.amplitudes[n - 1]))
                });
            json!({
                "freq_hz": f.sinusoid_hz,
                "amplitude": amp,
            })
        }
        EffectName::StiffnessNonlinearity => json!({}),
    };
    match v {
        Value::Object(m) => m,
        _ => Map::new(),
    }
}

/// A load or current channel's creep per second (its amplitudes: the bases, the offset, the
/// creep).
fn creep(ch: &propid_numerics::stand_model::fit::ChannelFit) -> Option<f64> {
    let at = if ch.quantity == Quantity::Current {
        3
    } else {
        2
    };
    ch.amplitudes.get(at).copied()
}

/// The evidence of `c` in words, with its parameters.
pub fn evidence(c: Candidate, p: &Map<String, Value>, drop: &str) -> String {
    let num = |k: &str| p.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN);
    let what = match c.effect {
        EffectName::DeadTime => format!(
            "the stand answers the command {:.3} s late (the ESC's dead time, and the reference \
             sensor's delay with it)",
            num("delay_s")
        ),
        EffectName::SensorLag => format!(
            "the {} sensor reads {:.3} s behind the reference channel through a lag of {:.3} s \
             of its own (a load cell's filter and refresh)",
            c.channel.unwrap_or("?"),
            num("delay_s"),
            num("tau_s")
        ),
        EffectName::AsymmetricDynamics => format!(
            "the rotor spins up with τ {:.3} s and down with τ {:.3} s",
            num("tau_up_s"),
            num("tau_down_s")
        ),
        EffectName::SpeedDependentTau => format!(
            "the rotor's time constant changes with speed as (n_ref/n)^{:.2}",
            num("tau_speed_exponent")
        ),
        EffectName::StaticNonlinearity => format!(
            "the thrust curve: the load grows as speed^{:.2} and the speed as the command^{:.2} \
             above the dead band",
            num("exponent"),
            num("speed_map_exponent")
        ),
        EffectName::SupplySag => format!(
            "the rotor's speed follows the measured supply voltage as V^{:.2}",
            num("voltage_exponent")
        ),
        EffectName::Saturation => format!(
            "the command acts as if clipped at {:.3} (the top of the ESC's range or a power \
             limit)",
            num("level")
        ),
        EffectName::BaselineDrift => format!(
            "the load channels creep ({:.4} per s on the output)",
            num("rate_per_s")
        ),
        EffectName::ExtraMode => format!(
            "a resonance of the stand at {:.2} Hz (ζ {:.2}) between the rotor and the load cell",
            num("fn_hz"),
            num("zeta")
        ),
        EffectName::PeriodicDisturbance => format!(
            "a steady sinusoid at {:.3} Hz (amplitude {:.4} on the output)",
            num("freq_hz"),
            num("amplitude")
        ),
        EffectName::StiffnessNonlinearity => String::new(),
    };
    format!("{what}; {drop}")
}
