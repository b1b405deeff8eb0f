//! Faults a link really has (issue 12 item 5), forced through the real binary against the
//! simulated stand run as its own process (as in deployment): a device that resets mid-run
//! (re-armed only when `[experiment] rearm_on_reset` says so), a device that stops answering
//! with its port open (the host's stall watchdog), a port that vanishes and comes back under a
//! new name behind its udev-style symlink, and a recording whose disk fills mid-run (the file
//! size limit RLIMIT_FSIZE of the daemon's process: writes fail with EFBIG, as on a full disk).
//! Also: re-arms bounded by `[experiment] max_rearms`, a passive CSV bench that stops
//! streaming (stalled, reopened with backoff, resumed), and `propid demo` on a frozen stand.
//! Each runs a few seconds: short plans, short timeouts.

use crate::daemon_proc;

use daemon_proc::{kind, of_type, sim_process, stats, Daemon};
use propid_sim::pty::point_link;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A daemon config: one operating point `[0.4]` of `pulses` pulses, a model every 4, short
/// timeouts; `device` and `experiment` are extra keys of those tables.
fn config(dir: &Path, pulses: u32, device: &str, experiment: &str) -> PathBuf {
    let p = dir.join("propid.toml");
    let text = format!(
        "[device]\nreconnect_initial_ms = 50\nreconnect_max_ms = 200\n{device}\
         [daemon]\nstop_timeout_ms = 100\n\
         [identify]\npulses_per_model = 4\n\
         [experiment]\nlevels = [0.4]\nramp_ms = 100\nsettle_ms = 300\n\
         pulse_amplitudes = [0.1, 0.15]\npulse_spacing_ms = 150\npulses_per_level = {pulses}\n\
         {experiment}"
    );
    std::fs::write(&p, text).unwrap();
    p
}

/// Where in `lines` the first line of kind `k` is.
fn position(lines: &[Value], k: &str) -> usize {
    lines
        .iter()
        .position(|l| l["kind"] == k)
        .unwrap_or_else(|| panic!("no {k}: {lines:#?}"))
}

fn models_after(lines: &[Value], i: usize) -> usize {
    of_type(&lines[i..], "model").len()
}

#[test]
fn a_device_reset_rearms_when_the_config_says_so_and_models_follow() {
    // (without rearm_on_reset the run ends with exit 8: host_faults.rs and daemon_live.rs)
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let cfg = config(dir.path(), 1000, "", "rearm_on_reset = true\n");
    // the stand resets after 1.5 s (a USB re-enumeration: hang-up, a new boot 200 ms later)
    let sim = sim_process(
        &link,
        20.0,
        &["--hangup-after", "1.5", "--reopen-after", "200"],
    );
    let mut d = Daemon::run(&cfg, link.to_str().unwrap(), None);
    let reset = d.wait_for(10.0, |l| l["kind"] == "device_reset");
    assert_eq!(reset["rearm"], true, "{reset}");
    assert!(reset["message"].as_str().unwrap().contains("re-arms"));
    d.wait_for(5.0, |l| l["kind"] == "arm_acknowledged");
    d.wait_for(5.0, |l| l["type"] == "model");
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(5.0);
    drop(sim);
    assert!(status.success(), "{status:?} {err}");
    let at = position(&lines, "device_reset");
    assert!(models_after(&lines, at) >= 1);
    // the plan resumed at its operating point, armed again on the new boot
    assert!(kind(&lines[at..], "connected").len() == 1, "{lines:#?}");
    assert!(kind(&lines[at..], "level_reached")[0]["index"] == 0);
    assert!(kind(&lines, "arm_acknowledged").len() >= 2);
    let s = stats(&lines);
    assert!(s["reconnects"].as_u64().unwrap() >= 1, "{s}");
    assert!(s["segments"].as_u64().unwrap() >= 2, "{s}");
}

