//! The run report of an experiment kind in Markdown (`propid run --report DIR`, `propid
//! replay --report DIR`): the thrust curve with the flight-controller numbers (given by the
//! caller), the step table, τ against throttle, the ramp's hysteresis, the frequency
//! response, the models (a pulses run's per operating point: fn, ζ, τ against throttle). The
//! figures it names ([`THRUST_SVG`], [`TAU_SVG`], [`BODE_SVG`], [`MODELS_SVG`]) are drawn by
//! the caller.

use std::fmt::Write as _;

use crate::{Material, Published, StaticMapLine};

/// The report's file.
pub const MARKDOWN: &str = "report.md";
/// The thrust curve.
pub const THRUST_SVG: &str = "thrust_curve.svg";
/// τ against throttle.
pub const TAU_SVG: &str = "tau.svg";
/// The Bode plot.
pub const BODE_SVG: &str = "bode.svg";
/// fn, ζ and τ of the models against their operating points.
pub const MODELS_SVG: &str = "models.svg";

fn ms(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{:.1}", v * 1e3))
}

fn num(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

/// Which figures the report refers to (the caller draws those it says).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Figures {
    /// A thrust map is there.
    pub thrust: bool,
    /// Steps with a time constant are there.
    pub tau: bool,
    /// A frequency response is there.
    pub bode: bool,
    /// Models are there.
    pub models: bool,
}

/// The figures `m` supports.
pub fn figures(m: &Material) -> Figures {
    let mut f = Figures {
        models: !m.models.is_empty(),
        ..Figures::default()
    };
    for p in &m.published {
        match p {
            Published::StaticMap(m) if m.output == "thrust" => f.thrust = true,
            Published::Step(s) if s.figures.time_constant_s.is_some() => f.tau = true,
            Published::FrequencyResponse(_) => f.bode = true,
            _ => {}
        }
    }
    f
}

fn map_section(out: &mut String, m: &StaticMapLine) {
    let leg = m.leg.map(|l| format!(" ({l} leg)")).unwrap_or_default();
    let _ = writeln!(out, "\n### {}{leg}\n", m.output);
    let _ = writeln!(
        out,
        "| throttle | mean ({u}) | std ({u}) | samples |",
        u = m.map.unit
    );
    let _ = writeln!(out, "|---:|---:|---:|---:|");
    for l in &m.map.levels {
        let _ = writeln!(
            out,
            "| {:.3} | {:.4} | {:.4} | {} |",
            l.throttle, l.mean, l.std, l.samples
        );
    }
    if let Some(p) = &m.map.power {
        let _ = writeln!(
            out,
            "\nPower law `T = k·(u − u0)^e`: k = {:.4}, u0 = {:.3}, e = {:.3}.",
            p.k, p.u0, p.exponent
        );
    }
    if let Some(e) = &m.map.expo {
        // the flight controllers' own normalisations: the section after the maps
        let _ = writeln!(
            out,
            "Expo `T/t_max = (1 − a)·x + a·x²` over the throttle: a = {:.3}, t_max = {:.4} {}.",
            e.a, e.t_max, m.map.unit
        );
    }
    if let Some(k) = &m.map.k_t {
        let _ = writeln!(out, "Thrust coefficient k_t = {:.4e} N/(rad/s)².", k.k_t);
    }
    if let Some(h) = &m.hysteresis {
        let _ = writeln!(
            out,
            "\nHysteresis (down leg − up leg): largest {:.4} {} ({:.1} % of full) at throttle \
             {:.3}, mean {:+.4} over {} throttles.",
            h.max_abs, m.map.unit, h.max_pct, h.at_throttle, h.mean, h.points
        );
    }
    for (dir, d) in &m.directions {
        let _ = writeln!(
            out,
            "\nSteps {dir} (medians of {} steps, {} timed): dead time {} ms, τ {} ms, rise {} \
             ms, settling {} ms.",
            d.steps,
            d.timed,
            ms(d.dead_time_s),
            ms(d.time_constant_s),
            ms(d.rise_10_90_s),
            ms(d.settling_90_s)
        );
    }
}

