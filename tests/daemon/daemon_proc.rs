//! The real `propid` binary as a child process, for the end-to-end daemon tests: its stdout
//! lines arrive parsed on a channel, signals go to its pid, and `finish` waits for the exit.

#![allow(dead_code)]

use propid_sim::pty::{RunOptions, SimHandle, SimReport};
use propid_sim::SimConfig;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

/// The binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_propid");

/// Writes a daemon config with a short experiment at `levels`, plus `extra` TOML lines
/// (whole tables, e.g. `"[daemon]\nqueue_capacity = 16\n"`).
pub fn daemon_config(dir: &Path, levels: &str, pulses: u32, k: u32, extra: &str) -> PathBuf {
    let p = dir.join("propid.toml");
    let text = format!(
        "[device]\nreconnect_initial_ms = 50\nreconnect_max_ms = 200\n\
         [identify]\npulses_per_model = {k}\n\
         [experiment]\nlevels = {levels}\nramp_ms = 100\nsettle_ms = 300\n\
         pulse_amplitudes = [0.1, 0.15]\npulse_spacing_ms = 150\npulses_per_level = {pulses}\n\
         {extra}"
    );
    std::fs::write(&p, text).unwrap();
    p
}

/// A running child with its stdout lines arriving on a channel.
pub struct Daemon {
    pub child: Child,
    rx: Receiver<Value>,
    pub lines: Vec<Value>,
}

impl Daemon {
    /// Starts `propid ARGS` with stdout and stderr piped.
    pub fn start(args: &[&str]) -> Daemon {
        let mut cmd = Command::new(BIN);
        cmd.args(args);
        Daemon::spawn(cmd)
    }

