//! `propid run` over the real pty loopback against the simulated stand (in this test process):
//! a clean run and the replay of its recording publish identical model lines; SIGINT sends STOP
//! and exits 0 with the stats line; hang-up and reconnect (new boot: never re-armed); the
//! device watchdog trips when the daemon's heartbeats stop; injected link faults are counted.

use propid::sim::pty::{RunOptions, SimHandle};
use propid::sim::SimConfig;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_propid");

/// A daemon config with a short experiment.
fn daemon_config(dir: &Path, levels: &str, pulses: u32, k: u32) -> std::path::PathBuf {
    let p = dir.join("propid.toml");
    let text = format!(
        "[device]\nreconnect_initial_ms = 50\nreconnect_max_ms = 200\n\
         [identify]\npulses_per_model = {k}\n\
         [experiment]\nlevels = {levels}\nramp_ms = 100\nsettle_ms = 300\n\
         pulse_amplitudes = [0.1, 0.15]\npulse_spacing_ms = 150\npulses_per_level = {pulses}\n"
    );
    std::fs::write(&p, text).unwrap();
    p
}

fn sim(rate: u32, tweak: impl FnOnce(&mut SimConfig), link: Option<&Path>) -> SimHandle {
    let mut cfg = SimConfig::default();
    cfg.stand.sample_rate_hz = rate;
    tweak(&mut cfg);
    let opts = RunOptions {
        link: link.map(Path::to_path_buf),
        seconds: Some(60.0),
    };
    SimHandle::spawn(cfg, opts).unwrap()
}

/// The running daemon with its stdout lines arriving on a channel.
struct Daemon {
    child: Child,
    rx: Receiver<Value>,
    lines: Vec<Value>,
}

impl Daemon {
    fn start(args: &[&str]) -> Daemon {
        let mut child = Command::new(BIN)
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let out = child.stdout.take().unwrap();
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines() {
                let Ok(l) = l else { return };
                let v: Value = serde_json::from_str(&l).unwrap_or_else(|e| panic!("{l}: {e}"));
                if tx.send(v).is_err() {
                    return;
                }
            }
        });
        Daemon {
            child,
            rx,
            lines: Vec::new(),
        }
    }

    /// Waits for a line matching `pred` (panics after `secs`).
    fn wait_for(&mut self, secs: f64, pred: impl Fn(&Value) -> bool) -> Value {
        let end = Instant::now() + Duration::from_secs_f64(secs);
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(v) => {
                    self.lines.push(v.clone());
                    if pred(&v) {
                        return v;
                    }
                }
                Err(_) => panic!("no matching line within {secs} s; got {:#?}", self.lines),
            }
        }
    }

    fn signal(&self, sig: i32) {
        let r = unsafe { libc::kill(self.child.id() as i32, sig) };
        assert_eq!(r, 0);
    }

    /// Waits for the exit; returns the status and every line.
    fn finish(mut self, secs: f64) -> (std::process::ExitStatus, Vec<Value>, String) {
        let end = Instant::now() + Duration::from_secs_f64(secs);
        let status = loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                break s;
            }
            if Instant::now() > end {
                let _ = self.child.kill();
                panic!("daemon did not exit; lines {:#?}", self.lines);
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        while let Ok(v) = self.rx.recv_timeout(Duration::from_millis(500)) {
            self.lines.push(v);
        }
        let mut err = String::new();
        if let Some(mut e) = self.child.stderr.take() {
            use std::io::Read;
            let _ = e.read_to_string(&mut err);
        }
        (status, self.lines, err)
    }
}

fn kind<'a>(lines: &'a [Value], k: &str) -> Vec<&'a Value> {
    lines.iter().filter(|l| l["kind"] == k).collect()
}

fn of_type<'a>(lines: &'a [Value], t: &str) -> Vec<&'a Value> {
    lines.iter().filter(|l| l["type"] == t).collect()
}

#[test]
fn live_run_and_replay_of_its_recording_publish_identical_models() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.35, 0.5]", 4, 4);
    let rec = dir.path().join("run.tsp");
    let sim = sim(500, |_| {}, None);
    let port = sim.path().display().to_string();
    let d = Daemon::start(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--port",
        &port,
        "--record",
        rec.to_str().unwrap(),
    ]);
    let (status, live, err) = d.finish(30.0);
    let _ = sim.stop();
    assert!(status.success(), "{err}");
    assert_eq!(kind(&live, "plan_finished").len(), 1, "{live:#?}");
    let stats = live.last().unwrap();
    assert_eq!(stats["type"], "stats");
    assert_eq!(stats["samples_lost"], 0);
    assert_eq!(stats["overflows"], 0);
    let dropped: u64 = stats["frames_dropped"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(dropped, 0);

    let out = Command::new(BIN)
        .args(["replay", rec.to_str().unwrap(), "--config"])
        .arg(&cfg)
        .output()
        .unwrap();
    assert!(out.status.success());
    let replayed: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let models = |v: &[Value]| -> Vec<Value> {
        v.iter()
            .filter(|l| l["type"] == "model" || l["type"] == "schedule")
            .cloned()
            .collect()
    };
    let live_models = models(&live);
    assert_eq!(of_type(&live, "model").len(), 2, "{live:#?}");
    assert_eq!(live_models, models(&replayed));
    let rs = replayed.last().unwrap();
    assert_eq!(rs["samples"], stats["samples"]);
    assert_eq!(rs["frames_ok"], stats["frames_ok"]);
}

