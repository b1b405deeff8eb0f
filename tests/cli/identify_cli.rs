//! `propid identify` as a user runs it: the real binary on small CSV files in a temp dir.

use crate::support::propid;
use propid_testkit as core_support;

use std::path::{Path, PathBuf};

use core_support::Plant;
use rand::{Rng, SeedableRng};
use serde_json::Value;

/// Writes `t_s,throttle_pct,thrust_N[,rpm]` rows for `u` through `plant`.
fn write_csv(dir: &Path, name: &str, plant: &Plant, u: &[f64]) -> PathBuf {
    let y = plant.simulate(u, 1.5);
    let mut text = String::from("t_s,throttle_pct,thrust_N");
    if y.len() > 1 {
        text.push_str(",rpm");
    }
    text.push('\n');
    for k in 0..u.len() {
        text.push_str(&format!(
            "{},{},{}",
            k as f64 * plant.dt,
            100.0 * u[k],
            y[0][k]
        ));
        if y.len() > 1 {
            text.push_str(&format!(",{}", y[1][k]));
        }
        text.push('\n');
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn random_u(n: usize) -> Vec<f64> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    (0..n)
        .map(|_| 0.4 + 0.05 * rng.gen_range(-1.0..1.0))
        .collect()
}

fn json(args: &[&str]) -> Value {
    let (code, out, err) = propid(args);
    assert_eq!(code, 0, "stderr: {err}");
    assert_eq!(out.lines().count(), 1, "exactly one JSON line: {out}");
    serde_json::from_str(&out).expect("valid JSON")
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

#[test]
fn random_throttle_csv_takes_the_okid_path_and_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(12.0, 0.35, 6.0, 0.002);
    let f = write_csv(dir.path(), "random.csv", &plant, &random_u(1500));
    let v = json(&["identify", f.to_str().unwrap(), "--json"]);
    let m = &v["model"];
    assert_eq!(m["order"], 2);
    assert!(rel(m["fn_hz"].as_f64().unwrap(), 12.0) < 1e-6, "{m}");
    assert!(rel(m["zeta"].as_f64().unwrap(), 0.35) < 1e-6);
    assert!(rel(m["dc_gain"].as_f64().unwrap(), plant.dc(0)) < 1e-6);
    let s = &v["source"];
    assert_eq!(s["path"], "okid");
    assert_eq!(s["format"], "csv");
    assert_eq!(s["input"], "throttle_pct");
    assert_eq!(s["outputs"][0], "thrust_N");
    assert!((s["rate_hz"].as_f64().unwrap() - 500.0).abs() < 1e-6);
    assert!(s["okid"]["observer_order"].as_u64().unwrap() >= 2);
    for key in [
        "poles_s",
        "poles_z",
        "a",
        "b",
        "c",
        "d",
        "singular_values",
        "indicators",
    ] {
        assert!(m.get(key).is_some(), "model.{key}");
    }
}

#[test]
fn two_outputs_give_a_dc_gain_list() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(8.0, 0.6, 4.0, 0.002).with_output([900.0, 2.0], 0.0);
    let f = write_csv(dir.path(), "two.csv", &plant, &random_u(1500));
    let v = json(&[
        "identify",
        f.to_str().unwrap(),
        "--json",
        "--output",
        "thrust_N",
        "--output",
        "rpm",
    ]);
    let g = v["model"]["dc_gain"]
        .as_array()
        .expect("a list for two outputs");
    assert_eq!(g.len(), 2);
    assert!(rel(g[1].as_f64().unwrap(), plant.dc(1)) < 1e-6);
}

#[test]
fn pulse_experiment_takes_the_pulse_path() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(10.0, 0.3, 5.0, 0.002);
    let mut u = vec![0.4; 3000];
    for s in (100..3000).step_by(400) {
        u[s] = 0.45;
    }
    let f = write_csv(dir.path(), "pulses.csv", &plant, &u);
    // Noiseless: the automatic order is 3, the third pole at s ≈ 0 (±1e-7 rad/s, rounding
    // decides the sign) with a meaningless DC gain (jackknife sd 1e3..1e4); the quality checks
    // reject that model (exit 4, identify_quality.rs). The path is the question here.
    let v = json(&["identify", f.to_str().unwrap(), "--json", "--order", "2"]);
    assert_eq!(v["quality"]["accepted"], true, "{v}");
    assert_eq!(v["source"]["path"], "pulse");
    assert!(v["source"].get("okid").is_none());
    assert!(v["model"]["pulses"].as_u64().unwrap() >= 5);
}

