//! The human tables of the step figures and static maps (`identify`'s summary); the JSON has
//! the same numbers as `"steps"` and `"static_map"`.

use std::collections::BTreeMap;
use std::fmt::Write;

use serde::Serialize;

use propid_numerics::stand::ChannelTiming;
use propid_numerics::stand::StandFigures;
use propid_numerics::stand_model::report::{Figure, Stand};
use propid_numerics::static_map::{not_repeatable, MIN_SHARE, NOISE_FACTOR};
use propid_numerics::step_directions::by_direction;
use propid_numerics::step_response::{Direction, StepFigures};

/// One entry of `"steps"`: the step's figures on the identified output, and its dead time and
/// time constant on every output channel of the stand (`"channels"`, by key; omitted when
/// the input is no command).
#[derive(Debug, Clone, Serialize)]
pub struct StepOut<'a> {
    /// The figures on the identified output.
    #[serde(flatten)]
    pub figures: &'a StepFigures,
    /// Per channel key, the step's timing there.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub channels: BTreeMap<&'static str, ChannelTiming>,
}

/// A number, or `-` where the data supports none.
fn num(v: Option<f64>, prec: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.prec$}"),
        _ => "-".into(),
    }
}

/// An overshoot (the column's `%` follows), or `< bound` when it is within the noise.
fn overshoot(value: Option<f64>, below: Option<f64>) -> String {
    match (value, below) {
        (None, Some(b)) => format!("< {b:.1}"),
        (v, _) => num(v, 1),
    }
}

/// `value ± sd`, or `value` alone without an uncertainty.
fn pm(v: f64, sd: Option<f64>) -> String {
    let f = |x: f64| {
        if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e5) {
            format!("{x:.4e}")
        } else {
            format!("{x:.4}")
        }
    };
    match sd {
        Some(s) => format!("{} ± {}", f(v), f(s)),
        None => f(v),
    }
}

/// Two table cells (the real-data tables): the static map of thrust (else of the identified
/// output, [`super::load::OUTPUT_KEY`])
/// — number of levels, the zero-command reading taken out (`zero`), power law `k`, `u0`,
/// exponent `e`, `expo a`, unit — and the steps —
/// how many, and per direction ([`by_direction`]: up, then down) the median dead time (`< dt`
/// when below a sample) and time constant (s) of those that resolve them; `–` for none.
pub fn brief(f: &StandFigures) -> (String, String) {
    // The thrust's map, else the identified output's (never another channel's).
    let map = f
        .static_map
        .get("thrust")
        .or_else(|| f.static_map.get(super::load::OUTPUT_KEY))
        .map_or_else(
            || "–".to_string(),
            |m| {
                let mut t = format!("{} levels", m.levels.len());
                if let Some(z) = &m.zero_offset {
                    let _ = write!(t, "; zero {}", pm(z.value, None));
                }
                if let Some(p) = &m.power {
                    let _ = write!(
                        t,
                        "; k {}, u0 {:.3}, e {:.2}",
                        pm(p.k, None),
                        p.u0,
                        p.exponent
                    );
                }
                if let Some(e) = &m.expo {
                    let _ = write!(t, "; expo a {:.2}", e.a);
                }
                format!("{t} ({})", m.unit)
            },
        );
    let steps = if f.steps.is_empty() {
        "–".to_string()
    } else {
        let dirs = by_direction(&f.steps);
        let sides: Vec<String> = ["up", "down"]
            .into_iter()
            .filter_map(|n| dirs.get(n).map(|d| (n, d)))
            .map(|(n, d)| {
                let dead = match d.dead_time_below_sample {
                    true => "< dt".to_string(),
                    false => num(d.dead_time_s, 3),
                };
                format!("{n} dead {dead}, τ {}", num(d.time_constant_s, 3))
            })
            .collect();
        format!("{}: {}", f.steps.len(), sides.join("; "))
    };
    (map, steps)
}

