//! Runs propid's identification over every dataset in `../shared/data` and writes a Markdown
//! table (rate, excitation, path, model, fit on held-out data). `scripts/real_data.sh` calls it;
//! README shows the table it writes. Nothing in the table is typed by hand.
//!
//! Usage: `cargo run --release --example real_data -- DATA_DIR OUT.md`
//!
//! Per file: the same reader and identification as `propid identify` (CSV reader with column
//! choice, steps from the response when no input was logged, pulse path or OKID + ERA), fitted
//! on the first two thirds of the record; the model (inputs as deviations from the estimation
//! mean, started in steady state, output offset matched on the estimation part) is simulated
//! over the whole record and scored on the last third:
//! `fit = 100 · (1 − ‖y − ŷ‖ / ‖y − mean(y)‖)` (validation samples only).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::DMatrix;
use propid::cli::identify::{stand_brief, stand_of, Args as IdentifyArgs, Quality};
use propid::cli::read::{ReadArgs, ReadFlags};
use propid_ingest::csv_file::{read_csv, CsvFileOptions, InputChoice};
use propid_ingest::steps::find_steps;
use propid_numerics::identify::{identify_any, AnyInput, PathTaken};
use propid_numerics::okid::OkidOptions;
use propid_numerics::operating_points::{operating_points, OpOptions};
use propid_numerics::order::HankelSize;
use propid_numerics::quality::Flaw;
use propid_numerics::segment::{Command, SegmentRules};
use propid_numerics::stand::steady_levels;
use propid_numerics::static_map::level_slope;
use propid_numerics::svd::SvdChoice;
use propid_numerics::workspace::IdentOptions;
use propid_numerics::ModelReport;
use propid_testkit::inject::BLCTRL_COLUMNS;

/// One file and how to read it.
struct Case {
    folder: &'static str,
    file: &'static str,
    /// The input column: `None` the command column, `Some("none")` no input (steps found in
    /// the response).
    input: Option<&'static str>,
    /// Raw command values at throttle 0 and 1 when the values cannot tell (`--input-range`).
    input_range: Option<(f64, f64)>,
    outputs: &'static [&'static str],
    fs: Option<f64>,
    columns: Option<&'static [&'static str]>,
    /// What the data's own documentation says the excitation is.
    excitation: &'static str,
}