#[test]
fn staircase_publishes_operating_points() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(6.0, 0.7, 3.0, 0.004);
    let u: Vec<f64> = (0..2000).map(|k| 0.2 + 0.1 * (k / 400) as f64).collect();
    let f = write_csv(dir.path(), "stairs.csv", &plant, &u);
    let v = json(&["identify", f.to_str().unwrap(), "--json", "--order", "2"]);
    let ops = &v["operating_points"];
    assert_eq!(ops["kind"], "staircase");
    let pts = ops["points"].as_array().unwrap();
    assert_eq!(pts.len(), 4, "levels 2..5 have a step into them: {ops}");
    for p in pts {
        assert!(rel(p["fn_hz"].as_f64().unwrap(), 6.0) < 1e-6, "{p}");
        assert!(rel(p["dc_gain"].as_f64().unwrap(), plant.dc(0)) < 1e-6);
    }
    assert_eq!(
        ops["skipped"].as_array().unwrap().len(),
        1,
        "the first level"
    );
    let (_, human, _) = propid(&["identify", f.to_str().unwrap(), "--order", "2"]);
    assert!(human.contains("operating points (staircase)"), "{human}");
    assert!(human.contains("path      OKID"), "{human}");
}

#[test]
fn response_only_step_record_finds_the_steps() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(5.0, 1.3, 1.0, 0.02);
    let u: Vec<f64> = (0..300)
        .map(|k| if (100..200).contains(&k) { 0.8 } else { 0.3 })
        .collect();
    let y = plant.simulate(&u, 0.0);
    let text: String = y[0]
        .iter()
        .enumerate()
        .map(|(k, v)| format!("{},{}\n", 0.02 * k as f64, v))
        .collect();
    let f = dir.path().join("steps.csv");
    std::fs::write(&f, text).unwrap();
    let v = json(&[
        "identify",
        f.to_str().unwrap(),
        "--json",
        "--columns",
        "t_s,load",
        "--output",
        "load",
        "--input",
        "none",
    ]);
    let s = &v["source"];
    assert_eq!(s["input"], "steps found from the response");
    let steps = s["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2);
    assert_eq!(steps[0]["sample"], 100);
    assert_eq!(steps[1]["sample"], 200);
    let taus = v["model"]["time_constants_s"].as_array().unwrap();
    assert!(!taus.is_empty(), "an overdamped plant has time constants");
}

#[test]
fn errors_map_to_exit_codes() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    let (code, _, err) = propid(&["identify", empty.to_str().unwrap()]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("empty"), "{err}");
    let nothrust = dir.path().join("nothrust.csv");
    std::fs::write(&nothrust, "t_s,throttle,torque_Nm\n0,1,2\n0.1,1,2\n").unwrap();
    let (code, _, err) = propid(&["identify", nothrust.to_str().unwrap()]);
    assert_eq!(code, 3);
    assert!(err.contains("torque_Nm"), "{err}");
    let flat = dir.path().join("flat.csv");
    let rows: String = (0..200)
        .map(|k| format!("{},{},2.0\n", k as f64 * 0.01, 3000 + (k % 7) * 10))
        .collect();
    std::fs::write(&flat, format!("t_s,throttle,thrust_N\n{rows}")).unwrap();
    let (code, _, err) = propid(&["identify", flat.to_str().unwrap()]);
    assert_eq!(code, 4, "constant thrust: {err}");
    let (code, _, _) = propid(&["identify", "/nonexistent/file.csv"]);
    assert_eq!(code, 7);
    let (code, _, _) = propid(&["identify", flat.to_str().unwrap(), "--svd", "fast"]);
    assert_eq!(code, 2);
}