/// Appends the step table and the static maps to `o` (nothing when the record has neither).
pub fn write_tables(o: &mut String, f: &StandFigures) {
    if !f.steps.is_empty() {
        let _ = match f.steps.iter().all(|s| s.from_response()) {
            true => writeln!(
                o,
                "steps ({}), found from the response: no command in the record, each timed from \
                 when the response starts to move (no dead time, no command levels):",
                f.steps.len()
            ),
            false => writeln!(o, "steps ({}):", f.steps.len()),
        };
        let _ = writeln!(
            o,
            "  {:>9}  {:>15}  {:>4}  {:>9}  {:>9}  {:>9}  {:>9}  {:>9}",
            "t (s)",
            "command",
            "dir",
            "dead (s)",
            "tau (s)",
            "10-90 (s)",
            "settle (s)",
            "overshoot"
        );
        for s in &f.steps {
            let dir = match s.direction {
                Direction::Up => "up",
                Direction::Down => "down",
            };
            let tau = match (s.time_constant_s, s.resolvable, s.note) {
                (None, false, Some(_)) if s.dead_time_s.is_some() => "< dt".to_string(),
                (t, ..) => num(t, 4),
            };
            let dead = match s.dead_time_below_sample {
                true => "< dt".to_string(),
                false => num(s.dead_time_s, 4),
            };
            // A step found from the response has no command levels.
            let command = match s.from_response() {
                true => format!("{:>15}", "(response)"),
                false => format!("{:>6.3} -> {:>5.3}", s.from, s.to),
            };
            let _ = writeln!(
                o,
                "  {:>9.3}  {command}  {:>4}  {:>9}  {:>9}  {:>9}  {:>9}  {:>8}%{}",
                s.t_s,
                dir,
                dead,
                tau,
                num(s.rise_10_90_s, 4),
                num(s.settling_90_s, 4),
                overshoot(s.overshoot_pct, s.overshoot_below_pct),
                s.note
                    .filter(|&n| n != propid_numerics::stand::NO_COMMAND)
                    .map(|n| format!("  ({n})"))
                    .unwrap_or_default()
            );
        }
        // Medians per direction, in the same columns, up first.
        let dirs = by_direction(&f.steps);
        for (name, d) in ["up", "down"]
            .into_iter()
            .filter_map(|n| dirs.get(n).map(|d| (n, d)))
        {
            let dead = match d.dead_time_below_sample {
                true => "< dt".to_string(),
                false => num(d.dead_time_s, 4),
            };
            let _ = writeln!(
                o,
                "  {:>9}  {:>15}  {:>4}  {:>9}  {:>9}  {:>9}  {:>9}  {:>8}%  ({} of {} steps timed)",
                "median",
                "",
                name,
                dead,
                num(d.time_constant_s, 4),
                num(d.rise_10_90_s, 4),
                num(d.settling_90_s, 4),
                overshoot(d.overshoot_pct, d.overshoot_below_pct),
                d.timed,
                d.steps
            );
        }
    }
    for (key, map) in &f.static_map {
        let _ = writeln!(
            o,
            "static map: {key} ({}) over {} levels",
            map.unit,
            map.levels.len()
        );
        let _ = writeln!(
            o,
            "  {:>9}  {:>12}  {:>10}  {:>8}",
            "throttle", "mean", "std", "samples"
        );
        for l in &map.levels {
            let _ = writeln!(
                o,
                "  {:>9.4}  {:>12.5}  {:>10.5}  {:>8}",
                l.throttle, l.mean, l.std, l.samples
            );
        }
        if let (Some(lo), Some(hi)) = (
            map.repeats.iter().map(|r| r.shift).reduce(f64::min),
            map.repeats.iter().map(|r| r.shift).reduce(f64::max),
        ) {
            // Not repeatable only beyond both bounds; within either, repeatable.
            let within = match not_repeatable(&map.levels, &map.repeats) {
                Some(_) => "beyond",
                None => "within",
            };
            let joined = if within == "beyond" { "and" } else { "or" };
            let within = format!(
                "{within} {NOISE_FACTOR} × the visits' spread {joined} {} % of full scale",
                100.0 * MIN_SHARE
            );
            let _ = writeln!(
                o,
                "  repeats   {} command(s) held again: the last visit minus the first {} .. {} \
                 {} ({within})",
                map.repeats.len(),
                num(Some(lo), 5),
                num(Some(hi), 5),
                map.unit
            );
        }
        if map.falls_with_command {
            let _ = writeln!(
                o,
                "  falls     the {key} falls as the command rises (a load cell mounted reversed, \
                 a pusher, a motor turning the other way): the curves fit its magnitude, k and \
                 t_max negative"
            );
        }
        if let Some(z) = &map.zero_offset {
            let _ = writeln!(
                o,
                "  zero      {} {} at zero command ({} level(s)): taken out, the curves below \
                 fit the {key} above it",
                pm(z.value, Some(z.sd)),
                map.unit,
                z.levels
            );
        }
        match &map.power {
            Some(p) => {
                let sd = p.uncertainty;
                let _ = writeln!(
                    o,
                    "  power     k·max(u − u0, 0)^e: k {}, u0 {}, e {}",
                    pm(p.k, sd.map(|s| s.k)),
                    pm(p.u0, sd.map(|s| s.u0)),
                    pm(p.exponent, sd.map(|s| s.exponent))
                );
            }
            None => {
                let _ = writeln!(o, "  power     - (fewer than 3 levels, or none above zero)");
            }
        }
        match &map.expo {
            Some(e) => {
                let sd = e.uncertainty;
                let _ = writeln!(
                    o,
                    "  expo      (1 − a)·x + a·x²: a {}, t_max {}",
                    pm(e.a, sd.map(|s| s.a)),
                    pm(e.t_max, sd.map(|s| s.t_max))
                );
            }
            None => {
                let _ = writeln!(
                    o,
                    "  expo      - (fewer than 2 levels, or no positive t_max)"
                );
            }
        }
        if let Some(k) = &map.k_t {
            let _ = writeln!(o, "  k_t       {} N/(rad/s)²", pm(k.k_t, k.k_t_sd));
        }
    }
}