#[test]
fn scheduled_hang_ups_and_resets_are_each_followed_and_re_armed() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let cfg = config(
        dir.path(),
        1000,
        "",
        "rearm_on_reset = true\nmax_rearms = 10\n",
    );
    // `propid sim --hangup-every/--reset-every` (the soak's faults): a hang-up at 1.5 s of the
    // run (a new boot behind the link 100 ms later), a reset with the port open at 2.5 s
    let sim = sim_process(
        &link,
        20.0,
        &[
            "--hangup-every",
            "1.5",
            "--reset-every",
            "2.5",
            "--reopen-after",
            "100",
        ],
    );
    let mut d = Daemon::run(&cfg, link.to_str().unwrap(), None);
    d.wait_for(10.0, |l| l["kind"] == "disconnected");
    d.wait_for(5.0, |l| l["kind"] == "device_reset");
    // the reset comes with the port open: a new boot id, no disconnection
    d.wait_for(5.0, |l| l["kind"] == "device_reset");
    d.wait_for(5.0, |l| l["kind"] == "arm_acknowledged");
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(5.0);
    drop(sim);
    assert!(status.success(), "{status:?} {err}");
    let resets = kind(&lines, "device_reset");
    assert!(resets.len() >= 2, "{lines:#?}");
    assert!(resets.iter().all(|r| r["rearm"] == true), "{resets:#?}");
    let second = lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l["kind"] == "device_reset")
        .nth(1)
        .unwrap()
        .0;
    let first = position(&lines, "device_reset");
    assert!(
        kind(&lines[first..second], "disconnected").is_empty(),
        "{lines:#?}"
    );
    // three boots, each announced by a `segment` line
    assert!(kind(&lines, "segment").len() >= 3, "{lines:#?}");
}

/// `propid run` against a stand that freezes after 1 s (port open, silent, reset when the host
/// closes the port), with a 300 ms stall watchdog.
fn frozen_stand(dir: &Path, rearm: bool) -> (Daemon, daemon_proc::KillOnDrop) {
    let link = dir.join("stand");
    let cfg = config(
        dir,
        1000,
        "stall_timeout_ms = 300\n",
        &format!("rearm_on_reset = {rearm}\n"),
    );
    let sim = sim_process(&link, 20.0, &["--freeze-after", "1.0"]);
    (Daemon::run(&cfg, link.to_str().unwrap(), None), sim)
}

/// The `link_stalled` line: one, with its fields; the stats count it.
fn check_stall(lines: &[Value]) {
    let st = kind(lines, "link_stalled");
    assert_eq!(st.len(), 1, "{lines:#?}");
    assert_eq!(st[0]["type"], "warning");
    assert_eq!(st[0]["stop_acknowledged"], false, "a frozen device");
    assert!(st[0]["silent_ms"].as_u64().unwrap() >= 300, "{}", st[0]);
    let at = position(lines, "link_stalled");
    assert!(
        !kind(&lines[at..], "reconnected").is_empty(),
        "reopened: {lines:#?}"
    );
    let s = stats(lines);
    assert_eq!(s["stalls"], 1, "{s}");
    assert!(s["reconnects"].as_u64().unwrap() >= 1, "{s}");
}

#[test]
fn a_device_silent_with_its_port_open_is_stopped_reported_reopened_and_ends_the_plan() {
    let dir = tempfile::tempdir().unwrap();
    let (d, sim) = frozen_stand(dir.path(), false);
    // no signal: the plan is over on the stall, the run ends by itself
    let (status, lines, err) = d.finish(10.0);
    drop(sim);
    assert_eq!(status.code(), Some(8), "{err} {lines:#?}");
    assert!(
        err.contains("the experiment plan ended on a fault"),
        "{err}"
    );
    check_stall(&lines);
    assert!(
        kind(&lines, "link_failed").is_empty(),
        "a stall, not a refusal to acknowledge"
    );
    assert_eq!(kind(&lines, "arm_acknowledged").len(), 1, "never re-armed");
}