#[test]
fn tsp1_binary_recording_is_identified() {
    use propid_wire::protocol::encode_frame;
    use propid_wire::protocol::message::{Message, Sample, SampleFlags};
    let plant = Plant::new(15.0, 0.3, 6.0, 0.001);
    let mut rng = rand::rngs::StdRng::seed_from_u64(9);
    let levels: Vec<u16> = (0..2000).map(|_| rng.gen_range(3500..4500)).collect();
    let u: Vec<f64> = levels.iter().map(|&l| f64::from(l) / 1e4).collect();
    let y = plant.simulate(&u, 2.0);
    let mut bytes = Vec::new();
    let mut buf = [0u8; 300];
    for (k, &level) in levels.iter().enumerate() {
        let s = Sample {
            sample_index: k as u32,
            t_us: 1000 * k as u32,
            throttle: level,
            flags: SampleFlags::ARMED | SampleFlags::THRUST_VALID,
            thrust_n: y[0][k] as f32,
            torque_nm: f32::NAN,
            rpm: f32::NAN,
            voltage_v: f32::NAN,
            current_a: f32::NAN,
        };
        let n = encode_frame(k as u16, &Message::Sample(s), &mut buf);
        bytes.extend_from_slice(&buf[..n]);
    }
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("run.tsp");
    std::fs::write(&f, bytes).unwrap();
    let v = json(&["identify", f.to_str().unwrap(), "--json", "--order", "2"]);
    assert_eq!(v["source"]["format"], "tsp1");
    assert_eq!(v["source"]["path"], "okid");
    assert_eq!(v["source"]["samples"], 2000);
    let m = &v["model"];
    assert!(rel(m["fn_hz"].as_f64().unwrap(), 15.0) < 1e-3, "{m}");
    assert!(rel(m["zeta"].as_f64().unwrap(), 0.3) < 1e-2, "{m}");
}

/// A recording of the simulated stand's experiment plan (levels reached by ramps, pulses at each
/// level) is a clean pulse experiment: the pulse path, one model per level.
#[test]
fn simulated_stand_recording_takes_the_pulse_path() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("run.tsp");
    // the 2nd-order plant named (config/sim.toml is the motor, whose fn/zeta vary)
    let cfg = crate::support::second_order_sim(dir.path());
    let (code, _, err) = propid(&[
        "sim",
        "--config",
        &cfg,
        "--record",
        rec.to_str().unwrap(),
        "--seconds",
        "20",
    ]);
    assert_eq!(code, 0, "{err}");
    let plant = propid_sim::plant::PlantConfig::default();
    let (fn_true, zeta_true) = (plant.fn_hz, plant.zeta);
    let v = json(&["identify", rec.to_str().unwrap(), "--json"]);
    assert_eq!(v["source"]["path"], "pulse");
    let m = &v["model"];
    assert!(rel(m["fn_hz"].as_f64().unwrap(), fn_true) < 0.1, "{m}");
    assert!(rel(m["zeta"].as_f64().unwrap(), zeta_true) < 0.2, "{m}");
    let pts = v["operating_points"]["points"].as_array().unwrap();
    assert!(
        pts.iter().filter(|p| p["path"] == "pulse").count() >= 3,
        "{pts:?}"
    );
}

