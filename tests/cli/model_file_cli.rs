//! Model files through the binary (issue 30): `diagnose --save` then `compare` on the held-out
//! part reproduces diagnose's own figure; a tampered, foreign or unfitting file is refused with
//! its exit code; `simulate` writes the outputs; `identify --save` then `params` on a Tyto-style
//! export gives the values its stand supports and refuses the others with the reason.

use crate::support::propid;
use propid_testkit::dialects::dialects;
use serde_json::Value;

/// A 2nd-order plant (3 Hz, ζ 0.6, 8 N per unit throttle, 0.4 N offset) driven by a multisine
/// (no steps: diagnose holds out the last 30 %), sampled at 100 Hz, a little seeded noise.
fn multisine_csv(n: usize) -> (String, Vec<f64>, Vec<f64>) {
    let dt = 0.01;
    let p = propid_testkit::Plant::new(3.0, 0.6, 8.0, dt);
    let u: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            0.5 + 0.08 * (2.0 * std::f64::consts::PI * 0.31 * t).sin()
                + 0.06 * (2.0 * std::f64::consts::PI * 1.13 * t + 1.0).sin()
                + 0.04 * (2.0 * std::f64::consts::PI * 2.7 * t + 2.0).sin()
        })
        .collect();
    let mut seed: u64 = 12345;
    let y: Vec<f64> = p.simulate(&u, 0.4)[0]
        .iter()
        .map(|v| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            v + 0.005 * (((seed >> 33) as f64 / (1u64 << 31) as f64) - 0.5)
        })
        .collect();
    let mut text = String::from("t_s,throttle,thrust_N\n");
    for k in 0..n {
        text.push_str(&format!("{:.4},{:.6},{:.6}\n", k as f64 * dt, u[k], y[k]));
    }
    (text, u, y)
}

