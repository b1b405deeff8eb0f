//! `diagnose --json` (in memory, [`super::read`]) on a stand export in its own units: the findings are in canonical units
//! (newtons for a thrust logged in gram-force), and `source` says which column was read in
//! which unit with what factor, and the command's scale, with `identify`'s names (`units`,
//! `input_range`, `input_range_from`), so that a reader can convert a finding back to the
//! file's units. And an effect hidden in the export itself, as a user would hide it (the
//! thrust column shifted by whole rows, its empty cells with it), is found on top of what the
//! clean export shows.

use propid_sim::plant::{Plant, PlantConfig};

use super::read::{diagnose_json as json_of, How};

const DT_S: f64 = 0.005;
const LEVELS: [f64; 5] = [0.3, 0.45, 0.6, 0.75, 0.5];
/// gram-force in newtons.
const GF: f64 = 0.00980665;

/// What [`export`] writes beside the simulated staircase.
#[derive(Clone, Copy, Default)]
struct Hidden {
    /// The thrust on every `every`-th row only (empty cells between the load cell's
    /// readings); 0 or 1: every row.
    every: usize,
    /// Its cells moved this many rows later.
    late: usize,
    /// A sinusoid added to the thrust: frequency, Hz, and amplitude, gf.
    sine: Option<(f64, f64)>,
}

/// A Tyto-style export of a simulated staircase (`Time (s)`, `ESC signal (µs)`, `Thrust (gf)`)
/// with `hidden` in it.
fn export(hidden: Hidden) -> String {
    let cfg = PlantConfig {
        noise_rms_n: 0.01,
        ..PlantConfig::default()
    };
    let mut plant = Plant::new(&cfg, DT_S, 5).unwrap();
    plant.settle(LEVELS[0]);
    let per = (1.5 / DT_S) as usize;
    let mut rows = Vec::new();
    for (i, &u) in LEVELS.iter().enumerate() {
        for k in 0..per {
            let n = i * per + k;
            let t = n as f64 * DT_S;
            let sine = hidden
                .sine
                .map_or(0.0, |(f, a)| a * (std::f64::consts::TAU * f * t).sin());
            let thrust_gf = plant.step(u).thrust_n / GF + sine;
            let cell = if n % hidden.every.max(1) == 0 {
                format!("{thrust_gf:.2}")
            } else {
                String::new()
            };
            rows.push((t, 1000.0 + 1000.0 * u, cell));
        }
    }
    let mut s = String::from("Time (s),ESC signal (µs),Thrust (gf)\n");
    for k in 0..rows.len() {
        let cell = &rows[k.saturating_sub(hidden.late)].2;
        s.push_str(&format!("{:.3},{:.0},{cell}\n", rows[k].0, rows[k].1));
    }
    s
}

/// `diagnose --json` of the export `text`.
fn diagnose_json(text: &str) -> serde_json::Value {
    json_of("export.csv", text.as_bytes(), How::default())
}

/// `dead_time`'s `delay_samples` in `diagnose --json` of `text`, if named.
fn delay_of(text: &str) -> Option<f64> {
    diagnose_json(text)["findings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["effect"] == "dead_time")
        .and_then(|f| f["delay_samples"].as_f64())
}

#[test]
fn a_delay_hidden_in_a_sparse_export_is_found_on_top_of_its_own() {
    let sparse = Hidden {
        every: 3,
        ..Hidden::default()
    };
    let own = delay_of(&export(sparse)).unwrap_or(0.0);
    for late in [3, 6] {
        let got = delay_of(&export(Hidden { late, ..sparse }));
        assert!(
            got.is_some_and(|d| (d - own - late as f64).abs() <= 1.0),
            "{late} rows hidden on top of {own}: {got:?}"
        );
    }
}

#[test]
fn a_sinusoid_in_a_gram_force_export_is_published_in_newtons_with_the_columns_units() {
    let (freq_hz, amplitude_gf) = (7.3, 6.0);
    let s = export(Hidden {
        sine: Some((freq_hz, amplitude_gf)),
        ..Hidden::default()
    });
    let v = diagnose_json(&s);
    let src = &v["source"];
    assert_eq!(src["format"], "csv");
    assert_eq!(src["input"], "ESC signal (µs)");
    assert_eq!(src["output"], "Thrust (gf)");
    assert_eq!(src["units"]["thrust"]["unit"], "gf");
    assert_eq!(src["units"]["thrust"]["factor"].as_f64(), Some(GF));
    assert_eq!(src["input_range"], serde_json::json!([1000.0, 2000.0]));
    assert_eq!(src["input_range_from"], "header: µs");
    assert!((src["rate_hz"].as_f64().unwrap() - 1.0 / DT_S).abs() < 1e-6);
    let rows = s.lines().count() - 1;
    assert_eq!(src["samples"].as_u64(), Some(rows as u64));
    let periodic = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["effect"] == "periodic_disturbance")
        .unwrap_or_else(|| panic!("no sinusoid named: {}", v["findings"]));
    let f = periodic["freq_hz"].as_f64().unwrap();
    let a = periodic["amplitude"].as_f64().unwrap();
    assert!((f / freq_hz - 1.0).abs() < 0.01, "{f} Hz");
    assert!(
        (a / (amplitude_gf * GF) - 1.0).abs() < 0.15,
        "{a} N, {} N hidden ({amplitude_gf} gf)",
        amplitude_gf * GF
    );
}
