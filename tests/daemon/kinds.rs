//! `[experiment] kind` staircase, ramp and chirp through the real binary against the simulated
//! stand on a pty (a second-order thrust response of known gain and resonance): the typed
//! lines each kind publishes, their figures against the stand's, the replay of the recording
//! publishing the same lines, and the run report.

use crate::browser;
use crate::daemon_http::url_of;
use crate::daemon_proc;

use daemon_proc::{of_type, replay, sim_stand, Daemon};
use serde_json::Value;

/// The config of a run of `kind` with `experiment` keys, for the stand at 1 kHz.
fn config(dir: &std::path::Path, experiment: &str) -> std::path::PathBuf {
    let p = dir.join("propid.toml");
    let text = format!(
        "[device]\nreconnect_initial_ms = 50\nreconnect_max_ms = 200\n\
         [experiment]\nramp_ms = 100\nsettle_ms = 500\n{experiment}"
    );
    std::fs::write(&p, text).unwrap();
    p
}

/// The kinds' lines of a run, in order.
fn kind_lines(lines: &[Value]) -> Vec<Value> {
    lines
        .iter()
        .filter(|l| {
            ["step", "static_map", "frequency_response", "model"]
                .contains(&l["type"].as_str().unwrap_or(""))
        })
        .cloned()
        .collect()
}

