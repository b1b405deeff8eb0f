//! The detection table of `propid diagnose` (issue 5): for every effect of the catalogue,
//! `CASES` seeded synthetic cases (random plants, random effect parameters, see
//! `propid_sim::synth`), and how often the effect was named, how often another one was,
//! the parameter error, and the validation-fit gain; plus the false-alarm rate on clean cases.
//!
//! Then the real data: `propid diagnose` (the same loader and diagnosis as the CLI) on the
//! datasets of `../shared/data` (skipped with a message when absent), one row per file.
//!
//! Run: `cargo run --release --example detection_table [CASES] [DATA_DIR]` (default 20;
//! DATA_DIR defaults to `$PROPID_SHARED_DATA`, else `../shared/data`). Prints Markdown;
//! `scripts/detection_table.sh` puts it into `docs/diagnose.md`.

use propid_numerics::EffectName;
use std::fmt::Write;
use std::path::{Path, PathBuf};

use propid::cli::diagnose::{load, Args};
use propid::cli::identify::{stand_brief, stand_of, Args as IdentifyArgs};
use propid::cli::read::{ReadArgs, ReadFlags};
use propid_diagnose::{self as diagnose, Diagnosis};
use propid_numerics::order::HankelSize;
use propid_numerics::svd::SvdChoice;
use propid_sim::plant::PlantConfig;
use propid_sim::synth;

/// One real-data file and how to read it (columns as `propid identify` reads them).
struct RealCase {
    folder: &'static str,
    file: &'static str,
    input: Option<&'static str>,
    output: Option<&'static str>,
    fs: Option<f64>,
    columns: Option<&'static [&'static str]>,
}

const fn case(
    folder: &'static str,
    file: &'static str,
    input: Option<&'static str>,
    output: Option<&'static str>,
    fs: Option<f64>,
    columns: Option<&'static [&'static str]>,
) -> RealCase {
    RealCase {
        folder,
        file,
        input,
        output,
        fs,
        columns,
    }
}

const KRULL: &[&str] = &["t_s", "load_kg"];
const BLCTRL: &[&str] = propid_testkit::inject::BLCTRL_COLUMNS;

const REAL: &[RealCase] = &[
    case(
        "vanderploeg-rcbenchmark-steps",
        "90PERCENT_2024-08-13_185523.csv",
        None,
        None,
        None,
        None,
    ),
    case(
        "vanderploeg-rcbenchmark-steps",
        "StepsTestV2_2024-07-16_164339.csv",
        None,
        None,
        None,
        None,
    ),
    case(
        "vanderploeg-rcbenchmark-steps",
        "RampTest_2024-07-21_144641.csv",
        None,
        None,
        None,
        None,
    ),
    case(
        "krull-thrust-steps",
        "0500_thrust_response.csv",
        Some("none"),
        Some("load_kg"),
        None,
        Some(KRULL),
    ),
    case(
        "krull-thrust-steps",
        "1500_thrust_response.csv",
        Some("none"),
        Some("load_kg"),
        None,
        Some(KRULL),
    ),
    case(
        "krull-thrust-steps",
        "increasing_thrust_response.csv",
        Some("none"),
        Some("load_kg"),
        None,
        Some(KRULL),
    ),
    case(
        "dantonio-rcbenchmark-ramp",
        "StepsTest20230615_2023-06-15_174003.csv",
        None,
        None,
        None,
        None,
    ),
    case(
        "noahcurtiss-blctrl-steps",
        "robbe12.0.txt",
        Some("cmd"),
        Some("force"),
        Some(50.0),
        Some(BLCTRL),
    ),
    case(
        "noahcurtiss-blctrl-steps",
        "tiger12.0.txt",
        Some("cmd"),
        Some("force"),
        Some(50.0),
        Some(BLCTRL),
    ),
    case(
        "nanodrone-cf-motors",
        "multisine_20251017_run1.csv",
        Some("m1_thrust"),
        Some("m1_erpm"),
        None,
        None,
    ),
    case(
        "nanodrone-cf-motors",
        "random1_20251017_run1.csv",
        Some("m1_thrust"),
        Some("m1_erpm"),
        None,
        None,
    ),
    case(
        "nanodrone-cf-motors",
        "square_20251017_run1.csv",
        Some("m1_thrust"),
        Some("m1_erpm"),
        None,
        None,
    ),
    case(
        "bitcraze-cf21-pwm-steps",
        "cf21_stock2.csv",
        Some("pwm"),
        Some("weight[g]"),
        Some(100.0),
        None,
    ),
    case(
        "silverbox",
        "SNLS80mV.csv",
        Some("V1"),
        Some("V2"),
        Some(610.35),
        None,
    ),
    case(
        "f16-gvt",
        "F16Data_SineSw_Level7.csv",
        Some("force_N"),
        Some("acc1"),
        None,
        None,
    ),
    case(
        "daisy-mechanical",
        "robot_arm.csv",
        Some("u_torque"),
        Some("y_accel"),
        Some(100.0),
        None,
    ),
    case(
        "daisy-mechanical",
        "flutter.csv",
        Some("u"),
        Some("y"),
        Some(1.0),
        None,
    ),
    case(
        "cascaded-tanks",
        "dataBenchmark.csv",
        Some("uEst"),
        Some("yEst"),
        Some(0.25),
        None,
    ),
    case(
        "emps",
        "DATA_EMPS.csv",
        Some("vir_force_N"),
        Some("qm_position_m"),
        None,
        None,
    ),
];

