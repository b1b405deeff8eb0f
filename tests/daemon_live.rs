//! `propid run` over the real pty loopback against the simulated stand (in this test process):
//! a clean run and the replay of its recording publish identical model lines; SIGINT sends STOP
//! and exits 0 with the stats line; hang-up and reconnect (new boot: never re-armed); the
//! device watchdog trips when the daemon's heartbeats stop; injected link faults are counted.

#[path = "support/csv_bench.rs"]
mod csv_bench;

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

/// The models of a run (model and schedule lines).
fn models_of(v: &[Value]) -> Vec<Value> {
    v.iter()
        .filter(|l| l["type"] == "model" || l["type"] == "schedule")
        .cloned()
        .collect()
}

#[test]
fn csv_bench_is_detected_driven_identified_and_replayed_identically() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.35, 0.5]", 4, 4);
    let rec = dir.path().join("run.csv");
    let sim = sim(
        500,
        |c| c.stand.protocol = propid::sim::config::WireProtocol::Csv,
        None,
    );
    let truth = SimConfig::default().plant;
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
    let report = sim.stop().unwrap();
    assert!(status.success(), "{err}");
    // detected as CSV ("auto"), driven through the plan in CSV commands
    assert_eq!(kind(&live, "csv_link").len(), 1, "{live:#?}");
    assert_eq!(kind(&live, "plan_finished").len(), 1, "{live:#?}");
    assert!(report.firmware.executed > 0);
    let stats = live.last().unwrap();
    assert_eq!(stats["wire"], "csv");
    assert_eq!(stats["samples_lost"], 0);
    assert_eq!(stats["duplicates"], 0);
    let dropped: u64 = stats["frames_dropped"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(dropped, 0, "{stats}");
    // pulses found from the throttle column: one model per level, near the simulator's plant
    let models = of_type(&live, "model");
    assert_eq!(models.len(), 2, "{live:#?}");
    for m in &models {
        let f = m["fn_hz"].as_f64().unwrap();
        assert!(
            (f / truth.fn_hz - 1.0).abs() < 0.1,
            "fn {f} vs {}",
            truth.fn_hz
        );
        assert_eq!(m["pulses"], 4, "{m}");
    }
    // the raw CSV bytes replay to the same models
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
    assert_eq!(models_of(&live), models_of(&replayed));
    assert_eq!(replayed.last().unwrap()["samples"], stats["samples"]);
}

#[test]
fn passive_csv_bench_is_sampled_and_identified_from_its_throttle_column() {
    use serialport::SerialPort;
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("passive.toml");
    std::fs::write(
        &cfg,
        "[device]\nprotocol = \"csv\"\n[daemon]\nmax_run_s = 4.0\nstop_timeout_ms = 50\n",
    )
    .unwrap();
    // streams CSV rows and never answers (see tests/support/csv_bench.rs for the plant)
    let rows: String =
        csv_bench::HEADER.to_string() + &csv_bench::rows(csv_bench::PLANT, 3_000).concat();
    let (fn_hz, zeta) = (csv_bench::PLANT.fn_hz, csv_bench::PLANT.zeta);
    let (mut master, slave) = serialport::TTYPort::pair().unwrap();
    let port = slave.name().unwrap();
    master.set_timeout(Duration::from_millis(5)).unwrap();
    let d = Daemon::start(&["run", "--config", cfg.to_str().unwrap(), "--port", &port]);
    // paced like a bench (20 rows every 10 ms: twice real time, so a loaded machine still ends
    // the stream well before max_run_s); what the daemon writes is read and ignored
    let bench = std::thread::spawn(move || {
        let lines: Vec<&str> = rows.lines().collect();
        let mut sink = [0u8; 256];
        for chunk in lines.chunks(20) {
            let mut s = chunk.join("\n");
            s.push('\n');
            if master.write_all(s.as_bytes()).is_err() {
                return;
            }
            let _ = std::io::Read::read(&mut master, &mut sink);
            std::thread::sleep(Duration::from_millis(10));
        }
        std::thread::sleep(Duration::from_secs(2));
    });
    let (status, lines, err) = d.finish(20.0);
    bench.join().unwrap();
    drop(slave);
    assert!(status.success(), "{err}");
    assert_eq!(kind(&lines, "passive_bench").len(), 1, "{lines:#?}");
    let models = of_type(&lines, "model");
    assert!(models.len() >= 3, "{lines:#?}");
    for m in &models {
        let f = m["fn_hz"].as_f64().unwrap();
        let z = m["zeta"].as_f64().unwrap();
        assert!((f / fn_hz - 1.0).abs() < 0.02, "fn {f}");
        assert!((z / zeta - 1.0).abs() < 0.05, "zeta {z}");
        assert!(
            (m["dc_gain"].as_f64().unwrap() / 10.0 - 1.0).abs() < 0.05,
            "{m}"
        );
    }
    let stats = lines.last().unwrap();
    assert_eq!(stats["wire"], "csv");
    assert_eq!(stats["samples_lost"], 0, "{stats}");
}

#[test]
fn csv_link_faults_are_counted_and_the_live_counts_equal_the_replay_of_the_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.4]", 8, 4);
    let rec = dir.path().join("run.csv");
    let sim = sim(
        1000,
        |c| {
            c.stand.protocol = propid::sim::config::WireProtocol::Csv;
            c.faults.bit_flip_per_byte = 1e-4;
            c.faults.garbage_bursts_per_s = 2.0;
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
    let (status, live, err) = d.finish(30.0);
    let report = sim.stop().unwrap();
    assert!(status.success(), "{err}");
    assert_eq!(kind(&live, "plan_finished").len(), 1, "{live:#?}");
    let s = live.last().unwrap();
    assert_eq!(s["wire"], "csv");
    let dropped: u64 = s["frames_dropped"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert!(dropped > 0, "{s}");
    assert!(s["samples_lost"].as_u64().unwrap() > 0, "{s}");
    // every row the stand took is received or counted lost (the last few may be in flight)
    let seen = s["samples"].as_u64().unwrap() + s["samples_lost"].as_u64().unwrap();
    assert!(seen <= report.firmware.samples, "{s} {:?}", report.firmware);
    assert!(
        seen + 50 >= report.firmware.samples,
        "{s} {:?}",
        report.firmware
    );
    // the replay of the recorded bytes counts exactly the same
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
    let r = replayed.last().unwrap();
    for key in [
        "frames_ok",
        "frames_dropped",
        "samples",
        "samples_lost",
        "gaps",
    ] {
        assert_eq!(r[key], s[key], "{key}");
    }
    assert_eq!(models_of(&live), models_of(&replayed));
}
