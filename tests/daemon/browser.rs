//! Headless Chromium for the web page's tests (Debian's `chromium` package). A missing browser
//! is a failure, not a skip: `.ci/run` installs it on a fresh machine.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// The browser, or a panic that says how to install it.
pub fn chromium() -> PathBuf {
    for p in ["/usr/bin/chromium", "/usr/bin/chromium-browser"] {
        if Path::new(p).exists() {
            return PathBuf::from(p);
        }
    }
    panic!(
        "headless Chromium is needed for the web page's tests and is not installed: \
         run `apt-get install -y chromium` (as root; .ci/run does it on a fresh machine)"
    );
}

/// Runs Chromium headless on `url` with `args` (a fresh profile, no network but the page's),
/// waiting `page_ms` for the page before it acts (the event stream never ends), up to 60 s in
/// all; returns stdout.
fn run(url: &str, args: &[&str], page_ms: u32) -> String {
    let profile = tempfile::tempdir().unwrap();
    let mut child = Command::new(chromium())
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--window-size=1400,1900",
        ])
        // the event stream never ends: stop waiting for the page after this long
        .arg(format!("--timeout={page_ms}"))
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .args(args)
        .arg(url)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chromium");
    let mut out = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut out, &mut s);
        s
    });
    let status = crate::daemon_proc::wait_exit(&mut child, 60.0).expect("chromium hung");
    assert!(status.success(), "chromium failed: {status}");
    reader.join().unwrap()
}

/// The page's DOM after its scripts ran (`--dump-dom`).
pub fn dom(url: &str) -> String {
    run(url, &["--dump-dom"], 4000)
}

/// The DOM once `ready` holds of it (the page has drawn what the test waits for), retried.
pub fn dom_when(url: &str, ready: impl Fn(&str) -> bool) -> String {
    for _ in 0..10 {
        let d = dom(url);
        if ready(&d) {
            return d;
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    panic!("the page never showed what was waited for");
}

/// A screenshot of the page, saved at `png`. On a loaded machine Chromium may give up before
/// the page has painted: tried three times, waiting longer each time.
pub fn screenshot(url: &str, png: &Path) {
    for page_ms in [4000, 8000, 15000] {
        let _ = std::fs::remove_file(png);
        run(url, &[&format!("--screenshot={}", png.display())], page_ms);
        if std::fs::metadata(png).map(|m| m.len()).unwrap_or(0) > 10_000 {
            return;
        }
    }
    panic!("no screenshot at {} after three tries", png.display());
}

/// The value of attribute `attr` of the element whose opening tag contains `marker`.
pub fn attr(html: &str, marker: &str, attr: &str) -> Option<String> {
    let at = html.find(marker)?;
    let start = html[..at].rfind('<')?;
    let end = at + html[at..].find('>')?;
    let tag = &html[start..end];
    let key = format!(" {attr}=\"");
    let v = tag.find(&key)? + key.len();
    Some(tag[v..v + tag[v..].find('"')?].to_string())
}

/// Every opening tag starting with `prefix` (e.g. `<tr data-`).
pub fn tags<'a>(html: &'a str, prefix: &str) -> Vec<&'a str> {
    html.match_indices(prefix)
        .filter_map(|(i, _)| html[i..].find('>').map(|e| &html[i..i + e]))
        .collect()
}

/// The value of `attr` in one opening tag.
pub fn tag_attr(tag: &str, attr: &str) -> Option<String> {
    let key = format!(" {attr}=\"");
    let v = tag.find(&key)? + key.len();
    Some(tag[v..v + tag[v..].find('"')?].to_string())
}