fn json(out: &str) -> Value {
    serde_json::from_str(out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

#[test]
fn compare_on_diagnoses_held_out_part_reproduces_its_figure() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _, _) = multisine_csv(3000);
    let full = dir.path().join("full.csv");
    std::fs::write(&full, &text).unwrap();
    let model = dir.path().join("m.json");
    let (code, out, err) = propid(&[
        "diagnose",
        full.to_str().unwrap(),
        "--json",
        "--save",
        model.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let d = json(&out);
    assert_eq!(d["validation"]["method"], "holdout", "{out}");
    let figure = d["validation"]["mean_fit_percent"].as_f64().unwrap();
    let start = d["split"]["validation"][0].as_u64().unwrap() as usize;
    // DATA: the held-out rows only (header kept).
    let lines: Vec<&str> = text.lines().collect();
    let tail = std::iter::once(lines[0])
        .chain(lines[1 + start..].iter().copied())
        .collect::<Vec<_>>()
        .join("\n");
    let data = dir.path().join("tail.csv");
    std::fs::write(&data, tail + "\n").unwrap();
    let (code, out, err) = propid(&[
        "compare",
        model.to_str().unwrap(),
        data.to_str().unwrap(),
        "--init-samples",
        "20",
        "--json",
        "--report",
        dir.path().join("r").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let c = json(&out);
    assert_eq!(c["init_samples"], 20);
    let o = &c["outputs"][0];
    assert_eq!(o["name"], "thrust_N");
    assert_eq!(o["unit"], "N");
    let fit = o["fit_percent"].as_f64().unwrap();
    assert!(
        (fit - figure).abs() <= 0.01 * figure.abs(),
        "compare {fit} % against diagnose's held-out {figure} %"
    );
    assert!(o["rms"].as_f64().unwrap() < 0.05, "{o}");
    assert!(dir.path().join("r/compare.svg").exists());

    // simulate: the simulated outputs as CSV, one row per sample.
    let (code, out, err) = propid(&[
        "simulate",
        model.to_str().unwrap(),
        "--input",
        full.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let rows: Vec<&str> = out.lines().collect();
    assert_eq!(rows[0], "t_s,throttle,thrust_N");
    assert_eq!(rows.len(), 3001);
}

#[test]
fn a_tampered_foreign_or_unfitting_model_is_refused_with_its_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _, y) = multisine_csv(1500);
    let full = dir.path().join("full.csv");
    std::fs::write(&full, &text).unwrap();
    let model = dir.path().join("m.json");
    let (code, _, err) = propid(&[
        "diagnose",
        full.to_str().unwrap(),
        "--save",
        model.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let saved = std::fs::read_to_string(&model).unwrap();
    let run = |m: &str, data: &std::path::Path| {
        let path = dir.path().join("edited.json");
        std::fs::write(&path, m).unwrap();
        propid(&["compare", path.to_str().unwrap(), data.to_str().unwrap()])
    };
    // The file as saved compares.
    assert_eq!(run(&saved, &full).0, 0);
    // One number changed: tampered.
    let v: Value = serde_json::from_str(&saved).unwrap();
    let gain = v["extended"]["core"]["gain"].as_f64().unwrap();
    let tampered = saved.replacen(
        &format!("\"gain\": {}", Value::from(gain)),
        &format!("\"gain\": {}", gain * 1.01),
        1,
    );
    assert_ne!(tampered, saved);
    let (code, _, err) = run(&tampered, &full);
    assert_eq!(code, 9, "{err}");
    assert!(err.contains("checksum"), "{err}");
    // Another schema.
    let (code, _, err) = run(&saved.replace("propid-model/1", "propid-model/7"), &full);
    assert_eq!(code, 9, "{err}");
    assert!(err.contains("propid-model/7"), "{err}");
    // DATA without the model's input.
    let no_input = dir.path().join("no_input.csv");
    let mut t = String::from("t_s,thrust_N\n");
    for (k, v) in y.iter().enumerate() {
        t.push_str(&format!("{:.4},{v:.6}\n", k as f64 * 0.01));
    }
    std::fs::write(&no_input, t).unwrap();
    let (code, _, err) = run(&saved, &no_input);
    assert_eq!(code, 10, "{err}");
    assert!(err.contains("lacks what the model needs"), "{err}");
}

#[test]
fn params_of_a_tyto_export_give_what_its_stand_supports() {
    let dir = tempfile::tempdir().unwrap();
    let d = dialects()
        .into_iter()
        .find(|d| d.name == "tyto_1585_kgf")
        .unwrap();
    let file = dir.path().join("tyto.csv");
    std::fs::write(&file, &d.text).unwrap();
    let model = dir.path().join("m.json");
    let mut args = vec![
        "identify",
        file.to_str().unwrap(),
        "--json",
        "--save",
        model.to_str().unwrap(),
    ];
    args.extend(d.expect.args.iter().copied());
    let (code, out, err) = propid(&args);
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    assert!(v["params"]["ardupilot"].is_array(), "{}", v["params"]);
    // Gazebo: torque = 0.02 m × thrust on this stand.
    let (code, out, err) = propid(&["params", model.to_str().unwrap(), "--for", "gazebo"]);
    assert_eq!(code, 0, "{err}");
    let line = out
        .lines()
        .find(|l| l.contains("<momentConstant>"))
        .unwrap_or_else(|| panic!("{out}"));
    let k: f64 = line
        .trim()
        .trim_start_matches("<momentConstant>")
        .trim_end_matches("</momentConstant>")
        .parse()
        .unwrap();
    assert!((k - 0.02).abs() < 1e-3, "{k}");
    // ArduPilot: the staircase tops out at throttle 0.7, below MOT_SPIN_MAX: no expo, with
    // the reason; the 4S supply gives the battery limits.
    let (code, out, err) = propid(&[
        "params",
        model.to_str().unwrap(),
        "--for",
        "ardupilot",
        "--auw-kg",
        "1.0",
        "--motors",
        "4",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.lines().any(|l| l == "MOT_BAT_VOLT_MAX,16.8"), "{out}");
    assert!(out.lines().any(|l| l.starts_with("MOT_SPIN_MIN,")), "{out}");
    assert!(
        !out.lines().any(|l| l.starts_with("MOT_THST_EXPO,")),
        "{out}"
    );
    assert!(
        out.contains("# MOT_THST_EXPO: the record's highest steady command"),
        "{out}"
    );
    // The linear model compares on its own record.
    let mut args = vec![
        "compare",
        model.to_str().unwrap(),
        file.to_str().unwrap(),
        "--json",
    ];
    args.extend(d.expect.args.iter().copied());
    let (code, out, err) = propid(&args);
    assert_eq!(code, 0, "{err}");
    let fit = json(&out)["outputs"][0]["fit_percent"].as_f64().unwrap();
    assert!(fit > 80.0, "{out}");
}