const CASES: &[Case] = &[
    Case {
        folder: "vanderploeg-rcbenchmark-steps",
        file: "90PERCENT_2024-08-13_185523.csv",
        input: None,
        input_range: None,
        outputs: &[],
        fs: None,
        columns: None,
        excitation: "ESC staircase (5 levels)",
    },
    Case {
        folder: "vanderploeg-rcbenchmark-steps",
        file: "StepsTestV2_2024-07-17_181904.csv",
        input: None,
        input_range: None,
        outputs: &[],
        fs: None,
        columns: None,
        excitation: "steady averages per ESC step (static map only)",
    },
    Case {
        folder: "vanderploeg-rcbenchmark-steps",
        file: "RampTest_2024-07-21_144641.csv",
        input: None,
        input_range: None,
        outputs: &[],
        fs: None,
        columns: None,
        excitation: "ESC ramp at ~2 Hz (static map)",
    },
    Case {
        folder: "krull-thrust-steps",
        file: "0500_thrust_response.csv",
        input: Some("none"),
        input_range: None,
        outputs: &["load_kg"],
        fs: None,
        columns: Some(&["t_s", "load_kg"]),
        excitation: "DShot step up/down, command not logged",
    },
    Case {
        folder: "krull-thrust-steps",
        file: "1200_thrust_response.csv",
        input: Some("none"),
        input_range: None,
        outputs: &["load_kg"],
        fs: None,
        columns: Some(&["t_s", "load_kg"]),
        excitation: "DShot step up/down, command not logged",
    },
    Case {
        folder: "krull-thrust-steps",
        file: "1500_thrust_response.csv",
        input: Some("none"),
        input_range: None,
        outputs: &["load_kg"],
        fs: None,
        columns: Some(&["t_s", "load_kg"]),
        excitation: "DShot step up/down, command not logged",
    },
    Case {
        folder: "krull-thrust-steps",
        file: "increasing_thrust_response.csv",
        input: Some("none"),
        input_range: None,
        outputs: &["load_kg"],
        fs: None,
        columns: Some(&["t_s", "load_kg"]),
        excitation: "slow DShot ramp, command not logged",
    },
    Case {
        folder: "dantonio-rcbenchmark-ramp",
        file: "StepsTest20230615_2023-06-15_174003.csv",
        input: None,
        input_range: None,
        outputs: &[],
        fs: None,
        columns: None,
        excitation: "slow ESC ramp",
    },
    Case {
        folder: "noahcurtiss-blctrl-steps",
        file: "robbe12.0.txt",
        input: Some("cmd"),
        // The BL-Ctrl takes an 8-bit command (PROVENANCE.md): 10..250 of 0..255.
        input_range: Some((0.0, 255.0)),
        outputs: &["force"],
        fs: Some(50.0),
        columns: Some(BLCTRL_COLUMNS),
        excitation: "25-level staircase, ~50 Hz assumed",
    },
    Case {
        folder: "noahcurtiss-blctrl-steps",
        file: "tiger12.0.txt",
        input: Some("cmd"),
        // The BL-Ctrl takes an 8-bit command (PROVENANCE.md): 10..250 of 0..255.
        input_range: Some((0.0, 255.0)),
        outputs: &["force"],
        fs: Some(50.0),
        columns: Some(BLCTRL_COLUMNS),
        excitation: "25-level staircase, ~50 Hz assumed",
    },
    Case {
        folder: "nanodrone-cf-motors",
        file: "multisine_20251017_run1.csv",
        input: Some("m1_thrust"),
        input_range: None,
        outputs: &["m1_erpm"],
        fs: None,
        columns: None,
        excitation: "flight, multisine trajectory (closed loop)",
    },
    Case {
        folder: "nanodrone-cf-motors",
        file: "random1_20251017_run1.csv",
        input: Some("m1_thrust"),
        input_range: None,
        outputs: &["m1_erpm"],
        fs: None,
        columns: None,
        excitation: "flight, random trajectory (closed loop)",
    },
    Case {
        folder: "nanodrone-cf-motors",
        file: "square_20251017_run1.csv",
        input: Some("m1_thrust"),
        input_range: None,
        outputs: &["m1_erpm"],
        fs: None,
        columns: None,
        excitation: "flight, square trajectory (closed loop)",
    },
    Case {
        folder: "nanodrone-cf-motors",
        file: "melon_20251017_run1.csv",
        input: Some("m1_thrust"),
        input_range: None,
        outputs: &["m1_erpm"],
        fs: None,
        columns: None,
        excitation: "flight, melon trajectory (closed loop)",
    },
    Case {
        folder: "bitcraze-cf21-pwm-steps",
        file: "cf21_stock2.csv",
        input: Some("pwm"),
        input_range: None,
        outputs: &["weight[g]"],
        fs: Some(100.0),
        columns: None,
        excitation: "PWM staircase, no time base (100 Hz assumed)",
    },
    Case {
        folder: "silverbox",
        file: "SNLS80mV.csv",
        input: Some("V1"),
        input_range: None,
        outputs: &["V2"],
        fs: Some(610.35),
        columns: None,
        excitation: "noise with rising amplitude, then multisines",
    },
    Case {
        folder: "f16-gvt",
        file: "F16Data_SineSw_Level1.csv",
        input: Some("force_N"),
        input_range: None,
        outputs: &["acc1", "acc2", "acc3"],
        fs: None,
        columns: None,
        excitation: "sine sweep 2-15 Hz, level 1",
    },
    Case {
        folder: "f16-gvt",
        file: "F16Data_SineSw_Level7.csv",
        input: Some("force_N"),
        input_range: None,
        outputs: &["acc1", "acc2", "acc3"],
        fs: None,
        columns: None,
        excitation: "sine sweep 2-15 Hz, level 7",
    },
    Case {
        folder: "daisy-mechanical",
        file: "robot_arm.csv",
        input: Some("u_torque"),
        input_range: None,
        outputs: &["y_accel"],
        fs: Some(100.0),
        columns: None,
        excitation: "periodic sine sweep (dt 0.01 s assumed)",
    },
    Case {
        folder: "daisy-mechanical",
        file: "flutter.csv",
        input: Some("u"),
        input_range: None,
        outputs: &["y"],
        fs: Some(1.0),
        columns: None,
        excitation: "coloured noise (rate unknown: per sample)",
    },
    Case {
        folder: "daisy-mechanical",
        file: "CD_player_arm.csv",
        input: Some("u1"),
        input_range: None,
        outputs: &["y1", "y2"],
        fs: Some(1.0),
        columns: None,
        excitation: "actuator forces (rate unknown: per sample)",
    },
    Case {
        folder: "cascaded-tanks",
        file: "dataBenchmark.csv",
        input: Some("uEst"),
        input_range: None,
        outputs: &["yEst"],
        fs: Some(0.25),
        columns: None,
        excitation: "random steps of pump voltage",
    },
    Case {
        folder: "emps",
        file: "DATA_EMPS.csv",
        input: Some("vir_force_N"),
        input_range: None,
        outputs: &["qm_position_m"],
        fs: None,
        columns: None,
        excitation: "closed-loop position reference",
    },
];

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let data = PathBuf::from(args.get(1).map_or("../shared/data", String::as_str));
    let out = PathBuf::from(args.get(2).map_or("docs/real_data.md", String::as_str));
    if !data.is_dir() {
        println!(
            "real_data: {} is absent: skipped (no table written)",
            data.display()
        );
        return;
    }
    let mut md = String::from(HEADER);
    for case in CASES {
        let path = data.join(case.folder).join(case.file);
        let (map, steps) = stand_columns(case, &path);
        let row = match run_case(case, &path, &map, &steps) {
            Ok(r) => r,
            Err(e) => format!(
                "| {} | {} | – | {} | – | – | – | – | – | – | – | {map} | {steps} | {} |\n",
                case.folder,
                case.file,
                case.excitation,
                e.replace('|', "/")
            ),
        };
        eprint!("{row}");
        md.push_str(&row);
    }
    md.push_str(FOOTER);
    if let Err(e) = std::fs::write(&out, md) {
        eprintln!("real_data: writing {}: {e}", out.display());
        std::process::exit(7);
    }
    println!("real_data: wrote {}", out.display());
}

