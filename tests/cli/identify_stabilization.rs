//! `identify --json`'s `"stabilization"`, `identify --report DIR` and the diagram in
//! `diagnose --report DIR` (issue 13, item 3), with the real binary on a pulse CSV.

use crate::support::propid;
use propid_testkit as core_support;

use std::path::{Path, PathBuf};

use core_support::{add_noise, throttle, Plant};
use serde_json::Value;

/// `t_s,throttle_pct,thrust_N` of 5 one-sample pulses through `plant` (200 Hz), noise `sd`.
fn pulse_csv(dir: &Path, plant: &Plant, sd: f64) -> PathBuf {
    let spec: Vec<_> = (0..5)
        .map(|i| (100 + 400 * i, 1, [0.05, -0.1, 0.02][i % 3]))
        .collect();
    let u = throttle(2400, &[(0, 0.4)], &spec);
    let mut y = plant.simulate(&u, 3.0).remove(0);
    if sd > 0.0 {
        add_noise(&mut y, sd, 9);
    }
    let mut text = String::from("t_s,throttle_pct,thrust_N\n");
    for k in 0..u.len() {
        text.push_str(&format!(
            "{},{},{}\n",
            k as f64 * plant.dt,
            100.0 * u[k],
            y[k]
        ));
    }
    let path = dir.join("pulses.csv");
    std::fs::write(&path, text).unwrap();
    path
}

fn poles(s: &Value) -> usize {
    s["orders"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["poles"].as_array().unwrap().len())
        .sum()
}

#[test]
fn json_carries_the_diagram_and_the_report_draws_one_circle_per_pole() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005);
    let f = pulse_csv(dir.path(), &plant, 0.0);
    let report = dir.path().join("report");
    // Dense SVD: the Lanczos (truncated) SVD of noise-free data has no triplets beyond their
    // rank (σ = 0 exactly), and the diagram ends there.
    let (code, out, err) = propid(&[
        "identify",
        f.to_str().unwrap(),
        "--svd",
        "dense",
        "--json",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).expect("one JSON object");
    assert_eq!(v["model"]["order"], 2);
    let s = &v["stabilization"];
    assert_eq!(s["n_max"], 12, "2 · 2 + 8: {s}");
    assert_eq!(s["model_order"], 2);
    assert_eq!(s["criteria"]["freq_rel"], 0.01);
    assert_eq!(s["criteria"]["zeta_rel"], 0.05);
    assert_eq!(s["singular_values"].as_array().unwrap().len(), 12);
    let orders = s["orders"].as_array().unwrap();
    assert_eq!(orders.len(), 12);
    for (i, o) in orders.iter().enumerate() {
        assert_eq!(o["order"], i + 1);
        let at_fn = o["poles"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|p| {
                p["stable"] == true && (p["fn_hz"].as_f64().unwrap() / 10.0 - 1.0).abs() < 1e-6
            })
            .count();
        assert_eq!(at_fn, usize::from(i >= 1), "order {}: {o}", i + 1);
    }
    let svg = std::fs::read_to_string(report.join("stabilization.svg")).unwrap();
    assert!(svg.trim_start().starts_with("<svg"), "{}", &svg[..60]);
    assert!(svg.trim_end().ends_with("</svg>"));
    assert_eq!(
        svg.matches("<circle").count(),
        poles(s),
        "one circle per pole"
    );
    let filled = svg
        .lines()
        .filter(|l| l.starts_with("<circle") && !l.contains("fill=\"none\""))
        .count();
    let stable = orders
        .iter()
        .flat_map(|o| o["poles"].as_array().unwrap())
        .filter(|p| p["stable"] == true)
        .count();
    assert_eq!(filled, stable, "filled circles are the stable poles");
    let md = std::fs::read_to_string(report.join("identify.md")).unwrap();
    assert!(
        md.contains("](stabilization.svg)") && md.contains("11 of 12 orders"),
        "{md}"
    );
    // The human summary has its line.
    let (code, out, _) = propid(&["identify", f.to_str().unwrap(), "--svd", "dense"]);
    assert_eq!(code, 0);
    let line = out
        .lines()
        .find(|l| l.starts_with("stability"))
        .expect(&out);
    assert!(
        line.contains("11 of 12 orders") && line.ends_with(": 2-12"),
        "{line}"
    );
}

#[test]
fn diagnose_report_draws_the_diagram_of_its_era_start_and_its_json_is_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005);
    let f = pulse_csv(dir.path(), &plant, 0.002);
    let report = dir.path().join("report");
    let (code, out, err) = propid(&[
        "diagnose",
        f.to_str().unwrap(),
        "--json",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).expect("one JSON object");
    assert!(v["baseline"]["core_model"].is_object(), "an ERA start: {v}");
    assert!(v.get("stabilization").is_none() && v["baseline"].get("stabilization").is_none());
    let svg = std::fs::read_to_string(report.join("stabilization.svg")).unwrap();
    assert!(svg.trim_start().starts_with("<svg"));
    assert!(
        svg.matches("<circle").count() >= 12,
        "a pole per order at least"
    );
    let md = std::fs::read_to_string(report.join("index.md")).unwrap();
    assert!(md.contains("](stabilization.svg)"), "{md}");
}
