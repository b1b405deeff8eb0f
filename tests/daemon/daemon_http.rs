//! `--http`: the live web page of a run and of a replay. The daemon against the simulated stand
//! serves the page, its event stream carries the published lines (the first model event is
//! the model line), only GETs of the embedded files are answered; headless Chromium shows the
//! published model and a replay's final gain schedule (a screenshot is saved for review).

use crate::browser::{self, attr, tag_attr, tags};
use crate::daemon_proc::{daemon_config, of_type, sim_stand, Daemon};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::sync::mpsc::{channel, Receiver};
use std::time::Duration;

/// The same published number: the page's value (the browser parses the line's decimal text
/// exactly) and the test's (serde_json's default parser may land one unit in the last place
/// off the exact decimal) may differ in the last bit, never more.
pub(crate) fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs())
}

/// The page's URL from the `http` event line (the first line of a run with `--http`).
pub(crate) fn url_of(d: &mut Daemon) -> String {
    let l = d.wait_for(10.0, |l| l["kind"] == "http");
    l["url"].as_str().unwrap().to_string()
}

/// `host:port` of a URL `http://host:port/`.
pub(crate) fn host(url: &str) -> &str {
    url.trim_start_matches("http://").trim_end_matches('/')
}

/// One request by hand (the test's client): status and body.
pub(crate) fn request(url: &str, method: &str, path: &str) -> (u16, String) {
    let mut c = TcpStream::connect(host(url)).unwrap();
    c.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        c,
        "{method} {path} HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n\r\n",
        host(url)
    )
    .unwrap();
    let mut text = String::new();
    let _ = c.read_to_string(&mut text);
    let code = text.split(' ').nth(1).unwrap_or("0").parse().unwrap_or(0);
    let body = text.split_once("\r\n\r\n").map_or("", |b| b.1).to_string();
    (code, body)
}

/// The event stream's `data:` lines, parsed, on a channel.
pub(crate) fn events(url: &str) -> Receiver<Value> {
    let mut c = TcpStream::connect(host(url)).unwrap();
    write!(c, "GET /events HTTP/1.1\r\nHost: {}\r\n\r\n", host(url)).unwrap();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(c).lines() {
            let Ok(line) = line else { return };
            if let Some(d) = line.strip_prefix("data: ") {
                let v: Value = serde_json::from_str(d).unwrap_or_else(|e| panic!("{d}: {e}"));
                if tx.send(v).is_err() {
                    return;
                }
            }
        }
    });
    rx
}

/// A run that goes on for a while: one level, many pulses, a model every 4.
fn long_run(dir: &Path, port: &str) -> Daemon {
    let cfg = daemon_config(dir, "[0.4]", 1000, 4, "");
    let cfg = cfg.to_str().unwrap();
    Daemon::start(&[
        "run",
        "--config",
        cfg,
        "--port",
        port,
        "--http",
        "127.0.0.1:0",
    ])
}

#[test]
fn run_serves_the_page_and_its_stream_carries_the_published_lines() {
    let dir = tempfile::tempdir().unwrap();
    let sim = sim_stand(1000, |_| {});
    let mut d = long_run(dir.path(), &sim.path().display().to_string());
    let url = url_of(&mut d);
    assert!(
        url.starts_with("http://127.0.0.1:") && !url.ends_with(":0/"),
        "{url}"
    );
    let rx = events(&url);
    let published = d.wait_for(20.0, |l| l["type"] == "model");
    let mut seen = std::collections::BTreeSet::new();
    let streamed = loop {
        let v = rx
            .recv_timeout(Duration::from_secs(20))
            .expect("no model event");
        seen.insert(v["type"].as_str().unwrap().to_string());
        if v["type"] == "model" {
            break v;
        }
    };
    assert_eq!(streamed, published);
    // then the page's own lines of that window, and its samples (with the stand's voltage
    // and current) and counters
    let mut volts = 0;
    while volts == 0
        || ![
            "response",
            "stabilization",
            "schedule",
            "samples",
            "live_stats",
        ]
        .iter()
        .all(|t| seen.contains(*t))
    {
        let v = rx
            .recv_timeout(Duration::from_secs(20))
            .unwrap_or_else(|_| panic!("only {seen:?}"));
        let first = !seen.contains(v["type"].as_str().unwrap());
        if first && v["type"] == "response" {
            assert_eq!(v["t_s"], published["t_s"]);
            let (mean, model) = (
                v["mean"].as_array().unwrap(),
                v["model"].as_array().unwrap(),
            );
            assert!(mean.len() > 10 && model.len() == mean.len(), "{v}");
        }
        if v["type"] == "samples" {
            let n = v["t_s"].as_array().unwrap().len();
            for key in ["voltage_V", "current_A"] {
                let xs = v[key].as_array().unwrap();
                assert_eq!(xs.len(), n, "{v}");
                assert!(xs.iter().all(|x| x.as_f64().is_some()), "{key}: {v}");
            }
            let first_v = v["voltage_V"][0].as_f64().unwrap();
            assert!(first_v > 10.0 && first_v < 20.0, "{v}");
            volts += 1;
        }
        if first && v["type"] == "stabilization" {
            assert_eq!(v["t_s"], published["t_s"]);
            assert!(v["orders"].as_array().unwrap().len() >= 2, "{v}");
        }
        seen.insert(v["type"].as_str().unwrap().to_string());
    }
    let (code, body) = request(&url, "GET", "/");
    assert_eq!(code, 200);
    assert!(
        body.contains("/events") || body.contains("app.js"),
        "{body}"
    );
    assert_eq!(request(&url, "POST", "/").0, 405);
    assert_eq!(request(&url, "POST", "/events").0, 405);
    assert_eq!(request(&url, "GET", "/no/such/file").0, 404);
    assert_eq!(request(&url, "GET", "/../Cargo.toml").0, 404);
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(10.0);
    let _ = sim.stop();
    assert!(status.success(), "{err}");
    assert!(err.contains(&url), "{err}");
    assert_eq!(lines.last().unwrap()["type"], "stats");
    // the page's own lines never reach stdout
    for t in ["samples", "response", "stabilization", "live_stats"] {
        assert!(of_type(&lines, t).is_empty(), "{t} on stdout");
    }
    assert_eq!(of_type(&lines, "schedule").len(), 1);
}

