//! The calibrated simulation through the binary (`docs/stand-model.md`): `diagnose
//! --sim-config` writes the stand diagnose fitted on a generated Tyto-style export as a `propid
//! sim` configuration, `sim --replay-command` replays the export's command through it into a
//! CSV in the export's columns and units that scores as the written stand's fit within a point
//! (scored as diagnose scores, `propid_diagnose::stand::score_on_folds`), and `demo
//! --sim-config` runs the daemon against that stand.

use serde_json::Value;

use crate::identify_stand_model::write_export;
use crate::support::propid;

/// The columns of a CSV text: header names, then the rows' numbers (NaN for an empty cell).
fn columns(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|s| s.trim_start_matches('\u{feff}').to_string())
        .collect();
    let mut cols = vec![Vec::new(); head.len()];
    for l in lines {
        for (c, cell) in l.split(',').enumerate() {
            cols[c].push(cell.parse().unwrap_or(f64::NAN));
        }
    }
    (head, cols)
}

/// A little deterministic noise in [-0.5, 0.5].
fn wiggle(k: usize, seed: f64) -> f64 {
    ((k as f64 * 12.9898 + seed).sin() * 43_758.545_3).fract() - 0.5
}

/// The channels `(key, column)` of `cols` scored against `log` as diagnose scores them: on the
/// folds of the log's command (`ESC signal (µs)`) and thrust, at the log's readings (a held
/// column's repeated values are no readings).
fn scored(
    log: (&[String], &[Vec<f64>]),
    sim: (&[String], &[Vec<f64>]),
    channels: &[(&'static str, &str)],
) -> std::collections::BTreeMap<&'static str, f64> {
    use propid_diagnose::folds::Folds;
    use propid_numerics::segment::SegmentRules;
    use propid_numerics::stand_model::fit::Channel;
    let col = |(head, cols): (&[String], &[Vec<f64>]), name: &str| {
        cols[head.iter().position(|h| h == name).unwrap()].clone()
    };
    let time = col(log, "Time (s)");
    let dt = (time[time.len() - 1] - time[0]) / (time.len() - 1) as f64;
    let u: Vec<f64> = col(log, "ESC signal (µs)")
        .iter()
        .map(|us| (us - 1000.0) / 1000.0)
        .collect();
    let ys: Vec<(Vec<f64>, Vec<bool>)> = channels
        .iter()
        .map(|(_, name)| {
            let y = col(log, name);
            let held = (0..y.len()).map(|k| k > 0 && y[k] == y[k - 1]).collect();
            (y, held)
        })
        .collect();
    let folds = Folds::from_input(&u, &ys[0].0, 0.7, &SegmentRules::for_record(dt, true));
    let chans: Vec<Channel<'_>> = channels
        .iter()
        .zip(&ys)
        .map(|((key, _), (y, held))| Channel {
            key,
            quantity: propid_diagnose::stand::quantity(key).unwrap(),
            y,
            interpolated: held,
        })
        .collect();
    let sims: Vec<(&str, Vec<f64>)> = channels
        .iter()
        .map(|(key, name)| (*key, col(sim, name)))
        .collect();
    propid_diagnose::stand::score_on_folds(&chans, &sims, &folds)
}

#[test]
fn the_calibrated_stand_replays_the_log_within_a_point_of_the_fit() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("tyto.csv");
    let toml = dir.path().join("stand.toml");
    let sim = dir.path().join("sim.csv");
    write_export(&log);
    let (log_s, toml_s, sim_s) = (
        log.to_str().unwrap(),
        toml.to_str().unwrap(),
        sim.to_str().unwrap(),
    );
    let (code, out, err) = propid(&["diagnose", log_s, "--json", "--sim-config", toml_s]);
    assert_eq!(code, 0, "{err}");
    let d: Value = serde_json::from_str(&out).unwrap();
    let fitted = d["sim_config"]["fit_percent"].as_object().unwrap().clone();
    assert_eq!(fitted.len(), 3, "thrust, rpm, current: {}", d["sim_config"]);
    // The configuration is the stand's: a motor with the load cell's lag on the thrust.
    let cfg = propid_sim::SimConfig::load(&toml).unwrap();
    let cell = cfg.plant.sensors.thrust.expect("a thrust sensor");
    assert!((cell.tau_s - 0.15).abs() < 0.04, "{cell:?}");
    assert!((cell.refresh_s - 1.0 / 7.0).abs() < 0.01, "{cell:?}");

    let (code, out, err) = propid(&[
        "sim",
        "--config",
        toml_s,
        "--replay-command",
        log_s,
        "--out",
        sim_s,
    ]);
    assert_eq!(code, 0, "{err}");
    let r: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(r["type"], "sim_replay", "{r}");
    let held_out = &d["sim_config"]["held_out_fit_percent"];
    for (key, f) in &fitted {
        let (f, s) = (f.as_f64().unwrap(), r["fit_percent"][key].as_f64().unwrap());
        eprintln!(
            "{key}: the stand's fit {f:.2} %, held out {}, replay {s:.2} %",
            held_out[key]
        );
        assert!(
            (f - s).abs() <= 1.0 && f > 80.0,
            "{key}: fit {f}, replay {s}"
        );
        assert_eq!(
            d["sim_config"]["replay_fit_percent"][key],
            r["fit_percent"][key]
        );
    }
    // SIM.csv has the log's columns, in its units: scored from the files, it agrees.
    let (log_head, log_cols) = columns(&std::fs::read_to_string(&log).unwrap());
    let (sim_head, sim_cols) = columns(&std::fs::read_to_string(&sim).unwrap());
    let mut want = log_head.clone();
    want.sort();
    let mut got = sim_head.clone();
    got.sort();
    assert_eq!(got, want);
    let from_files = scored(
        (&log_head, &log_cols),
        (&sim_head, &sim_cols),
        &[
            ("thrust", "Thrust (gf)"),
            ("rpm", "Motor Electrical Speed (RPM)"),
            ("current", "Current (A)"),
        ],
    );
    for (key, v) in &from_files {
        let reported = r["fit_percent"][key].as_f64().unwrap();
        assert!((v - reported).abs() < 0.1, "{key}: {v} vs {reported}");
    }
    // In the log's units (a fit percent is not: the thrust's scale in gf).
    let top = |head: &[String], cols: &[Vec<f64>]| {
        let c = head.iter().position(|h| h == "Thrust (gf)").unwrap();
        cols[c].iter().copied().fold(f64::MIN, f64::max)
    };
    let (ymax, smax) = (top(&log_head, &log_cols), top(&sim_head, &sim_cols));
    assert!((smax / ymax - 1.0).abs() < 0.05, "gf: {smax} vs {ymax}");
}

