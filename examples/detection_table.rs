//! The detection table of `propid diagnose` (issue 5): for every effect of the catalogue,
//! `CASES` seeded synthetic cases (random plants, random effect parameters, see
//! `propid::diagnose::synth`), and how often the effect was named, how often another one was,
//! the parameter error, and the validation-fit gain; plus the false-alarm rate on clean cases.
//!
//! Run: `cargo run --release --example detection_table [CASES]` (default 20). Prints Markdown.

use propid::diagnose::{self, synth, Diagnosis};
use propid::sim::plant::PlantConfig;

/// Relative (or absolute, for delays and levels) error of the main parameter of a finding.
fn param_error(name: &str, cfg: &PlantConfig, d: &Diagnosis) -> Option<f64> {
    let f = d.findings.iter().find(|f| f.effect == name)?;
    let get = |k: &str| f.params.get(k).and_then(|v| v.as_f64());
    let e = &cfg.effects;
    let rel = |est: f64, truth: f64| ((est - truth) / truth).abs();
    Some(match name {
        "dead_time" => {
            let truth = (e.dead_time.as_ref()?.delay_s / synth::DT_S).round();
            (get("delay_samples")? - truth).abs()
        }
        "static_nonlinearity" => rel(get("exponent")?, e.static_nonlinearity.as_ref()?.exponent),
        "extra_mode" => rel(get("fn_hz")?, e.extra_mode.as_ref()?.fn_hz),
        "baseline_drift" => rel(get("rate_per_s")?, e.baseline_drift.as_ref()?.rate_per_s),
        "periodic_disturbance" => rel(
            get("amplitude")?,
            e.periodic_disturbance.as_ref()?.amplitude,
        ),
        "supply_sag" => rel(get("gain_per_volt")?, e.supply_sag.as_ref()?.gain_per_volt),
        "saturation" => (get("level")? - e.saturation.as_ref()?.level).abs(),
        _ => return None,
    })
}

fn unit(name: &str) -> &'static str {
    match name {
        "dead_time" => "samples (abs)",
        "saturation" => "throttle (abs)",
        _ => "relative",
    }
}

fn main() {
    let cases: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(20);
    let opts = diagnose::Options::default();
    println!("| effect | cases | named | other effect named | parameter error, median (max) | fit gain, median pp | rms ratio, median |");
    println!("|---|---|---|---|---|---|---|");
    for name in diagnose::catalogue::EFFECTS {
        let (mut named, mut other) = (0, 0);
        let mut errs = Vec::new();
        let mut gains = Vec::new();
        let mut ratios = Vec::new();
        for i in 0..cases {
            let Ok((cfg, m)) = synth::case(name, i) else {
                continue;
            };
            let Ok(d) = diagnose::diagnose(synth::DT_S, &m.u, &m.y, Some(&m.voltage), &opts) else {
                continue;
            };
            if d.findings.iter().any(|f| f.effect == name) {
                named += 1;
            }
            if d.findings.iter().any(|f| f.effect != name) {
                other += 1;
                eprintln!(
                    "{name} case {i}: also {:?}",
                    d.findings
                        .iter()
                        .map(|f| (&f.effect, f.score))
                        .collect::<Vec<_>>()
                );
            }
            if let Some(e) = param_error(name, &cfg, &d) {
                errs.push(e);
            } else {
                eprintln!(
                    "{name} case {i}: missed; fn {:.1} zeta {:.2}",
                    cfg.fn_hz, cfg.zeta
                );
            }
            if let Some(g) = d.gain {
                gains.push(g.fit_percent_points);
                ratios.push(g.rms_ratio);
            }
        }
        let med = |v: &mut Vec<f64>| {
            if v.is_empty() {
                return f64::NAN;
            }
            v.sort_by(|a, b| a.total_cmp(b));
            v[v.len() / 2]
        };
        let max = errs.iter().copied().fold(f64::NAN, f64::max);
        println!(
            "| `{name}` | {cases} | {named} ({:.0} %) | {other} | {:.3} ({max:.3}) {} | {:.2} | {:.3} |",
            100.0 * named as f64 / cases as f64,
            med(&mut errs),
            unit(name),
            med(&mut gains),
            med(&mut ratios)
        );
    }
    let clean_cases = cases.max(50);
    let mut alarms = 0;
    let mut fits = Vec::new();
    for i in 0..clean_cases {
        let Ok((_, m)) = synth::case("clean", i) else {
            continue;
        };
        let Ok(d) = diagnose::diagnose(synth::DT_S, &m.u, &m.y, Some(&m.voltage), &opts) else {
            continue;
        };
        fits.push(d.baseline.fit_percent);
        if !d.findings.is_empty() {
            alarms += 1;
            eprintln!(
                "clean case {i}: {:?}",
                d.findings
                    .iter()
                    .map(|f| (&f.effect, f.score))
                    .collect::<Vec<_>>()
            );
        }
    }
    fits.sort_by(|a, b| a.total_cmp(b));
    println!(
        "\nClean cases: {clean_cases}, false alarms: {alarms} ({:.1} %), baseline validation fit median {:.1} %.",
        100.0 * alarms as f64 / clean_cases as f64,
        fits.get(fits.len() / 2).copied().unwrap_or(f64::NAN)
    );
}