#[test]
fn a_stalled_device_is_rearmed_after_the_reopen_when_the_config_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (mut d, sim) = frozen_stand(dir.path(), true);
    d.wait_for(10.0, |l| l["kind"] == "link_stalled");
    d.wait_for(5.0, |l| l["kind"] == "arm_acknowledged");
    d.wait_for(5.0, |l| l["type"] == "model");
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(5.0);
    drop(sim);
    assert!(status.success(), "{status:?} {err}");
    check_stall(&lines);
    let at = position(&lines, "link_stalled");
    assert!(models_after(&lines, at) >= 1);
    assert_eq!(kind(&lines, "arm_acknowledged").len(), 2, "{lines:#?}");
}

#[test]
fn a_port_that_vanishes_and_returns_under_a_new_name_is_followed_through_its_symlink() {
    let dir = tempfile::tempdir().unwrap();
    // the stable name a udev rule gives the stand (scripts/99-propid.rules: /dev/propid-stand)
    let stable = dir.path().join("propid-stand");
    let cfg = config(dir.path(), 1000, "", "rearm_on_reset = true\n");
    let a_link = dir.path().join("stand-a");
    let a = sim_process(&a_link, 30.0, &["--seed", "1"]);
    let a_node = std::fs::read_link(&a_link).unwrap();
    point_link(&stable, &a_node).unwrap();
    let mut d = Daemon::run(&cfg, stable.to_str().unwrap(), None);
    d.wait_for(10.0, |l| l["type"] == "model");
    // the device goes away (its node with it); the link dangles
    drop(a);
    d.wait_for(5.0, |l| l["kind"] == "disconnected");
    std::thread::sleep(Duration::from_millis(300));
    // it comes back as another node; udev re-points the stable name
    let b_link = dir.path().join("stand-b");
    let b = sim_process(&b_link, 30.0, &["--seed", "2"]);
    let b_node = std::fs::read_link(&b_link).unwrap();
    point_link(&stable, &b_node).unwrap();
    let back = d.wait_for(10.0, |l| l["kind"] == "reconnected");
    // the event names the node the stable path now resolves to
    assert_eq!(back["device_node"], b_node.to_str().unwrap(), "{back}");
    let reset = d.wait_for(5.0, |l| l["kind"] == "device_reset");
    assert_eq!(reset["rearm"], true);
    d.wait_for(10.0, |l| l["type"] == "model");
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(5.0);
    drop(b);
    assert!(status.success(), "{status:?} {err}");
    let gone = position(&lines, "disconnected");
    assert!(models_after(&lines, gone) >= 1, "models again: {lines:#?}");
    let s = stats(&lines);
    assert!(s["reconnects"].as_u64().unwrap() >= 1, "{s}");
    assert!(s["segments"].as_u64().unwrap() >= 2, "{s}");
}

#[test]
fn a_recording_whose_disk_fills_mid_run_is_a_counted_warning_and_nothing_published_is_lost() {
    use std::os::unix::process::CommandExt;
    const LIMIT: u64 = 20_000;
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let rec = dir.path().join("run.tsp");
    let cfg = config(dir.path(), 8, "", "");
    let sim = sim_process(&link, 20.0, &[]);
    let mut cmd = std::process::Command::new(daemon_proc::BIN);
    cmd.args(["run", "--config", cfg.to_str().unwrap()])
        .args(["--port", link.to_str().unwrap()])
        .args(["--record", rec.to_str().unwrap()]);
    // SAFETY: between fork and exec only async-signal-safe calls (setrlimit, signal).
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: LIMIT,
                rlim_max: LIMIT,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            // a write past the limit fails with EFBIG instead of killing the process
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            Ok(())
        });
    }
    let d = Daemon::spawn(cmd);
    let (status, lines, err) = d.finish(20.0);
    drop(sim);
    // the run went on to its end; the failure is reported at the end with exit 7
    assert_eq!(status.code(), Some(7), "{err} {lines:#?}");
    assert!(err.contains("write error: recording"), "{err}");
    let failed = kind(&lines, "output_failed");
    assert_eq!(failed.len(), 1, "{lines:#?}");
    assert_eq!(failed[0]["sink"], "record");
    assert!(
        failed[0]["message"].as_str().unwrap().contains("too large"),
        "EFBIG: {}",
        failed[0]
    );
    // mid-run: the plan had started before the disk filled
    let at = position(&lines, "output_failed");
    assert!(position(&lines, "arm_acknowledged") < at, "{lines:#?}");
    // nothing published is lost: both models of the 8 pulses, the schedule, the plan's end
    assert_eq!(kind(&lines, "plan_finished").len(), 1, "{lines:#?}");
    assert_eq!(of_type(&lines, "model").len(), 2, "{lines:#?}");
    assert_eq!(of_type(&lines, "schedule").len(), 1);
    // the loss is counted: what the file holds against what was received
    let s = stats(&lines);
    let size = std::fs::metadata(&rec).unwrap().len();
    assert_eq!(size, LIMIT);
    assert_eq!(s["record_bytes_written"], size, "{s}");
    assert!(s["bytes"].as_u64().unwrap() > 2 * LIMIT, "{s}");
}

