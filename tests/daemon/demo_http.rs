//! `propid demo --http`: the schedule is on the terminal when the run ends while the page is
//! still served (until Ctrl-C), and the page gets each level's truth (the demo's `truth`
//! line) and shows it beside the gain schedule in headless Chromium; a screenshot of the
//! demo's page is saved for review.

use crate::browser::{self, tag_attr, tags};
use crate::daemon_http::{events, same};
use crate::daemon_proc::{signal, wait_exit, BIN};
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::Duration;

/// The lines of `r` on a channel.
fn lines_of(r: impl Read + Send + 'static) -> Receiver<String> {
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for l in BufReader::new(r).lines() {
            let Ok(l) = l else { return };
            if tx.send(l).is_err() {
                return;
            }
        }
    });
    rx
}

/// Lines of `rx` until one contains `marker` (panics after `secs` or when the stream ends,
/// with what it and `other`, the other stream, said); all of them, joined.
fn until(rx: &Receiver<String>, marker: &str, secs: u64, other: &Receiver<String>) -> String {
    let mut seen = String::new();
    loop {
        let l = rx
            .recv_timeout(Duration::from_secs(secs))
            .unwrap_or_else(|e| {
                let said: Vec<String> = other.try_iter().collect();
                panic!("no {marker:?} ({e}) in:\n{seen}\nthe other stream:\n{said:#?}")
            });
        seen.push_str(&l);
        seen.push('\n');
        if l.contains(marker) {
            return seen;
        }
    }
}

#[test]
fn demo_over_http_prints_its_schedule_at_the_end_and_the_page_shows_the_truth() {
    browser::chromium();
    let mut child = Command::new(BIN)
        .args(["demo", "--http", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = lines_of(child.stdout.take().unwrap());
    let err = lines_of(child.stderr.take().unwrap());
    let at = until(&err, "the live page is at ", 20, &out);
    let url = at
        .rsplit("the live page is at ")
        .next()
        .unwrap()
        .trim()
        .to_string();
    // the schedule and the counters when the run ends, the page still served
    let table = until(&out, " models in ", 60, &err);
    assert_eq!(
        table.lines().filter(|l| l.ends_with("| yes")).count(),
        3,
        "{table}"
    );
    until(&err, "stays up until Ctrl-C", 10, &out);
    assert!(child.try_wait().unwrap().is_none(), "the demo ended");
    // the page's history holds the truth of the three levels
    let rx = events(&url);
    let truth = loop {
        let v = rx
            .recv_timeout(Duration::from_secs(10))
            .expect("no truth line");
        if v["type"] == "truth" {
            break v;
        }
    };
    assert_eq!(truth["plant"], "motor", "{truth}");
    let levels = truth["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3, "{truth}");
    let mut last_gain = 0.0;
    for (l, op) in levels.iter().zip([0.3, 0.45, 0.6]) {
        assert_eq!(l["operating_point"], op, "{l}");
        let gain = l["gain"].as_f64().unwrap();
        assert!(gain > last_gain, "{truth}");
        last_gain = gain;
        let (up, down) = (
            l["tau_up_s"].as_f64().unwrap(),
            l["tau_down_s"].as_f64().unwrap(),
        );
        assert!(up > 0.0 && up < down, "{l}");
        assert_eq!(l["within"], true, "{l}");
        assert!(l["model"]["gain"].as_f64().unwrap() > 0.0, "{l}");
    }
    // the page shows each level's truth in the schedule table
    let dom = browser::dom_when(&url, |d| {
        d.contains("data-final=\"1\"") && d.contains("data-truth_gain=")
    });
    assert!(dom.contains("data-truth=\"motor\""), "{dom}");
    let rows = tags(&dom, "<tr data-operating_point=");
    assert_eq!(rows.len(), 3, "{dom}");
    for (tr, l) in rows.iter().zip(levels) {
        let shown: f64 = tag_attr(tr, "data-truth_gain").unwrap().parse().unwrap();
        assert!(same(shown, l["gain"].as_f64().unwrap()), "{tr} vs {l}");
    }
    let png = Path::new(env!("CARGO_TARGET_TMPDIR")).join("web-demo.png");
    browser::screenshot(&url, &png);
    eprintln!("screenshot of the demo's page: {}", png.display());
    signal(child.id(), libc::SIGINT);
    let status = wait_exit(&mut child, 10.0).expect("the demo did not end on SIGINT");
    assert!(status.success(), "{status}");
}