/// A stand the sim itself logs (motor with a dead band, a load cell with a lag), through
/// `diagnose --sim-config`: its parameters come back, and `demo --sim-config` identifies it.
#[test]
fn a_log_the_sim_wrote_gives_its_stand_back_and_the_demo_runs_on_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    std::fs::write(
        path("truth.toml"),
        "[stand]\nsample_rate_hz = 200\n[plant]\nkind = \"motor\"\nreference_throttle = 0.8\n\
         rpm_at_reference = 20000.0\nbattery_v = 16.0\ninternal_resistance_ohm = 0.05\n\
         discharge_v_per_s = 0.0\n[plant.motor]\nthrust_at_reference_n = 9.0\n\
         tau_up_s = 0.035\ntau_down_s = 0.06\ndead_time_s = 0.02\ncommand_zero = 0.08\n\
         [plant.sensors.thrust]\ndelay_s = 0.01\ntau_s = 0.03\n",
    )
    .unwrap();
    // The command, and the columns the simulated log is to have (placeholders that move
    // irregularly: a column that never moves is no channel, one that moves linearly reads as
    // interpolated between two readings).
    let mut cmd = String::from("t_s,throttle,thrust_N,rpm,current_A,voltage_V\n");
    let levels = [0.25, 0.5, 0.35, 0.8, 0.6, 0.3, 0.7, 0.45, 0.25];
    for (k, l) in levels
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(300))
        .enumerate()
    {
        let x = (k * k) % 997 + 1;
        // The supply is the log's measured voltage in a replay of a sagging plant: a battery's.
        let v = 16.0 + 0.02 * x as f64 / 997.0;
        cmd.push_str(&format!("{:.3},{l},{x},{x},{x},{v}\n", k as f64 * 0.005));
    }
    std::fs::write(path("cmd.csv"), cmd).unwrap();
    let (code, _, err) = propid(&[
        "sim",
        "--config",
        &path("truth.toml"),
        "--replay-command",
        &path("cmd.csv"),
        "--out",
        &path("log.csv"),
    ]);
    assert_eq!(code, 0, "{err}");
    // A measured log has noise (a clean replay repeats its values on every hold, which a
    // reader takes for a held channel).
    let (head, cols) = columns(&std::fs::read_to_string(path("log.csv")).unwrap());
    let mut noisy = head.join(",") + "\n";
    for k in 0..cols[0].len() {
        let row: Vec<String> = cols
            .iter()
            .enumerate()
            .map(|(c, y)| match c {
                0 | 1 => format!("{}", y[k]),
                _ => format!("{}", y[k] * (1.0 + 0.002 * wiggle(k, c as f64))),
            })
            .collect();
        noisy.push_str(&(row.join(",") + "\n"));
    }
    std::fs::write(path("noisy.csv"), noisy).unwrap();
    let (code, out, err) = propid(&[
        "diagnose",
        &path("noisy.csv"),
        "--sim-config",
        &path("stand.toml"),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("sim config: the fitted stand written to"),
        "{out}"
    );
    let cfg = propid_sim::SimConfig::load(std::path::Path::new(&path("stand.toml"))).unwrap();
    let (p, m) = (&cfg.plant, &cfg.plant.motor);
    let near = |what: &str, got: f64, want: f64, tol: f64| {
        assert!(
            (got - want).abs() <= tol,
            "{what}: {got} vs {want} ± {tol}: {p:?}"
        )
    };
    near("rpm_at_reference", p.rpm_at_reference, 20_000.0, 200.0);
    near("tau_up_s", m.tau_up_s, 0.035, 0.003);
    near("tau_down_s", m.tau_down_s, 0.06, 0.005);
    near("dead_time_s", m.dead_time_s, 0.02, 0.005);
    near("command_zero", m.command_zero, 0.08, 0.01);
    near("thrust_at_reference_n", m.thrust_at_reference_n, 9.0, 0.2);
    let cell = p.sensors.thrust.expect("a thrust sensor");
    near("thrust tau_s", cell.tau_s, 0.03, 0.006);
    near("thrust delay_s", cell.delay_s, 0.01, 0.005);
    let toml_s = path("stand.toml");
    let toml_s = toml_s.as_str();
    // The daemon against the stand as it was measured: models near the configuration's
    // linearised motor at its levels.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(["demo", "--json", "--sim-config", toml_s])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let text = String::from_utf8(out.stdout).unwrap();
    let models: Vec<Value> = text
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .filter(|l| l["type"] == "model")
        .collect();
    // One model per level of the plan, its gain rising with the level as the motor's does.
    // The published 2nd-order model is not the linearised motor here: the thrust reaches the
    // load cell 10 rows after the command (dead time and sensor delay), which a 2nd-order fit
    // of one-sample pulses folds into its gain (measured: 1.6 × the linearised gain).
    assert_eq!(models.len(), 3, "{text}");
    let dt = 1.0 / cfg.stand.sample_rate_hz as f64;
    let mut last = 0.0;
    for m in &models {
        let level = m["operating_point"].as_f64().unwrap();
        let truth = cfg.plant.linearise(level, dt, 0.0).unwrap();
        let gain = m["dc_gain"].as_f64().unwrap();
        eprintln!(
            "demo at {level}: gain {gain:.3} vs {:.3} N",
            truth.gain_n_per_throttle
        );
        let ratio = gain / truth.gain_n_per_throttle;
        assert!(
            (0.8..2.0).contains(&ratio) && gain > last,
            "{m} vs {truth:?}"
        );
        last = gain;
    }
}