/// The report of a run (`material`); `flight_controller`: the section on the flight
/// controllers' numbers from the thrust map, placed after the maps.
pub fn markdown(material: &Material, flight_controller: Option<&str>) -> String {
    let published = &material.published[..];
    let figs = figures(material);
    let mut out = format!("# propid run report: {}\n", material.kind.name());
    let maps: Vec<&StaticMapLine> = published
        .iter()
        .filter_map(|p| match p {
            Published::StaticMap(m) => Some(m),
            _ => None,
        })
        .collect();
    if !maps.is_empty() {
        out.push_str("\n## Static map\n");
        if figs.thrust {
            let _ = writeln!(out, "\n![thrust curve]({THRUST_SVG})");
        }
        if material.kind == crate::Kind::Pulses {
            out.push_str(
                "\nThe steady output at each operating point, between its pulses (after \
                 `settle_ms`).\n",
            );
        }
        for m in maps {
            map_section(&mut out, m);
        }
        if let Some(fc) = flight_controller {
            out.push_str(fc);
        }
    }
    if !material.models.is_empty() {
        out.push_str("\n## Models\n\n");
        out.push_str(
            "| t (s) | operating point | fn (Hz) | ζ | τ (ms) | DC gain | pulses |\n\
             |---:|---:|---:|---:|---:|---:|---:|\n",
        );
        let fin = |v: f64, d: usize| num(v.is_finite().then_some(v), d);
        for r in &material.models {
            let _ = writeln!(
                out,
                "| {:.2} | {:.3} | {} | {} | {} | {} | {} |",
                r.t_s,
                r.operating_point,
                fin(r.fn_hz, 2),
                fin(r.zeta, 3),
                ms(r.tau_s),
                fin(r.dc_gain, 4),
                r.pulses
            );
        }
        let _ = writeln!(
            out,
            "\n![fn, ζ and τ against the operating point]({MODELS_SVG})"
        );
    }
    let steps: Vec<_> = published
        .iter()
        .filter_map(|p| match p {
            Published::Step(s) => Some(s),
            _ => None,
        })
        .collect();
    if !steps.is_empty() {
        out.push_str("\n## Steps\n\n");
        out.push_str(
            "| # | t (s) | from | to | dir | dead time (ms) | τ (ms) | rise 10–90 (ms) | \
             settling (ms) | overshoot (%) |\n|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|\n",
        );
        for s in &steps {
            let f = &s.figures;
            let _ = writeln!(
                out,
                "| {} | {:.2} | {:.3} | {:.3} | {:?} | {} | {} | {} | {} | {} |",
                s.index,
                f.t_s,
                f.from,
                f.to,
                f.direction,
                ms(f.dead_time_s),
                ms(f.time_constant_s),
                ms(f.rise_10_90_s),
                ms(f.settling_90_s),
                num(f.overshoot_pct, 1)
            );
        }
        if figs.tau {
            let _ = writeln!(out, "\n![time constant against throttle]({TAU_SVG})");
        }
    }
    for p in published {
        let Published::FrequencyResponse(fr) = p else {
            continue;
        };
        let r = &fr.response;
        let _ = writeln!(
            out,
            "\n## Frequency response ({} about throttle {:.3})\n",
            fr.output, fr.level
        );
        let _ = writeln!(
            out,
            "Peak {} Hz, bandwidth (−3 dB) {} Hz, phase delay {} ms at {} Hz; low-frequency \
             gain {}; {} segments of {} samples.",
            num(r.peak_hz, 2),
            num(r.bandwidth_hz, 2),
            ms(r.phase_delay_s),
            num(r.phase_delay_at_hz, 2),
            num(r.gain_low, 4),
            r.segments,
            r.segment
        );
        if let Some(m) = &r.model {
            let _ = writeln!(
                out,
                "\nFitted `K ωn² e^(−sT)/(s² + 2ζωn s + ωn²)`: K = {:.4}, fn = {:.2} Hz, ζ = \
                 {:.3}, T = {:.1} ms (rms relative error {:.3}).",
                m.gain,
                m.natural_hz,
                m.damping,
                m.dead_time_s * 1e3,
                m.rms_rel_error
            );
        }
        let _ = writeln!(out, "\n![Bode plot]({BODE_SVG})");
    }
    if published.is_empty() && material.models.is_empty() {
        out.push_str("\nNothing was published: the run ended before any result.\n");
    }
    out
}
