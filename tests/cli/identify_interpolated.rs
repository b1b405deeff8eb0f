//! A slow load cell that the stand software interpolated onto every row (readings every ten
//! rows, the rows between on the straight line joining them): the values are kept and marked as
//! not read (`src/ingest/interpolated.rs`), so that what needs the readings themselves gets
//! them — the noise floor of `diagnose` (zero second differences on a line) and the outlier
//! rule (a reading's own noise is a kink among zero residuals). The same readings written with
//! empty cells between give the same diagnosis.

use std::path::Path;

use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde_json::Value;

use crate::support::propid;

/// Rows per load-cell reading.
const EVERY: usize = 10;
/// The readings' noise, N.
const SIGMA_N: f64 = 0.01;

/// The stand's readings: a staircase (3 s per level at 100 rows per second) through a
/// first-order lag (τ 0.12 s) to 0.4 N at full throttle, read every [`EVERY`] rows with
/// Gaussian noise of [`SIGMA_N`]; `None` on the rows between readings.
fn readings() -> (Vec<f64>, Vec<Option<f64>>) {
    let levels = [0.2, 0.5, 0.35, 0.7, 0.45];
    let u: Vec<f64> = levels
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(300))
        .collect();
    let a = (-0.01f64 / 0.12).exp();
    let noise = Normal::new(0.0, SIGMA_N).unwrap();
    let mut rng = StdRng::seed_from_u64(11);
    let mut x = 0.4 * u[0];
    let y = u
        .iter()
        .enumerate()
        .map(|(k, &uk)| {
            x = a * x + (1.0 - a) * 0.4 * uk;
            (k % EVERY == 0).then(|| x + noise.sample(&mut rng))
        })
        .collect();
    (u, y)
}

/// The readings as an export: `interpolated` fills the rows between two readings on the line
/// joining them (the rows after the last reading stay empty), otherwise they are empty cells.
fn write(path: &Path, interpolated: bool) {
    let (u, y) = readings();
    let mut s = String::from("Time (s),Throttle (%),Thrust (N)\n");
    for (k, &uk) in u.iter().enumerate() {
        let (a, b) = (k - k % EVERY, k - k % EVERY + EVERY);
        let cell = match (y[k], interpolated, y.get(b).copied().flatten()) {
            (Some(v), _, _) => format!("{v:?}"),
            (None, true, Some(yb)) => {
                let ya = y[a].unwrap();
                format!("{:?}", ya + (k - a) as f64 / EVERY as f64 * (yb - ya))
            }
            _ => String::new(),
        };
        s.push_str(&format!("{:.2},{},{cell}\n", k as f64 * 0.01, 100.0 * uk));
    }
    std::fs::write(path, s).unwrap();
}

fn json(args: &[&str]) -> Value {
    let (code, out, err) = propid(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    serde_json::from_str(&out).unwrap()
}

#[test]
fn a_load_cell_interpolated_by_the_exporter_is_judged_at_its_readings() {
    let dir = tempfile::tempdir().unwrap();
    let (lined, sparse) = (dir.path().join("lined.csv"), dir.path().join("sparse.csv"));
    write(&lined, true);
    write(&sparse, false);
    let (lined, sparse) = (lined.to_str().unwrap(), sparse.to_str().unwrap());

    let id = json(&["identify", lined, "--json"]);
    let thrust = &id["source"]["csv"]["channels"]["thrust"];
    let rows = thrust["interpolated_rows"].as_u64().unwrap_or(0);
    assert!((1300..1350).contains(&rows), "{thrust}");
    assert_eq!(id["source"]["outliers"], 0, "no reading is a spike");
    let (code, out, _) = propid(&["identify", lined]);
    assert_eq!(code, 0);
    assert!(out.contains("interpolated by the exporter"), "{out}");

    let d = json(&["diagnose", lined, "--json"]);
    assert_eq!(d["source"]["outliers"], 0, "{}", d["source"]);
    let floor = d["noise_floor"]["rms"].as_f64().unwrap();
    assert!(
        (floor / SIGMA_N - 1.0).abs() < 0.25,
        "the readings' noise {SIGMA_N}, not the lines': {}",
        d["noise_floor"]
    );
    // Empty cells between the same readings: the same samples read, the same floor.
    let ds = json(&["diagnose", sparse, "--json"]);
    assert_eq!(ds["noise_floor"], d["noise_floor"]);
    assert_eq!(ds["source"]["outliers"], 0);
}