const HEADER: &str = "\
# propid on real data

Produced by `scripts/real_data.sh` (`examples/real_data.rs`) from the datasets in
`../shared/data` (see their `PROVENANCE.md`); do not edit by hand. Each model is fitted on the
first two thirds of the record and scored on the last third (free-run simulation from steady
state; fit = 100·(1 − ‖y − ŷ‖/‖y − ȳ‖) on the held-out samples; 100 is perfect, 0 is no better
than the mean, negative is worse; *diverges*: below −1000 %, an unstable or drifting model).
Order chosen automatically. *DC gain* is `refused` where it contradicts the slope of the
estimation part's own steady levels (`propid identify`'s `dc_gain_contradicts_levels`, exit
4), or where a stand's command is sampled more slowly than a motor settles (a third of a
second: `sample_period_too_long`, every sample a steady state). Rates in Hz; `τ` are the time
constants of the real poles; `fn`/`ζ` of the dominant oscillatory pair (– if none). *Static
map* and *steps* are `propid identify`'s `static_map` and `steps` of the whole record (they
need no model, so they are shown when the identification fails too): the power law
`T = k·max(u − u0, 0)^e` of the first output (throttle 0..1), the flight-controller blend
`expo a`, the number of levels; the number of clean command steps with the median dead time and
time constant (s) of those that resolve them.

| dataset | file | rate | excitation | path | order | fn (Hz) | ζ | τ (s) | DC gain | held-out fit (%) | static map | steps | notes |
|---|---|---|---|---|---|---|---|---|---|---|---|---|---|
";

const FOOTER: &str = "
Notes: *steps found* = the file has no input column; the steps were found from the response and
the input is the sequence of levels (DC gain ≈ 1 by construction; the dynamics are what count).
*OP* = operating points identified (staircase levels or ramp windows). A low held-out fit on
thrust-stand staircases is the nonlinearity of the propeller (gain grows with the command); on
closed-loop flight data it is feedback. `propid diagnose` names such effects.
";

/// The static-map and step columns from `propid identify`'s own figures
/// ([`propid::cli::identify::stand_of`], the same reader and options as the row).
fn stand_columns(case: &Case, path: &Path) -> (String, String) {
    let args = IdentifyArgs {
        read: ReadArgs {
            file: path.to_path_buf(),
            output: case.outputs.iter().map(|s| s.to_string()).collect(),
            how: ReadFlags {
                input: case.input.map(str::to_string),
                fs: case.fs,
                columns: case
                    .columns
                    .map(|c| c.iter().map(|s| s.to_string()).collect()),
                esc_us: None,
                input_range: case.input_range.map(|(a, b)| vec![a, b]),
                poles: None,
            },
        },
        order: None,
        json: true,
        save: None,
        report: None,
        svd: SvdChoice::default(),
        hankel: HankelSize::default(),
    };
    match stand_of(&args) {
        Ok(f) => stand_brief(&f),
        Err(_) => ("–".into(), "–".into()),
    }
}