#[test]
fn a_device_that_keeps_resetting_is_rearmed_at_most_max_rearms_times_then_the_run_ends() {
    let dir = tempfile::tempdir().unwrap();
    let stable = dir.path().join("propid-stand");
    let cfg = config(
        dir.path(),
        1000,
        "",
        "rearm_on_reset = true\nmax_rearms = 1\n",
    );
    // three boots of the stand behind the stable name: each a new boot id (its own seed)
    let boot = |name: &str, seed: &str| {
        let link = dir.path().join(name);
        let sim = sim_process(&link, 30.0, &["--seed", seed]);
        point_link(&stable, &std::fs::read_link(&link).unwrap()).unwrap();
        sim
    };
    let a = boot("stand-a", "1");
    let mut d = Daemon::run(&cfg, stable.to_str().unwrap(), None);
    d.wait_for(10.0, |l| l["kind"] == "arm_acknowledged");
    drop(a);
    d.wait_for(5.0, |l| l["kind"] == "disconnected");
    let b = boot("stand-b", "2");
    let first = d.wait_for(10.0, |l| l["kind"] == "device_reset");
    assert_eq!(first["rearm"], true, "{first}");
    d.wait_for(5.0, |l| l["kind"] == "arm_acknowledged");
    drop(b);
    d.wait_for(5.0, |l| l["kind"] == "disconnected");
    let c = boot("stand-c", "3");
    // no signal: past the bound the plan is over and the run ends by itself
    let (status, lines, err) = d.finish(15.0);
    drop(c);
    assert_eq!(status.code(), Some(8), "{err} {lines:#?}");
    assert!(
        err.contains("the experiment plan ended on a fault"),
        "{err}"
    );
    let resets = kind(&lines, "device_reset");
    assert_eq!(resets.len(), 2, "{lines:#?}");
    assert_ne!(resets[1]["rearm"], true, "{}", resets[1]);
    assert!(resets[1]["message"]
        .as_str()
        .unwrap()
        .contains("will not re-arm"));
    let limit = kind(&lines, "rearm_limit_reached");
    assert_eq!(limit.len(), 1, "{lines:#?}");
    assert_eq!(limit[0]["type"], "warning");
    assert_eq!(limit[0]["rearms"], 1);
    assert!(
        limit[0]["message"]
            .as_str()
            .unwrap()
            .contains("experiment.max_rearms"),
        "{}",
        limit[0]
    );
    assert_eq!(
        kind(&lines, "arm_acknowledged").len(),
        2,
        "never armed a third time"
    );
}