/// Runs `experiment` against the stand with `(fn_hz, zeta, gain)`, with `--record` and
/// `--report`; returns the lines, the replay's lines and the report directory.
fn run_kind(
    experiment: &str,
    plant: (f64, f64, f64),
    secs: f64,
) -> (Vec<Value>, Vec<Value>, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(dir.path(), experiment);
    let sim = sim_stand(1000, |c| {
        c.plant.fn_hz = plant.0;
        c.plant.zeta = plant.1;
        c.plant.gain_n_per_throttle = plant.2;
    });
    let port = sim.path().display().to_string();
    let rec = dir.path().join("run.tsp");
    let report = dir.path().join("report");
    let d = Daemon::start(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--port",
        &port,
        "--record",
        rec.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    let (status, lines, err) = d.finish(secs);
    sim.stop().unwrap();
    assert!(status.success(), "{status:?} {err}");
    assert!(
        lines.iter().any(|l| l["kind"] == "plan_finished"),
        "{lines:#?}"
    );
    let replayed = replay(&rec, &cfg);
    (lines, replayed, dir)
}

#[test]
fn a_staircase_maps_the_stands_steady_thrust_and_replays_the_same_lines() {
    let gain = 12.0;
    let (lines, replayed, dir) = run_kind(
        "kind = \"staircase\"\nlevels = [0.3, 0.45, 0.6]\nhold_ms = 1000\n",
        (12.0, 0.7, gain),
        60.0,
    );
    let steps = of_type(&lines, "step");
    // 0.3→0.45→0.6→0.45→0.3 (the start from rest is no step: no hold before it)
    let dirs: Vec<&str> = steps
        .iter()
        .map(|s| s["direction"].as_str().unwrap())
        .collect();
    assert_eq!(dirs, ["up", "up", "down", "down"], "{lines:#?}");
    for s in &steps {
        // the stand's 2nd order at 12 Hz, ζ 0.7: a first-order fit of τ ≈ 15–25 ms
        let tau = s["time_constant_s"].as_f64().unwrap();
        assert!(tau > 0.005 && tau < 0.05, "{s}");
    }
    let maps = of_type(&lines, "static_map");
    let thrust = maps.iter().find(|m| m["output"] == "thrust").unwrap();
    let levels = thrust["levels"].as_array().unwrap();
    let held: Vec<f64> = levels
        .iter()
        .map(|l| l["throttle"].as_f64().unwrap())
        .collect();
    for u in [0.3, 0.45, 0.6] {
        assert!(held.iter().any(|h| (h - u).abs() < 1e-3), "{thrust}");
    }
    for l in levels
        .iter()
        .filter(|l| l["throttle"].as_f64().unwrap() > 0.1)
    {
        let u = l["throttle"].as_f64().unwrap();
        let mean = l["mean"].as_f64().unwrap();
        assert!(
            (mean - gain * u).abs() < 0.03 * gain * u,
            "{l} for {}",
            gain * u
        );
        assert!(l["std"].as_f64().is_some() && l["samples"].as_u64().unwrap() > 100);
    }
    assert!(thrust["directions"]["up"]["time_constant_s"]
        .as_f64()
        .is_some());
    // the replay of the recording publishes the same lines
    assert_eq!(kind_lines(&lines), kind_lines(&replayed));
    let md = std::fs::read_to_string(dir.path().join("report/report.md")).unwrap();
    assert!(
        md.contains("## Steps") && md.contains("## Static map"),
        "{md}"
    );
    // the flight controllers' numbers from the map, with their normalisation
    assert!(
        md.contains("### Flight-controller numbers") && md.contains("`MOT_THST_EXPO`"),
        "{md}"
    );
    for svg in ["thrust_curve.svg", "tau.svg"] {
        let s = std::fs::read_to_string(dir.path().join("report").join(svg)).unwrap();
        assert!(s.starts_with("<svg") || s.contains("<svg"), "{svg}");
    }
    the_page_shows_the_lines(dir.path(), &steps, &maps);
}

/// The rows of the table `id` in a DOM: each row's cells' text.
fn rows(dom: &str, id: &str) -> Vec<Vec<String>> {
    let Some(at) = dom.find(&format!("<table id=\"{id}\"")) else {
        return Vec::new();
    };
    let table = &dom[at..at + dom[at..].find("</table>").unwrap()];
    let Some(body) = table.split("<tbody>").nth(1) else {
        return Vec::new();
    };
    body.split("<tr>")
        .skip(1)
        .map(|tr| {
            tr.split("<td>")
                .skip(1)
                .map(|td| td.split("</td>").next().unwrap().to_string())
                .collect()
        })
        .collect()
}

/// The replay of the run's recording served over HTTP: in Chromium, the page's "Experiment
/// kind" section shows a row per `step` line and per level of each `static_map` line, with
/// their numbers.
fn the_page_shows_the_lines(dir: &std::path::Path, steps: &[&Value], maps: &[&Value]) {
    browser::chromium();
    let (rec, cfg) = (dir.join("run.tsp"), dir.join("propid.toml"));
    let mut d = Daemon::start(&[
        "replay",
        rec.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--http",
        "127.0.0.1:0",
    ]);
    let url = url_of(&mut d);
    d.wait_for(30.0, |l| l["type"] == "stats");
    let levels: usize = maps
        .iter()
        .map(|m| m["levels"].as_array().unwrap().len())
        .sum();
    let dom = browser::dom_when(&url, |dom| rows(dom, "static-map").len() == levels);
    assert!(dom.contains("id=\"kinds-kind\">(staircase)"), "{dom}");
    let shown = rows(&dom, "steps");
    assert_eq!(shown.len(), steps.len(), "{dom}");
    for (row, s) in shown.iter().zip(steps) {
        assert_eq!(row[0], s["index"].to_string());
        assert_eq!(row[4], s["direction"].as_str().unwrap());
        let tau_ms = s["time_constant_s"].as_f64().unwrap() * 1e3;
        assert_eq!(row[6], format!("{tau_ms:.1}"), "{row:?} {s}");
    }
    let want: Vec<(String, String)> = maps
        .iter()
        .flat_map(|m| m["levels"].as_array().unwrap().iter())
        .map(|l| {
            let f = |k: &str, d: usize| format!("{:.d$}", l[k].as_f64().unwrap());
            (f("throttle", 3), f("mean", 4))
        })
        .collect();
    let got: Vec<(String, String)> = rows(&dom, "static-map")
        .into_iter()
        .map(|r| (r[2].clone(), r[3].clone()))
        .collect();
    assert_eq!(got, want, "{dom}");
    d.signal(libc::SIGINT);
    let (status, _, err) = d.finish(10.0);
    assert!(status.success(), "{err}");
}

#[test]
fn a_chirp_finds_the_stands_resonance_and_replays_the_same_lines() {
    let (fn_hz, zeta) = (8.0, 0.15);
    let (lines, replayed, dir) = run_kind(
        "kind = \"chirp\"\nlevels = [0.5]\nchirp_f0_hz = 1.0\nchirp_f1_hz = 20.0\n\
         chirp_amplitude = 0.05\nchirp_s = 12.0\n",
        (fn_hz, zeta, 10.0),
        60.0,
    );
    let fr = of_type(&lines, "frequency_response");
    assert_eq!(fr.len(), 1, "{lines:#?}");
    let resonance = fn_hz * (1.0f64 - 2.0 * zeta * zeta).sqrt();
    let peak = fr[0]["peak_hz"].as_f64().unwrap();
    assert!(
        (peak - resonance).abs() < 0.1 * resonance,
        "peak {peak} for {resonance}"
    );
    let model = &fr[0]["model"];
    let f = model["natural_hz"].as_f64().unwrap();
    assert!((f - fn_hz).abs() < 0.1 * fn_hz, "{model}");
    // the fit is published as a model line too, the pulse model's fields
    let models = of_type(&lines, "model");
    assert_eq!(models.len(), 1, "{lines:#?}");
    assert_eq!(models[0]["path"], "frequency_response");
    assert_eq!(models[0]["fn_hz"], model["natural_hz"]);
    assert_eq!(models[0]["operating_point"], 0.5);
    assert!(fr[0]["bins"].as_array().unwrap().len() > 10);
    assert!(fr[0]["bandwidth_hz"].as_f64().is_some(), "{}", fr[0]);
    assert!(fr[0]["phase_delay_s"].as_f64().is_some());
    assert_eq!(kind_lines(&lines), kind_lines(&replayed));
    let md = std::fs::read_to_string(dir.path().join("report/report.md")).unwrap();
    assert!(md.contains("## Frequency response"), "{md}");
    assert!(dir.path().join("report/bode.svg").exists());
}

#[test]
fn a_ramp_reports_both_legs_and_their_hysteresis() {
    let (lines, replayed, _dir) = run_kind(
        "kind = \"ramp\"\nlevels = [0.2, 0.6]\nramp_rate_per_s = 0.1\nhold_ms = 500\n",
        (12.0, 0.7, 10.0),
        60.0,
    );
    let maps: Vec<&Value> = of_type(&lines, "static_map")
        .into_iter()
        .filter(|m| m["output"] == "thrust")
        .collect();
    assert_eq!(maps.len(), 2, "{lines:#?}");
    assert_eq!(
        (&maps[0]["leg"], &maps[1]["leg"]),
        (&"up".into(), &"down".into())
    );
    // the stand has no hysteresis: the legs agree within a lag's worth (rate × τ × gain)
    let h = &maps[1]["hysteresis"];
    assert!(h["max_pct"].as_f64().unwrap() < 5.0, "{h}");
    assert_eq!(kind_lines(&lines), kind_lines(&replayed));
}
