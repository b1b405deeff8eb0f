//! A slow load cell written on every row as its last reading, repeated (Bitcraze's system-ID
//! deck logs its thrust this way: one new value in ten rows): read at its own rate, the
//! repeats taken as cells not updated (`src/ingest/held.rs`), instead of as a staircase that
//! lags by half its period; and a command logged only where it changes, held until the next
//! change instead of interpolated into ramps.

use std::path::Path;

use serde_json::Value;

use crate::support::propid;

/// Rows per load-cell reading.
const HOLD_ROWS: usize = 10;
/// The stand's dead time, rows (at 100 rows per second).
const DEAD_ROWS: usize = 5;
/// Its time constant, s.
const TAU_S: f64 = 0.15;
const DT_S: f64 = 0.01;

/// A staircase of throttle levels (2 s each) through a dead time and a first-order lag,
/// thrust 10 N at full throttle, the load cell read every [`HOLD_ROWS`] rows (at a phase that
/// does not line up with the steps) and its last reading repeated on the rows between; a
/// little deterministic noise on each reading. `time_s,throttle,thrust_N`.
fn write_export(path: &Path) {
    let levels = [0.2, 0.4, 0.6, 0.3, 0.5, 0.7, 0.45];
    let per = 200;
    let u: Vec<f64> = levels
        .iter()
        .flat_map(|&l| std::iter::repeat(l).take(per))
        .collect();
    let a = (-DT_S / TAU_S).exp();
    let mut x = 10.0 * u[0];
    let truth: Vec<f64> = (0..u.len())
        .map(|k| {
            let now = x;
            x = a * x + (1.0 - a) * 10.0 * u[k.saturating_sub(DEAD_ROWS)];
            now
        })
        .collect();
    let mut s = String::from("time_s,throttle,thrust_N\n");
    let mut reading = truth[0];
    for (k, (&uk, &yk)) in u.iter().zip(&truth).enumerate() {
        if k % HOLD_ROWS == 3 {
            reading = yk + 0.002 * (k as f64 * 0.7).sin();
        }
        s.push_str(&format!("{:.2},{uk},{reading:.5}\n", k as f64 * DT_S));
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn a_load_cell_repeating_its_last_reading_is_read_at_its_own_rate() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("held.csv");
    write_export(&csv);
    let (code, out, err) = propid(&["identify", csv.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let thrust = &v["source"]["csv"]["channels"]["thrust"];
    assert_eq!(thrust["held_rows"], HOLD_ROWS, "{thrust}");
    assert!(
        v["source"]["csv"]["channels"]["throttle"]
            .get("held_rows")
            .is_none(),
        "the command holds its levels by design: {}",
        v["source"]["csv"]["channels"]
    );
    // Each step's dead time within half a reading of the stand's: read as a held staircase
    // it came out about half a reading (25 ms) long on every step.
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 6, "{}", v["steps"]);
    let truth = DEAD_ROWS as f64 * DT_S;
    let dead: Vec<f64> = steps
        .iter()
        .map(|s| s["dead_time_s"].as_f64().unwrap_or(f64::NAN))
        .collect();
    let mean = dead.iter().sum::<f64>() / dead.len() as f64;
    assert!(
        (mean - truth).abs() < 0.25 * HOLD_ROWS as f64 * DT_S,
        "mean dead time {mean:.3} s against {truth} s: {dead:?}"
    );
    // The human summary says how the thrust was read.
    let (code, out, err) = propid(&["identify", csv.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("held      thrust repeats each reading for 10 rows: read at its own rate"),
        "{out}"
    );
}

#[test]
fn a_command_logged_on_its_changes_gives_steps_not_ramps() {
    // The throttle written only on the rows where it changes, the thrust on every row: the
    // steps are found at the changes, and the summary says the command was held.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("on_change.csv");
    let a = (-DT_S / TAU_S).exp();
    let levels = [0.2, 0.4, 0.6, 0.3, 0.5];
    let mut x = 10.0 * levels[0];
    let mut s = String::from("time_s,throttle,thrust_N\n");
    for k in 0..1000 {
        let u = levels[k / 200];
        let cmd = if k % 200 == 0 {
            u.to_string()
        } else {
            String::new()
        };
        s.push_str(&format!("{:.2},{cmd},{x:.5}\n", k as f64 * DT_S));
        x = a * x + (1.0 - a) * 10.0 * u;
    }
    std::fs::write(&csv, s).unwrap();
    let (code, out, err) = propid(&["identify", csv.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let steps = v["steps"].as_array().unwrap();
    let at: Vec<f64> = steps.iter().map(|s| s["t_s"].as_f64().unwrap()).collect();
    assert_eq!(at.len(), 4, "{at:?}");
    for (i, t) in at.iter().enumerate() {
        assert!((t - 2.0 * (i + 1) as f64).abs() < 0.015, "{at:?}");
    }
    for s in steps {
        let tau = s["time_constant_s"].as_f64().unwrap();
        assert!((tau / TAU_S - 1.0).abs() < 0.1, "{s}");
    }
    assert_eq!(v["source"]["missing"], 0, "{}", v["source"]);
    let (code, out, err) = propid(&["identify", csv.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("held      throttle written only where it changes: 995 empty cells"),
        "{out}"
    );
}