/// A staircase up and down through a first-order motor (τ 60 ms up, 120 ms down: spin-down is
/// slower), a 20 ms dead time and a quadratic thrust map: `identify --json` reports every
/// step's figures and the static map, and the human summary shows them as tables.
#[test]
fn a_staircase_reports_its_steps_and_static_map() {
    let dt = 0.005;
    let levels = [0.2, 0.35, 0.5, 0.65, 0.8, 0.5, 0.3];
    let u: Vec<f64> = levels
        .iter()
        .flat_map(|&v| std::iter::repeat(v).take(400))
        .collect();
    let (delay, kmap) = (4, 12.0);
    let mut y = vec![0.0; u.len()];
    let mut x = kmap * levels[0] * levels[0];
    for k in 0..u.len() {
        let target = kmap * u[k.saturating_sub(delay)].powi(2);
        let tau: f64 = if target >= x { 0.06 } else { 0.12 };
        x += (target - x) * (1.0 - (-dt / tau).exp());
        // 0.5 mN of deterministic ripple, as a load cell shows
        y[k] = x + 5e-4 * ((k * 37 % 11) as f64 / 5.0 - 1.0);
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("staircase.csv");
    let rows: String = (0..u.len())
        .map(|k| format!("{},{},{}\n", k as f64 * dt, 100.0 * u[k], y[k]))
        .collect();
    std::fs::write(&path, format!("t_s,throttle_pct,thrust_N\n{rows}")).unwrap();
    let v = json(&["identify", "--json", path.to_str().unwrap()]);
    let steps = v["steps"].as_array().expect("steps");
    assert_eq!(steps.len(), levels.len() - 1);
    for (i, s) in steps.iter().enumerate() {
        let (from, to) = (levels[i], levels[i + 1]);
        assert!((s["from"].as_f64().unwrap() - from).abs() < 1e-9, "{s}");
        assert!((s["to"].as_f64().unwrap() - to).abs() < 1e-9, "{s}");
        let up = to > from;
        assert_eq!(s["direction"], if up { "up" } else { "down" });
        let tau = s["time_constant_s"].as_f64().unwrap();
        let want = if up { 0.06 } else { 0.12 };
        assert!(
            (tau - want).abs() < 0.15 * want,
            "step {i}: τ {tau} vs {want}"
        );
        let dead = s["dead_time_s"].as_f64().unwrap();
        assert!(
            (dead - delay as f64 * dt).abs() <= 1.5 * dt,
            "step {i}: θ {dead}"
        );
        assert_eq!(s["resolvable"], true);
        assert!(s["rise_10_90_s"].as_f64().unwrap() > 0.0);
        // No overshoot: 0, or a bound within the ripple (`overshoot_below_pct`).
        let over = s["overshoot_pct"].as_f64();
        let below = s["overshoot_below_pct"].as_f64();
        assert!(over.or(below).unwrap() < 1.0, "{s}");
    }
    let thrust = &v["static_map"]["thrust"];
    assert_eq!(thrust["unit"], "N");
    let lv = thrust["levels"].as_array().unwrap();
    assert_eq!(lv.len(), levels.len());
    for l in lv {
        let u = l["throttle"].as_f64().unwrap();
        assert!(
            (l["mean"].as_f64().unwrap() - kmap * u * u).abs() < 2e-3,
            "{l}"
        );
    }
    let p = &thrust["power"];
    assert!((p["exponent"].as_f64().unwrap() - 2.0).abs() < 0.05, "{p}");
    assert!(p["uncertainty"]["exponent"].as_f64().unwrap() > 0.0);
    let e = &thrust["expo"];
    assert!((e["a"].as_f64().unwrap() - 1.0).abs() < 0.02, "{e}");
    assert!((e["t_max"].as_f64().unwrap() - kmap).abs() < 0.1, "{e}");
    let (code, human, _) = propid(&["identify", path.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert!(human.contains("steps (6):"), "{human}");
    assert!(
        human.contains("static map: thrust (N) over 7 levels"),
        "{human}"
    );
}

/// A record without steps (random input) has empty `steps` and `static_map`.
#[test]
fn random_input_has_no_steps_and_no_static_map() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(12.0, 0.4, 5.0, 0.002);
    let path = write_csv(dir.path(), "random.csv", &plant, &random_u(3000));
    let v = json(&["identify", "--json", path.to_str().unwrap()]);
    assert_eq!(v["steps"].as_array().unwrap().len(), 0);
    assert!(v["static_map"].as_object().unwrap().is_empty());
}

/// Two runs written into one file, the second with its own header line and a clock that starts
/// again: the rows that cannot be read are not lost in silence — the summary says how many rows
/// were skipped and why, and how many were dropped because their time went back.
#[test]
fn a_second_run_appended_to_a_file_is_said_not_silently_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(6.0, 0.7, 3.0, 0.004);
    let u: Vec<f64> = (0..2000).map(|k| 0.2 + 0.1 * (k / 400) as f64).collect();
    let f = write_csv(dir.path(), "run.csv", &plant, &u);
    let text = std::fs::read_to_string(&f).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let both = format!("{}\n{}\n", lines.join("\n"), lines[..501].join("\n"));
    std::fs::write(&f, both).unwrap();
    let v = json(&["identify", f.to_str().unwrap(), "--json"]);
    let csv = &v["source"]["csv"];
    assert_eq!(
        csv["skipped"]["not_a_number"], 1,
        "the second header: {csv}"
    );
    assert_eq!(csv["jitter"]["non_increasing"], 500, "{csv}");
    let (_, human, _) = propid(&["identify", f.to_str().unwrap()]);
    assert!(
        human.contains("skipped: 0 with a bad checksum, 1 with text in a number field"),
        "{human}"
    );
    assert!(human.contains("500 rows dropped"), "{human}");
}