#[test]
fn a_passive_csv_bench_that_stops_streaming_is_stalled_once_reopened_with_backoff_and_resumed() {
    use serialport::SerialPort;
    use std::io::Write;
    const PAUSE: Duration = Duration::from_secs(3);
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("passive.toml");
    std::fs::write(
        &cfg,
        "[device]\nprotocol = \"csv\"\nstall_timeout_ms = 300\nreconnect_initial_ms = 50\n\
         reconnect_max_ms = 1600\n[daemon]\nmax_run_s = 20.0\nstop_timeout_ms = 50\n",
    )
    .unwrap();
    let rows = propid_testkit::csv_bench::rows(propid_testkit::csv_bench::PLANT, 4_000);
    let (mut master, slave) = serialport::TTYPort::pair().unwrap();
    let port = slave.name().unwrap();
    master.set_timeout(Duration::from_millis(5)).unwrap();
    let mut d = Daemon::run(&cfg, &port, None);
    // paced like a bench (20 rows every 10 ms); 1 500 rows, silence, the other 2 500 rows
    let bench = std::thread::spawn(move || {
        let mut sink = [0u8; 256];
        let mut send = |master: &mut serialport::TTYPort, chunk: &[String]| {
            let _ = master.write_all(chunk.concat().as_bytes());
            let _ = std::io::Read::read(master, &mut sink); // what the daemon writes
            std::thread::sleep(Duration::from_millis(10));
        };
        let _ = master.write_all(propid_testkit::csv_bench::HEADER.as_bytes());
        for chunk in rows[..1_500].chunks(20) {
            send(&mut master, chunk);
        }
        let t = std::time::Instant::now();
        while t.elapsed() < PAUSE {
            send(&mut master, &[]);
        }
        for chunk in rows[1_500..].chunks(20) {
            send(&mut master, chunk);
        }
        std::thread::sleep(Duration::from_secs(8));
    });
    // rows again, and a model from them; stopped while the rows still flow
    d.wait_for(15.0, |l| l["kind"] == "link_resumed");
    d.wait_for(5.0, |l| l["type"] == "model");
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(5.0);
    drop(slave);
    drop(bench);
    assert!(status.success(), "{err}");
    assert_eq!(kind(&lines, "passive_bench").len(), 1, "{lines:#?}");
    // warned once, counted once
    let st = kind(&lines, "link_stalled");
    assert_eq!(st.len(), 1, "{lines:#?}");
    let s = stats(&lines);
    assert_eq!(s["stalls"], 1, "{s}");
    // the reopens back off (closed 50, 100, 200, 400, 800 ms after each 300 ms of silence:
    // five by the end of the 3 s pause, measured 5; at a fixed 50 ms there would be eight)
    let reopens = s["reconnects"].as_u64().unwrap();
    assert!((1..=6).contains(&reopens), "{s}");
    // one `reconnected` announced, then said when the rows return
    let at = position(&lines, "link_stalled");
    assert_eq!(kind(&lines[at..], "reconnected").len(), 1, "{lines:#?}");
    let resumed = kind(&lines, "link_resumed");
    assert_eq!(resumed.len(), 1, "{lines:#?}");
    assert_eq!(resumed[0]["type"], "event");
    assert!(
        resumed[0]["silent_ms"].as_u64().unwrap() >= 2_500,
        "{}",
        resumed[0]
    );
    let back = position(&lines, "link_resumed");
    assert!(back > at);
}

#[test]
fn demo_leaves_an_unanswered_command_on_a_silent_link_to_the_stall_watchdog_as_run_does() {
    let dir = tempfile::tempdir().unwrap();
    let sim_cfg = dir.path().join("sim.toml");
    // the stand freezes after 1 s with its port open (the default stall_timeout_ms is 1000)
    std::fs::write(
        &sim_cfg,
        "[plant]\nkind = \"second_order\"\n[faults]\nfreeze_after_s = 1.0\n",
    )
    .unwrap();
    let d = Daemon::start(&["demo", "--json", "--sim-config", sim_cfg.to_str().unwrap()]);
    let (status, lines, err) = d.finish(30.0);
    assert_eq!(status.code(), Some(8), "{err} {lines:#?}");
    assert!(
        kind(&lines, "link_failed").is_empty(),
        "a stall, not a link failure: {lines:#?}"
    );
    assert_eq!(kind(&lines, "link_stalled").len(), 1, "{lines:#?}");
    assert_eq!(stats(&lines)["stalls"], 1);
}