/// Short text of a finding's parameters.
fn params_text(f: &diagnose::Finding) -> String {
    let v: Vec<String> = f
        .params
        .iter()
        .map(|(k, v)| match v.as_f64() {
            // Four decimals; tiny coefficients (a cubic stiffness in eRPM⁻²) in scientific form.
            Some(x) if x != 0.0 && x.abs() < 1e-3 => format!("{k} {x:.3e}"),
            Some(x) => format!("{k} {x:.4}"),
            None => format!("{k} {}", v.as_str().unwrap_or("")),
        })
        .collect();
    format!(
        "`{}` ({}; held-out {:+.1} pp)",
        f.effect,
        v.join(", "),
        f.cv_gain_pp
    )
}

fn real_data(dir: &Path) {
    println!("\n### Real data (`{}`)\n", dir.display());
    if !dir.is_dir() {
        println!(
            "Skipped: {} is absent (a user's clone has no ../shared).",
            dir.display()
        );
        eprintln!("real data skipped: {} absent", dir.display());
        return;
    }
    println!("| dataset | file | input → output | samples, rate | validation | baseline fit | effects found | extended fit | gain | verdict | static map | steps |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for c in REAL {
        let path: PathBuf = dir.join(c.folder).join(c.file);
        if !path.exists() {
            println!("| {} | {} | | | | missing | | | | | | |", c.folder, c.file);
            continue;
        }
        let read = ReadArgs {
            file: path,
            output: c.output.map(str::to_string).into_iter().collect(),
            how: ReadFlags {
                input: c.input.map(str::to_string),
                fs: c.fs,
                columns: c.columns.map(|v| v.iter().map(|s| s.to_string()).collect()),
                esc_us: None,
                // The BL-Ctrl takes an 8-bit command (PROVENANCE.md): 10..250 of 0..255.
                input_range: (c.columns == Some(BLCTRL)).then(|| vec![0.0, 255.0]),
                poles: None,
            },
        };
        let (map, steps) = stand_of(&IdentifyArgs {
            read: read.clone(),
            order: None,
            json: true,
            save: None,
            report: None,
            svd: SvdChoice::default(),
            hankel: HankelSize::default(),
        })
        .map_or_else(|_| ("–".into(), "–".into()), |f| stand_brief(&f));
        let args = Args {
            read,
            json: false,
            report: None,
            estimation_fraction: 0.7,
            sim_config: None,
            save: None,
        };
        let row = load(&args).map_err(|e| e.to_string()).and_then(|s| {
            let opts = diagnose::Options::default();
            s.diagnose(&opts).map(|d| (s, d)).map_err(|e| e.to_string())
        });
        match row {
            Ok((s, d)) => {
                let found: Vec<String> = d.findings.iter().map(params_text).collect();
                let (ext, gain) = match (&d.extended, &d.gain) {
                    (Some(e), Some(g)) => (
                        format!("{:.1} %", e.fit_percent),
                        format!("{:+.1} pp, RMS × {:.2}", g.fit_percent_points, g.rms_ratio),
                    ),
                    _ => ("–".to_string(), "–".to_string()),
                };
                let validation = match d.validation.method {
                    diagnose::folds::Method::BlockedCv => {
                        format!("blocked CV, {} folds", d.validation.folds.len())
                    }
                    diagnose::folds::Method::Holdout => "hold-out tail".to_string(),
                };
                let verdict = verdict_text(&d);
                println!(
                    "| {} | {} | {} → {}{} | {}, {:.4} Hz | {validation} | {:.1} % | {} | {} | {} | {verdict} | {map} | {steps} |",
                    c.folder,
                    c.file,
                    s.input_name,
                    s.output_name,
                    if s.voltage.is_some() {
                        " (+ voltage)"
                    } else {
                        ""
                    },
                    s.u.len(),
                    1.0 / s.dt_s,
                    d.baseline.fit_percent,
                    if found.is_empty() {
                        "none".to_string()
                    } else {
                        found.join("; ")
                    },
                    ext,
                    gain
                );
            }
            Err(e) => println!(
                "| {} | {} | | | | not diagnosed: {} | | | | | {map} | {steps} |",
                c.folder,
                c.file,
                e.replace('|', "/")
            ),
        }
    }
}