fn run_case(case: &Case, path: &Path, map: &str, steps: &str) -> Result<String, String> {
    let text = std::fs::read(path).map_err(|e| format!("absent ({e})"))?;
    let text = String::from_utf8_lossy(&text);
    let opts = CsvFileOptions {
        input: match case.input {
            None => InputChoice::Command,
            Some("none") => InputChoice::None,
            Some(c) => InputChoice::Column(c.to_string()),
        },
        input_range: case.input_range,
        outputs: case.outputs.iter().map(|s| s.to_string()).collect(),
        fs_hz: case.fs,
        columns: case
            .columns
            .map(|c| c.iter().map(|s| s.to_string()).collect()),
        ..CsvFileOptions::default()
    };
    let file = read_csv(&text, &opts).map_err(|e| e.to_string())?;
    let rec = &file.record;
    let ys: Vec<Vec<f64>> = file
        .outputs
        .iter()
        .map(|n| rec.channel(n).map(|c| c.data.clone()).unwrap_or_default())
        .collect();
    let mut notes = Vec::new();
    let u = match &file.input {
        Some(n) => rec.channel(n).map(|c| c.data.clone()).unwrap_or_default(),
        None => {
            let f = find_steps(&ys[0]).ok_or("too short to find steps")?;
            if f.steps.is_empty() {
                return Err("no input column and no settled step found in the response".into());
            }
            notes.push(format!("{} steps found", f.steps.len()));
            f.input
        }
    };
    if let Some(j) = &file.source.jitter {
        if j.steady_rows {
            notes.push("a table of steady states (held row to row)".into());
        } else if j.resampled {
            notes.push(format!(
                "resampled (rms jitter {:.1} ms)",
                1e3 * j.rms_jitter_s
            ));
        }
    }
    let n = u.len();
    let n_est = 2 * n / 3;
    let y_est: Vec<&[f64]> = ys.iter().map(|c| &c[..n_est]).collect();
    let u_est = [&u[..n_est]];
    let input = AnyInput {
        dt_s: rec.dt_s,
        u: &u_est,
        y: &y_est,
        missing: &rec.missing[..n_est],
        pulse_starts: None,
    };
    // The segmentation of `propid identify`: at the record's rate for a stand's command.
    let command = file.source.input_is_a_command();
    let rules = SegmentRules::for_record(rec.dt_s, command);
    let ident = IdentOptions {
        max_pulse_width: rules.max_pulse_samples,
        ..IdentOptions::default()
    };
    let model = match identify_any(&input, &ident, &OkidOptions::default()) {
        Ok(m) => m,
        // `propid identify` refuses such a record whatever its model (every sample a steady
        // state); the few rows of its estimation part may give none at all.
        Err(_) if command && rules.samples_are_steady() => {
            notes.push(format!("refused ({})", Flaw::SamplePeriodTooLong.name()));
            return Err(notes.join("; "));
        }
        Err(e) => return Err(e.to_string()),
    };
    let op_opts = OpOptions {
        segment: rules,
        ..OpOptions::default()
    };
    let ops = operating_points(&input, &ident, &op_opts);
    if !ops.points.is_empty() {
        notes.push(format!("{} OP ({})", ops.points.len(), ops.kind));
    }
    let fit = held_out_fit(&model.report, &u, &ys, n_est);
    let r = &model.report;
    if let Some(k) = model.okid.as_ref().and_then(|k| k.realised_dc_gain) {
        notes.push(format!("DC gain Σ Y_k (ERA's realisation {k:.4})"));
    }
    // `propid identify`'s quality gate itself, on the model of the estimation part and the slope
    // of that part's own steady levels.
    let cmd = Command::with_missing(&u[..n_est], &rec.missing[..n_est]);
    let slope = level_slope(&steady_levels(cmd, &rules, &ys[0][..n_est]));
    let quality = Quality::of(r, slope.as_ref(), command);
    if !quality.accepted {
        notes.push(format!("refused ({})", quality.names()));
    } else if let propid_numerics::report::Gain::Scalar(g) = r.dc_gain {
        if g <= 0.0 {
            notes.push("warning: DC gain ≤ 0 (the output falls as the input rises)".into());
        }
    }
    let path_name = match model.path {
        PathTaken::Pulse => "pulse",
        PathTaken::Okid => "okid",
    };
    let mut row = String::new();
    let _ = writeln!(
        row,
        "| {} | {} | {:.4} | {} | {} | {} | {} | {} | {} | {} | {} | {map} | {steps} | {} |",
        case.folder,
        case.file,
        1.0 / rec.dt_s,
        case.excitation,
        path_name,
        r.order,
        num(r.fn_hz, 3),
        num(r.zeta, 3),
        list(&r.time_constants_s),
        if !quality.accepted {
            "refused".to_string()
        } else {
            gain(&r.dc_gain)
        },
        fit.iter()
            .map(|f| num(*f, 1))
            .collect::<Vec<_>>()
            .join(", "),
        notes.join("; ")
    );
    Ok(row)
}