    /// Starts `cmd` (the binary with its arguments, and whatever else the test sets up) with
    /// stdout and stderr piped.
    pub fn spawn(mut cmd: Command) -> Daemon {
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let out = child.stdout.take().unwrap();
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines() {
                let Ok(l) = l else { return };
                // every line is whole JSON: a torn line would fail here
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

    /// Starts `propid run --config CFG --port PORT` (`--record RECORD` when given).
    pub fn run(cfg: &Path, port: &str, record: Option<&Path>) -> Daemon {
        let mut args = vec!["run", "--config", path_str(cfg), "--port", port];
        if let Some(r) = record {
            args.extend(["--record", path_str(r)]);
        }
        Daemon::start(&args)
    }

    /// Waits for a line matching `pred` (panics after `secs`).
    pub fn wait_for(&mut self, secs: f64, pred: impl Fn(&Value) -> bool) -> Value {
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

    /// Sends `sig` to the child.
    pub fn signal(&self, sig: i32) {
        signal(self.child.id(), sig);
    }

    /// Waits for the exit (kills the child and panics after `secs`); returns the status,
    /// every stdout line and stderr.
    pub fn finish(mut self, secs: f64) -> (ExitStatus, Vec<Value>, String) {
        let status = wait_exit(&mut self.child, secs)
            .unwrap_or_else(|| panic!("propid did not exit; lines {:#?}", self.lines));
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

/// A path as the `&str` an argument list needs (test paths are UTF-8).
fn path_str(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 test path")
}

/// `propid replay RECORD --config CFG` to its end: every stdout line, parsed (panics when the
/// replay fails).
pub fn replay(record: &Path, cfg: &Path) -> Vec<Value> {
    let out = Command::new(BIN)
        .arg("replay")
        .arg(record)
        .arg("--config")
        .arg(cfg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "replay failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

/// The model and schedule lines of a run, in order.
pub fn models_of(lines: &[Value]) -> Vec<Value> {
    lines
        .iter()
        .filter(|l| l["type"] == "model" || l["type"] == "schedule")
        .cloned()
        .collect()
}

/// Sends `sig` to process `pid` (a child this test started).
pub fn signal(pid: u32, sig: i32) {
    let r = unsafe { libc::kill(pid as i32, sig) };
    assert_eq!(r, 0, "kill({pid}, {sig})");
}

/// Waits up to `secs` for `child` to exit; kills it and returns None when it does not.
pub fn wait_exit(child: &mut Child, secs: f64) -> Option<ExitStatus> {
    let end = Instant::now() + Duration::from_secs_f64(secs);
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return Some(s);
        }
        if Instant::now() > end {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Lines with `"kind": k`.
pub fn kind<'a>(lines: &'a [Value], k: &str) -> Vec<&'a Value> {
    lines.iter().filter(|l| l["kind"] == k).collect()
}

/// Lines with `"type": t`.
pub fn of_type<'a>(lines: &'a [Value], t: &str) -> Vec<&'a Value> {
    lines.iter().filter(|l| l["type"] == t).collect()
}

/// The final stats line (asserted to be the last line).
pub fn stats(lines: &[Value]) -> &Value {
    let s = lines.last().expect("no lines");
    assert_eq!(s["type"], "stats", "{lines:#?}");
    s
}

/// Sum of `frames_dropped` over its kinds.
pub fn dropped_total(s: &Value) -> u64 {
    s["frames_dropped"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum()
}

/// The simulated stand's configuration with a plant the assertions know exactly: fn 25 Hz,
/// ζ 0.5, 8 N per unit throttle, no noise, no quantisation; the default experiment (three
/// operating points, 0.3, 0.45, 0.6, of 8 pulses).
pub fn clean_stand() -> SimConfig {
    let mut cfg = SimConfig::default();
    cfg.plant.fn_hz = 25.0;
    cfg.plant.zeta = 0.5;
    cfg.plant.gain_n_per_throttle = 8.0;
    cfg.plant.noise_rms_n = 0.0;
    cfg.plant.quantum_n = 0.0;
    cfg
}

/// The simulated stand on a pty in this test process, at `rate` Hz, with `tweak` applied to the
/// default configuration (stops by itself after 60 s).
pub fn sim_stand(rate: u32, tweak: impl FnOnce(&mut SimConfig)) -> SimHandle {
    let mut cfg = SimConfig::default();
    cfg.stand.sample_rate_hz = rate;
    tweak(&mut cfg);
    let opts = RunOptions {
        link: None,
        seconds: Some(60.0),
        faults_for: None,
    };
    SimHandle::spawn(cfg, opts).unwrap()
}

/// `propid run` against the stand at 1 kHz, stopped by signal `sig` once the first level is
/// reached: asserts the shutdown contract (exit 0 within 3 s, the STOP acknowledged exactly
/// once, the stats line last, the stand executed commands) and returns the lines and the
/// stand's report.
pub fn stopped_by_signal(sig: i32) -> (Vec<Value>, SimReport) {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4, "");
    let sim = sim_stand(1000, |_| {});
    let port = sim.path().display().to_string();
    let mut d = Daemon::run(&cfg, &port, None);
    d.wait_for(10.0, |l| l["kind"] == "level_reached");
    let t = Instant::now();
    d.signal(sig);
    let (status, lines, err) = d.finish(5.0);
    assert!(t.elapsed() < Duration::from_secs(3));
    let report = sim.stop().unwrap();
    assert!(status.success(), "{status:?} {err}");
    assert_eq!(
        kind(&lines, "shutdown_stop_acknowledged").len(),
        1,
        "{lines:#?}"
    );
    stats(&lines);
    assert!(report.firmware.executed > 0, "{report:?}");
    (lines, report)
}

/// A child process killed (by its pid) when the test ends, even on a panic.
pub struct KillOnDrop(pub Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts `propid sim --seconds S --link LINK ARGS` as its own process (as in deployment) and
/// waits for the link to appear. The stand is the 2nd-order plant, named in a configuration
/// beside the link (`config/sim.toml`, read without `--config`, is the motor).
pub fn sim_process(link: &Path, seconds: f64, args: &[&str]) -> KillOnDrop {
    let cfg = link.with_extension("sim.toml");
    std::fs::write(&cfg, "[plant]\nkind = \"second_order\"\n").unwrap();
    let child = Command::new(BIN)
        .args(["sim", "--seconds", &seconds.to_string(), "--config"])
        .arg(&cfg)
        .args(args)
        .arg("--link")
        .arg(link)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let guard = KillOnDrop(child);
    let t = Instant::now();
    while !link.exists() {
        assert!(t.elapsed() < Duration::from_secs(10), "no pty link");
        std::thread::sleep(Duration::from_millis(20));
    }
    guard
}