/// Appends each step's dead time and time constant on every output channel, side by side
/// (nothing when the steps have no timing per channel, or only one channel).
pub fn write_channel_timing(o: &mut String, steps: &[StepOut<'_>]) {
    let keys: Vec<&'static str> = steps
        .first()
        .map(|s| s.channels.keys().copied().collect())
        .unwrap_or_default();
    if keys.len() < 2 {
        return;
    }
    let _ = writeln!(o, "step timing per channel, dead time / tau (s):");
    let mut head = format!("  {:>9}  {:>4}", "t (s)", "dir");
    for k in &keys {
        let _ = write!(head, "  {k:>17}");
    }
    let _ = writeln!(o, "{head}");
    for s in steps {
        let dir = match s.figures.direction {
            Direction::Up => "up",
            Direction::Down => "down",
        };
        let mut line = format!("  {:>9.3}  {dir:>4}", s.figures.t_s);
        for k in &keys {
            let cell = s.channels.get(k).map_or_else(
                || "-".to_string(),
                |c| format!("{} / {}", num(c.dead_time_s, 3), num(c.time_constant_s, 3)),
            );
            let _ = write!(line, "  {cell:>17}");
        }
        let _ = writeln!(o, "{line}");
    }
}

/// A figure of the stand: `value ± sd (from channel)`, or `- (reason)`.
fn figure(f: &Figure, prec: usize) -> String {
    match f.value {
        Some(v) => {
            let v = match (v.abs(), prec) {
                (a, _) if a != 0.0 && !(1e-3..1e5).contains(&a) => format!("{v:.4e}"),
                _ => format!("{v:.prec$}"),
            };
            let sd = f.uncertainty.map_or_else(String::new, |s| {
                if s != 0.0 && !(1e-3..1e5).contains(&s) {
                    format!(" ± {s:.2e}")
                } else {
                    format!(" ± {s:.prec$}")
                }
            });
            let from = f
                .from
                .as_deref()
                .map_or_else(String::new, |c| format!("  (from {c})"));
            let note = f
                .note
                .as_deref()
                .map_or_else(String::new, |n| format!("; {n}"));
            format!("{v}{sd}{from}{note}")
        }
        None => format!("-  ({})", f.reason.as_deref().unwrap_or("not shown")),
    }
}

/// Appends the stand's physics (`"stand"`): each figure with the channel it came from, or why
/// the record cannot show it.
pub fn write_physics(o: &mut String, stand: Option<&Stand>) {
    let r = match stand {
        None => return,
        Some(Stand::Refused(r)) => {
            let _ = writeln!(o, "stand model: none ({})", r.refused);
            return;
        }
        Some(Stand::Fitted(r)) => r,
    };
    let _ = writeln!(
        o,
        "stand model (the rotor timed on {}, each sensor against it):",
        r.reference_channel
    );
    let rows: [(&str, &Figure, usize); 11] = [
        ("esc dead time (s)", &r.esc_dead_time_s, 4),
        ("rotor tau up (s)", &r.rotor_tau_up_s, 4),
        ("rotor tau down (s)", &r.rotor_tau_down_s, 4),
        ("tau speed exponent", &r.rotor_tau_speed_exponent, 3),
        ("reference speed (rpm)", &r.reference_speed_rpm, 0),
        ("command dead band u0", &r.command_zero, 4),
        ("speed map exponent", &r.speed_map_exponent, 3),
        ("thrust exponent e", &r.thrust_exponent, 3),
        ("k_t", &r.k_t, 4),
        ("k_q", &r.k_q, 4),
        ("supply resistance (ohm)", &r.supply_resistance_ohm, 4),
    ];
    for (name, f, prec) in rows {
        let _ = writeln!(o, "  {name:<24} {}", figure(f, prec));
    }
    for (key, s) in &r.sensors {
        let _ = writeln!(
            o,
            "  sensor {key:<9} refresh {} s, {} readings, rms {}",
            num(s.refresh_s.value, 4),
            s.readings,
            num(Some(s.rms), 4)
        );
        let _ = writeln!(o, "    {:<22} {}", "delay (s)", figure(&s.delay_s, 4));
        let _ = writeln!(o, "    {:<22} {}", "tau (s)", figure(&s.tau_s, 4));
    }
}