fn num(v: f64, digits: usize) -> String {
    if v == f64::NEG_INFINITY {
        "diverges".into()
    } else if v.is_finite() {
        format!("{v:.digits$}")
    } else {
        "–".into()
    }
}

fn list(v: &[f64]) -> String {
    if v.is_empty() {
        return "–".into();
    }
    v.iter()
        .take(3)
        .map(|x| format!("{x:.3}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn gain(g: &propid_numerics::report::Gain) -> String {
    use propid_numerics::report::Gain;
    match g {
        Gain::Scalar(v) => format!("{v:.4}"),
        Gain::List(v) => v
            .iter()
            .map(|x| format!("{x:.3}"))
            .collect::<Vec<_>>()
            .join(", "),
        Gain::Matrix(m) => format!("{m:?}"),
    }
}

/// Free-run simulation of the model over the whole record; fit on samples `n_est..`, per output.
fn held_out_fit(r: &ModelReport, u: &[f64], ys: &[Vec<f64>], n_est: usize) -> Vec<f64> {
    let n = r.order;
    let q = ys.len();
    let mat = |m: &Vec<Vec<f64>>, rows: usize, cols: usize| {
        DMatrix::from_fn(rows, cols, |i, j| {
            m.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0)
        })
    };
    let (a, b, c, d) = (
        mat(&r.a, n, n),
        mat(&r.b, n, 1),
        mat(&r.c, q, n),
        mat(&r.d, q, 1),
    );
    let finite = u[..n_est].iter().filter(|v| v.is_finite());
    let (s, cnt) = finite.fold((0.0, 0usize), |acc, v| (acc.0 + v, acc.1 + 1));
    let u_mean = s / cnt.max(1) as f64;
    let mut last = u.iter().copied().find(|v| v.is_finite()).unwrap_or(u_mean);
    let du0 = last - u_mean;
    let eye = DMatrix::<f64>::identity(n, n);
    let mut x = (eye - &a)
        .lu()
        .solve(&(&b * du0))
        .unwrap_or_else(|| DMatrix::zeros(n, 1));
    let mut sim = vec![Vec::with_capacity(u.len()); q];
    for &uk in u {
        if uk.is_finite() {
            last = uk;
        }
        let du = DMatrix::from_element(1, 1, last - u_mean);
        let yk = &c * &x + &d * &du;
        for (i, s) in sim.iter_mut().enumerate() {
            s.push(yk[i]);
        }
        x = &a * x + &b * du;
    }
    (0..q)
        .map(|i| {
            let y = &ys[i];
            let ok = |k: usize| y[k].is_finite() && sim[i][k].is_finite();
            let est: Vec<usize> = (0..n_est).filter(|&k| ok(k)).collect();
            let val: Vec<usize> = (n_est..y.len()).filter(|&k| ok(k)).collect();
            if est.is_empty() || val.is_empty() {
                return f64::NAN;
            }
            let off = est.iter().map(|&k| y[k] - sim[i][k]).sum::<f64>() / est.len() as f64;
            let mean = val.iter().map(|&k| y[k]).sum::<f64>() / val.len() as f64;
            let err: f64 = val.iter().map(|&k| (y[k] - sim[i][k] - off).powi(2)).sum();
            let tot: f64 = val.iter().map(|&k| (y[k] - mean).powi(2)).sum();
            let fit = 100.0 * (1.0 - (err / tot).sqrt());
            // A simulation that runs away (unstable model) is reported as such, not as a number.
            if fit < -1000.0 {
                f64::NEG_INFINITY
            } else {
                fit
            }
        })
        .collect()
}