/// The verdict cell: the kind, the final residual in noise floors, and the warnings' kinds
/// (`diagnose`'s JSON names).
fn verdict_text(d: &Diagnosis) -> String {
    let mut t = serde_json::to_value(d.verdict.kind)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default();
    if let Some(f) = d.noise_floor.as_ref().filter(|f| f.rms > 0.0) {
        let _ = write!(t, " ({:.1} × noise)", d.residual.final_rms() / f.rms);
    }
    let mut kinds: Vec<String> = d
        .warnings
        .iter()
        .filter_map(|w| {
            serde_json::to_value(w.kind)
                .ok()?
                .as_str()
                .map(str::to_string)
        })
        .collect();
    kinds.dedup();
    if !kinds.is_empty() {
        let _ = write!(t, "; warns {}", kinds.join(", "));
    }
    t
}

/// Relative (or absolute, for delays and levels) error of the main parameter of a finding.
/// `v_mean` is the record's mean supply voltage: the simulated stand scales the throttle by
/// `1 + g (V − battery_v)`, diagnose reports the gain per volt at the mean voltage `V̄`, and
/// the two are the same law when `g_V = g / (1 + g (V̄ − battery_v))`.
fn param_error(name: EffectName, cfg: &PlantConfig, d: &Diagnosis, v_mean: f64) -> Option<f64> {
    let f = d.findings.iter().find(|f| f.effect == name)?;
    let get = |k: &str| f.params.get(k).and_then(|v| v.as_f64());
    let e = &cfg.effects;
    let rel = |est: f64, truth: f64| ((est - truth) / truth).abs();
    Some(match name {
        EffectName::DeadTime => {
            let truth = (e.dead_time.as_ref()?.delay_s / synth::DT_S).round();
            (get("delay_samples")? - truth).abs()
        }
        EffectName::StaticNonlinearity => {
            rel(get("exponent")?, e.static_nonlinearity.as_ref()?.exponent)
        }
        EffectName::ExtraMode => rel(get("fn_hz")?, e.extra_mode.as_ref()?.fn_hz),
        EffectName::BaselineDrift => rel(get("rate_per_s")?, e.baseline_drift.as_ref()?.rate_per_s),
        EffectName::PeriodicDisturbance => rel(
            get("amplitude")?,
            e.periodic_disturbance.as_ref()?.amplitude,
        ),
        EffectName::SupplySag => {
            let g = e.supply_sag.as_ref()?.gain_per_volt;
            rel(
                get("gain_per_volt")?,
                g / (1.0 + g * (v_mean - cfg.battery_v)),
            )
        }
        EffectName::Saturation => (get("level")? - e.saturation.as_ref()?.level).abs(),
        EffectName::AsymmetricDynamics => {
            let a = e.asymmetric_dynamics.as_ref()?;
            rel(get("down_over_up")?, a.down_scale / a.up_scale)
        }
        EffectName::StiffnessNonlinearity => {
            let truth = e.stiffness_nonlinearity.as_ref()?.k3_per_k1;
            let curvature = f.params.get("curvature").and_then(|v| v.as_str());
            if curvature != Some(if truth > 0.0 { "hardens" } else { "softens" }) {
                return Some(f64::INFINITY);
            }
            rel(get("k3_per_k1")?, truth)
        }
        // Stand-only effects: never hidden in this 2nd-order plant.
        EffectName::SensorLag | EffectName::SpeedDependentTau => return None,
    })
}

fn unit(name: EffectName) -> &'static str {
    match name {
        EffectName::DeadTime => "samples (abs)",
        EffectName::Saturation => "throttle (abs)",
        _ => "relative",
    }
}

fn main() {
    let cases: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(20);
    let data = PathBuf::from(
        std::env::args()
            .nth(2)
            .or_else(|| std::env::var("PROPID_SHARED_DATA").ok())
            .unwrap_or("../shared/data".into()),
    );
    let opts = diagnose::Options::default();
    println!("### Synthetic cases ({cases} per effect, seeded)\n");
    println!("| effect | cases | named | other effect named | parameter error, median (max) | fit gain, median pp | rms ratio, median |");
    println!("|---|---|---|---|---|---|---|");
    for name in diagnose::effects::names() {
        let (mut named, mut other) = (0, 0);
        let mut errs = Vec::new();
        let mut gains = Vec::new();
        let mut ratios = Vec::new();
        for i in 0..cases {
            let Ok((cfg, m)) = synth::case(Some(name), i) else {
                continue;
            };
            let Ok(d) = diagnose::diagnose(synth::DT_S, &m.u, &m.y, &[], Some(&m.voltage), &opts)
            else {
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
                        .map(|f| (f.effect.as_str(), f.score))
                        .collect::<Vec<_>>()
                );
            }
            let v_mean = m.voltage.iter().sum::<f64>() / m.voltage.len().max(1) as f64;
            if let Some(e) = param_error(name, &cfg, &d, v_mean) {
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
        let Ok((_, m)) = synth::case(None, i) else {
            continue;
        };
        let Ok(d) = diagnose::diagnose(synth::DT_S, &m.u, &m.y, &[], Some(&m.voltage), &opts)
        else {
            continue;
        };
        fits.push(d.baseline.fit_percent);
        if !d.findings.is_empty() {
            alarms += 1;
            eprintln!(
                "clean case {i}: {:?}",
                d.findings
                    .iter()
                    .map(|f| (f.effect.as_str(), f.score))
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
    real_data(&data);
}