/// Issue 13's test: the page in headless Chromium, live, shows the values of a published
/// model line; a screenshot is saved for review.
#[test]
fn the_page_in_chromium_shows_the_published_model() {
    browser::chromium();
    let dir = tempfile::tempdir().unwrap();
    let sim = sim_stand(1000, |_| {});
    let mut d = long_run(dir.path(), &sim.path().display().to_string());
    let url = url_of(&mut d);
    d.wait_for(20.0, |l| l["type"] == "model");
    let dom = browser::dom_when(&url, |dom| {
        attr(dom, "id=\"model\"", "data-t_s").is_some_and(|t| !t.is_empty())
    });
    let t: f64 = attr(&dom, "id=\"model\"", "data-t_s")
        .unwrap()
        .parse()
        .unwrap();
    let same_t = |l: &Value| l["type"] == "model" && l["t_s"].as_f64().is_some_and(|x| same(x, t));
    let model = match d.lines.iter().find(|l| same_t(l)) {
        Some(m) => m.clone(),
        None => d.wait_for(20.0, same_t),
    };
    let shown = |key: &str| attr(&dom, &format!("id=\"model-{key}\""), "data-value").unwrap();
    for key in ["fn_hz", "zeta", "dc_gain", "operating_point"] {
        let v: f64 = shown(key).parse().unwrap();
        let line = model[key].as_f64().unwrap();
        assert!(same(v, line), "{key}: page {v}, line {line}");
    }
    assert_eq!(shown("order"), model["order"].to_string());
    assert_eq!(shown("pulses"), model["pulses"].to_string());
    // the stand's supply voltage and current are drawn (their latest values shown)
    for (key, lo, hi) in [("voltage_V", 10.0, 20.0), ("current_A", 0.0, 100.0)] {
        let v: f64 = attr(&dom, &format!("id=\"now-{key}\""), "data-value")
            .unwrap()
            .parse()
            .unwrap_or_else(|e| panic!("{key}: {e}"));
        assert!(v > lo && v < hi, "{key} {v}");
    }
    let png = Path::new(env!("CARGO_TARGET_TMPDIR")).join("web.png");
    browser::screenshot(&url, &png);
    eprintln!("screenshot of the live page: {}", png.display());
    d.signal(libc::SIGINT);
    let (status, _, err) = d.finish(10.0);
    let _ = sim.stop();
    assert!(status.success(), "{err}");
}

/// Issue 13's test: a replay served over HTTP shows (in Chromium) the final gain schedule of
/// the replay's JSON lines, row by row, to the bit.
#[test]
fn a_replay_served_over_http_shows_the_final_schedule_of_its_lines() {
    browser::chromium();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("stand.tsp");
    let mut bytes = Vec::new();
    let cfg = propid_sim::SimConfig::default();
    propid_sim::record::record(&cfg, 60.0, &mut bytes).unwrap();
    std::fs::write(&rec, bytes).unwrap();
    let mut d = Daemon::start(&["replay", rec.to_str().unwrap(), "--http", "127.0.0.1:0"]);
    let url = url_of(&mut d);
    d.wait_for(30.0, |l| l["type"] == "stats");
    let schedule = of_type(&d.lines, "schedule")[0]["models"]
        .as_array()
        .unwrap()
        .clone();
    assert!(schedule.len() >= 2, "{schedule:#?}");
    let dom = browser::dom_when(&url, |dom| dom.contains("data-final=\"1\""));
    let rows = tags(&dom, "<tr data-operating_point=");
    assert_eq!(rows.len(), schedule.len(), "{dom}");
    for (tr, m) in rows.iter().zip(&schedule) {
        for key in ["operating_point", "fn_hz", "zeta", "dc_gain"] {
            let v: f64 = tag_attr(tr, &format!("data-{key}"))
                .unwrap()
                .parse()
                .unwrap();
            let line = m[key].as_f64().unwrap();
            assert!(same(v, line), "{key}: {tr} vs {m}");
        }
        assert_eq!(tag_attr(tr, "data-order").unwrap(), m["order"].to_string());
    }
    d.signal(libc::SIGINT);
    let (status, _, err) = d.finish(10.0);
    assert!(status.success(), "{err}");
}