#[test]
fn sigint_sends_stop_until_acknowledged_and_exits_zero_with_stats() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4);
    let sim = sim(1000, |_| {}, None);
    let port = sim.path().display().to_string();
    let mut d = Daemon::start(&["run", "--config", cfg.to_str().unwrap(), "--port", &port]);
    d.wait_for(10.0, |l| l["kind"] == "level_reached");
    let t = Instant::now();
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(5.0);
    assert!(t.elapsed() < Duration::from_secs(3));
    let report = sim.stop().unwrap();
    assert!(status.success(), "{status:?} {err}");
    assert_eq!(
        kind(&lines, "shutdown_stop_acknowledged").len(),
        1,
        "{lines:#?}"
    );
    assert_eq!(lines.last().unwrap()["type"], "stats");
    assert!(report.firmware.executed > 0);
}

#[test]
fn hangup_reconnects_by_path_and_never_rearms_a_new_boot() {
    // The stand runs as its own process (`propid sim`), as in deployment: a pty master created
    // in this test process would be inherited by the daemon and the hang-up never seen.
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4);
    let mut sim = Command::new(BIN)
        .args([
            "sim",
            "--seconds",
            "20",
            "--hangup-after",
            "1.5",
            "--reopen-after",
            "200",
        ])
        .arg("--link")
        .arg(&link)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t = Instant::now();
    while !link.exists() && t.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut d = Daemon::start(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--port",
        link.to_str().unwrap(),
    ]);
    d.wait_for(10.0, |l| l["kind"] == "reconnected");
    // the new boot shows up as a new segment, and the plan reports it and stops commanding
    d.wait_for(5.0, |l| l["kind"] == "device_reset");
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(5.0);
    let _ = sim.kill();
    let _ = sim.wait();
    assert!(status.success(), "{err}");
    assert!(!kind(&lines, "disconnected").is_empty());
    assert_eq!(
        kind(&lines, "arm_acknowledged").len(),
        1,
        "armed once, never again"
    );
    assert!(kind(&lines, "segment").len() >= 2);
    let stats = lines.last().unwrap();
    assert!(stats["reconnects"].as_u64().unwrap() >= 1);
    assert!(stats["segments"].as_u64().unwrap() >= 2);
}

#[test]
fn watchdog_trips_when_the_daemons_heartbeats_stop() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4);
    // a low rate keeps the backlog small while the daemon is frozen
    let sim = sim(200, |_| {}, None);
    let port = sim.path().display().to_string();
    let mut d = Daemon::start(&["run", "--config", cfg.to_str().unwrap(), "--port", &port]);
    d.wait_for(10.0, |l| l["kind"] == "armed");
    d.signal(libc::SIGSTOP); // no heartbeats for 1 s (watchdog 500 ms)
    std::thread::sleep(Duration::from_millis(1000));
    d.signal(libc::SIGCONT);
    d.wait_for(5.0, |l| l["kind"] == "watchdog_trip");
    d.wait_for(5.0, |l| l["kind"] == "plan_halted_watchdog");
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(5.0);
    let report = sim.stop().unwrap();
    assert!(status.success(), "{err}");
    assert_eq!(report.firmware.watchdog_trips, 1);
    assert_eq!(lines.last().unwrap()["type"], "stats");
}

#[test]
fn injected_link_faults_are_counted_and_the_run_completes() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.4]", 4, 4);
    let rec = dir.path().join("run.tsp");
    let sim = sim(
        1000,
        |c| {
            c.faults.bit_flip_per_byte = 2e-4;
            c.faults.garbage_bursts_per_s = 5.0;
            c.faults.drop_sample_prob = 0.002;
        },
        None,
    );
    let port = sim.path().display().to_string();
    let d = Daemon::start(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--port",
        &port,
        "--record",
        rec.to_str().unwrap(),
    ]);
    let (status, lines, err) = d.finish(30.0);
    let report = sim.stop().unwrap();
    assert!(status.success(), "{err}");
    let s = lines.last().unwrap();
    let dropped: u64 = s["frames_dropped"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert!(dropped > 0, "{s}");
    // The daemon read a prefix of what the stand sent: it cannot count more than was injected.
    assert!(
        dropped <= report.faults.frames_dropped(),
        "{s} {:?}",
        report.faults
    );
    assert!(s["samples_lost"].as_u64().unwrap() > 0);
    // Exactly what a plain decoder counts on the recorded bytes: nothing lost in between.
    let bytes = std::fs::read(&rec).unwrap();
    let mut dec = propid::protocol::Decoder::new();
    let mut n = 0u64;
    dec.push(&bytes, |_| n += 1);
    assert_eq!(s["frames_ok"].as_u64().unwrap(), n);
    assert_eq!(dec.stats().dropped.total(), dropped);
}
