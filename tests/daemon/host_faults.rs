//! Faults of the host around a live daemon (issue 12), through the real binary against the
//! simulated stand: the recording (full disk, never overwritten, flushed, rotated, a pipe that
//! is never read), the plan ended on a fault (exit 8), the socket (client cap, a live socket
//! kept, mode), a second SIGTERM (143), FIFOs and files where outputs go, a signal before the
//! run starts.

use crate::daemon_proc;

use daemon_proc::{daemon_config, kind, of_type, sim_process, sim_stand, stats, Daemon};
use std::os::unix::fs::PermissionsExt;
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::time::{Duration, Instant};

#[test]
fn a_recording_on_a_full_disk_is_reported_and_the_run_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.4]", 4, 4, "");
    let sim = sim_stand(500, |_| {});
    let port = sim.path().display().to_string();
    let d = Daemon::run(&cfg, &port, Some(Path::new("/dev/full")));
    let (status, lines, err) = d.finish(30.0);
    let _ = sim.stop();
    assert_eq!(status.code(), Some(7), "{err}");
    assert!(err.contains("write error: recording /dev/full"), "{err}");
    let failed = kind(&lines, "output_failed");
    assert_eq!(failed.len(), 1, "{lines:#?}");
    assert_eq!(failed[0]["sink"], "record");
    assert_eq!(failed[0]["path"], "/dev/full");
    // the run went on: the plan finished, models and the stats line are published
    assert_eq!(kind(&lines, "plan_finished").len(), 1, "{lines:#?}");
    assert!(!of_type(&lines, "model").is_empty(), "{lines:#?}");
    let s = stats(&lines);
    assert_eq!(s["record_bytes_written"], 0);
    assert!(s["bytes"].as_u64().unwrap() > 0);
}

#[test]
fn a_recording_never_overwrites_is_flushed_and_rotates() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4, "");
    let rec = dir.path().join("rec.tsp");
    std::fs::write(&rec, b"an earlier run").unwrap();
    std::fs::write(dir.path().join("rec.2.tsp"), b"another").unwrap();
    // a FIFO without a reader where the next file would go: skipped, never opened (it blocks)
    mkfifo(&dir.path().join("rec.3.tsp"));
    let sim = sim_stand(1000, |_| {});
    let port = sim.path().display().to_string();
    let mut d = Daemon::start(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--port",
        &port,
        "--record",
        rec.to_str().unwrap(),
        "--record-max-bytes",
        "65536",
    ]);
    let first = d.wait_for(10.0, |l| l["kind"] == "recording");
    let first_path = dir.path().join("rec.1.tsp");
    assert_eq!(first["path"], first_path.to_str().unwrap());
    d.wait_for(10.0, |l| l["kind"] == "level_reached");
    // flushed while running: the file grows in every 250 ms (the buffer holds 64 KiB, ~2 s)
    let size = |p: &Path| std::fs::metadata(p).map_or(0, |m| m.len());
    let mut last = size(&first_path);
    for _ in 0..3 {
        std::thread::sleep(Duration::from_millis(250));
        let now = size(&first_path);
        assert!(now > last || now >= 60_000, "{last} -> {now}");
        last = now;
    }
    // run past two more files, then stop
    d.wait_for(20.0, |l| {
        l["kind"] == "recording" && l["path"].as_str().is_some_and(|p| p.ends_with("rec.5.tsp"))
    });
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(10.0);
    let _ = sim.stop();
    assert!(status.success(), "{err}");
    assert_eq!(std::fs::read(&rec).unwrap(), b"an earlier run");
    assert_eq!(
        std::fs::read(dir.path().join("rec.2.tsp")).unwrap(),
        b"another"
    );
    let files: Vec<String> = kind(&lines, "recording")
        .iter()
        .map(|l| l["path"].as_str().unwrap().to_string())
        .collect();
    let names: Vec<_> = files
        .iter()
        .map(|p| {
            Path::new(p)
                .file_name()
                .unwrap()
                .to_str()
                .unwrap()
                .to_string()
        })
        .collect();
    assert_eq!(
        names[..3],
        ["rec.1.tsp", "rec.4.tsp", "rec.5.tsp"],
        "{names:?}"
    );
    let total: u64 = files.iter().map(|p| size(Path::new(p))).sum();
    let s = stats(&lines);
    assert_eq!(s["record_bytes_written"], total);
    assert_eq!(s["record_bytes_dropped"], 0);
    assert_eq!(s["bytes"], total, "every byte received is recorded");
    for p in &files[..files.len() - 1] {
        assert!(size(Path::new(p)) <= 65_536, "{p}");
    }
}

#[test]
fn a_device_reset_ends_the_run_with_exit_8() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4, "");
    let sim = sim_process(
        &link,
        20.0,
        &["--hangup-after", "1.5", "--reopen-after", "200"],
    );
    let t = Instant::now();
    let d = Daemon::run(&cfg, link.to_str().unwrap(), None);
    // no signal: the daemon stops by itself once the plan is over on a fault
    let (status, lines, err) = d.finish(15.0);
    drop(sim);
    assert_eq!(status.code(), Some(8), "{err} {lines:#?}");
    assert!(
        err.contains("the experiment plan ended on a fault"),
        "{err}"
    );
    assert!(t.elapsed() < Duration::from_secs(10));
    // the plan says why (the new boot's refusal of a pulse may come before its HELLO)
    assert!(
        !kind(&lines, "device_reset").is_empty() || !kind(&lines, "command_refused").is_empty(),
        "{lines:#?}"
    );
    assert_eq!(kind(&lines, "arm_acknowledged").len(), 1, "never re-armed");
    stats(&lines);
}

/// A daemon serving `socket` (extra `[publish]` keys in `publish`) against a stand at 200 Hz.
fn socket_daemon(dir: &Path, socket: &Path, publish: &str) -> (Daemon, propid_sim::pty::SimHandle) {
    let extra = format!(
        "[publish]\nsocket = {:?}\n{publish}",
        socket.to_str().unwrap()
    );
    let cfg = daemon_config(dir, "[0.4]", 1000, 4, &extra);
    let sim = sim_stand(200, |_| {});
    let port = sim.path().display().to_string();
    let mut d = Daemon::run(&cfg, &port, None);
    d.wait_for(10.0, |l| l["kind"] == "connected");
    (d, sim)
}

#[test]
fn socket_clients_are_capped_and_the_rest_refused_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("p.sock");
    let (d, sim) = socket_daemon(dir.path(), &sock, "max_clients = 3\n");
    let mut clients = Vec::new();
    for _ in 0..20 {
        clients.push(UnixStream::connect(&sock).unwrap());
        std::thread::sleep(Duration::from_millis(30));
    }
    std::thread::sleep(Duration::from_millis(300));
    d.signal(libc::SIGINT);
    let (status, lines, err) = d.finish(10.0);
    let _ = sim.stop();
    assert!(status.success(), "{err}");
    assert_eq!(stats(&lines)["clients_refused"], 17, "{:?}", stats(&lines));
    // a refused client is told why, then closed
    use std::io::Read;
    let mut text = String::new();
    clients[10].read_to_string(&mut text).unwrap();
    assert!(text.contains("too_many_clients"), "{text}");
}

#[test]
fn a_live_socket_is_never_taken_over_and_is_owner_only() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("p.sock");
    let (d, sim) = socket_daemon(dir.path(), &sock, "");
    let mode = std::fs::metadata(&sock).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600);
    // a second daemon on the same path refuses to start and leaves the socket alone
    let other = tempfile::tempdir().unwrap();
    let cfg2 = daemon_config(
        other.path(),
        "[0.4]",
        4,
        4,
        &format!("[publish]\nsocket = {:?}\n", sock.to_str().unwrap()),
    );
    let out = std::process::Command::new(daemon_proc::BIN)
        .args([
            "run",
            "--config",
            cfg2.to_str().unwrap(),
            "--port",
            "/nonexistent",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(7), "{err}");
    assert!(err.contains("is in use") || err.contains("in use"), "{err}");
    assert!(
        UnixStream::connect(&sock).is_ok(),
        "the first daemon still serves"
    );
    d.signal(libc::SIGINT);
    let (status, _, err) = d.finish(10.0);
    let _ = sim.stop();
    assert!(status.success(), "{err}");
    assert!(!sock.exists(), "removed at exit by its owner");
    // a stale socket file (no daemon behind it) is replaced
    let stale = std::os::unix::net::UnixListener::bind(&sock).unwrap();
    drop(stale);
    assert!(sock.exists());
    let (d, sim) = socket_daemon(dir.path(), &sock, "");
    assert!(UnixStream::connect(&sock).is_ok());
    d.signal(libc::SIGINT);
    let (status, _, err) = d.finish(10.0);
    let _ = sim.stop();
    assert!(status.success(), "{err}");
}

#[test]
fn a_socket_group_gives_mode_0660_and_an_unknown_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("p.sock");
    let gid = unsafe { libc::getgid() };
    let (d, sim) = socket_daemon(dir.path(), &sock, &format!("socket_group = \"{gid}\"\n"));
    let meta = std::fs::metadata(&sock).unwrap();
    assert_eq!(meta.permissions().mode() & 0o777, 0o660);
    use std::os::unix::fs::MetadataExt;
    assert_eq!(meta.gid(), gid);
    d.signal(libc::SIGINT);
    let _ = d.finish(10.0);
    let _ = sim.stop();
    let cfg = daemon_config(
        dir.path(),
        "[0.4]",
        4,
        4,
        "[publish]\nsocket_group = \"no-such-group-propid\"\n",
    );
    let out = std::process::Command::new(daemon_proc::BIN)
        .args(["run", "--config", cfg.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(5), "{err}");
    assert!(err.contains("publish.socket_group"), "{err}");
}

#[test]
fn a_second_sigterm_exits_143() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4, "");
    // the stand frozen: STOP goes unanswered and the daemon waits its stop timeout (1 s)
    let stand = sim_process(&link, 30.0, &[]);
    let mut d = Daemon::run(&cfg, link.to_str().unwrap(), None);
    d.wait_for(10.0, |l| l["kind"] == "level_reached");
    daemon_proc::signal(stand.0.id(), libc::SIGSTOP);
    d.signal(libc::SIGTERM);
    std::thread::sleep(Duration::from_millis(100));
    d.signal(libc::SIGTERM);
    let status = daemon_proc::wait_exit(&mut d.child, 5.0).expect("no exit");
    daemon_proc::signal(stand.0.id(), libc::SIGCONT);
    drop(stand);
    assert_eq!(status.code(), Some(143), "{status:?}");
}

/// A FIFO at `path` (no reader, no writer yet).
fn mkfifo(path: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
}

/// The read end of the FIFO at `path`, opened without waiting for a writer, never read.
fn reader_that_never_reads(path: &Path) -> std::fs::File {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .unwrap()
}

/// `propid ARGS` to its exit (killed, and a panic, after `secs`): the status and stderr.
fn exit_of(args: &[&str], secs: f64) -> (std::process::ExitStatus, String) {
    let d = Daemon::start(args);
    let (status, _, err) = d.finish(secs);
    (status, err)
}

#[test]
fn a_recording_to_a_pipe_whose_reader_never_reads_drops_counts_and_the_stand_keeps_running() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("rec.pipe");
    mkfifo(&fifo);
    let _reader = reader_that_never_reads(&fifo);
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4, "");
    // 20 kHz: the pipe (64 KiB) and the recorder's chunks (2 MiB) fill within seconds
    let sim = sim_stand(20_000, |_| {});
    let port = sim.path().display().to_string();
    let mut d = Daemon::run(&cfg, &port, Some(&fifo));
    let warning = d.wait_for(30.0, |l| l["kind"] == "output_failed");
    assert_eq!(warning["sink"], "record");
    assert_eq!(warning["path"], fifo.to_str().unwrap());
    // past the stand's watchdog many times over: heartbeats go on whatever the pipe does
    std::thread::sleep(Duration::from_millis(1500));
    let t = Instant::now();
    d.signal(libc::SIGTERM);
    let (status, lines, err) = d.finish(10.0);
    let report = sim.stop().unwrap();
    // STOP first, then at most CLOSE_TIMEOUT for the recorder
    assert!(t.elapsed() < Duration::from_secs(4), "{:?}", t.elapsed());
    assert_eq!(status.code(), Some(7), "{err}");
    assert!(
        err.contains("fell behind") && err.contains("bytes dropped"),
        "{err}"
    );
    assert_eq!(
        kind(&lines, "shutdown_stop_acknowledged").len(),
        1,
        "{lines:#?}"
    );
    assert_eq!(kind(&lines, "output_failed").len(), 1, "once: {lines:#?}");
    assert_eq!(report.firmware.watchdog_trips, 0, "{report:?}");
    let s = stats(&lines);
    let (written, dropped) = (
        s["record_bytes_written"].as_u64().unwrap(),
        s["record_bytes_dropped"].as_u64().unwrap(),
    );
    assert!(dropped > 0 && written < 1 << 20, "{s}");
    assert_eq!(written + dropped, s["bytes"].as_u64().unwrap(), "{s}");
}

#[test]
fn fifos_and_files_where_outputs_go_are_clear_errors_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("out.fifo");
    mkfifo(&fifo);
    // the publish file a FIFO (opening it would wait for a reader)
    let cfg = daemon_config(
        dir.path(),
        "[0.4]",
        4,
        4,
        &format!("[publish]\nfile = {:?}\n", fifo.to_str().unwrap()),
    );
    let cfg = cfg.to_str().unwrap();
    let (status, err) = exit_of(&["run", "--config", cfg, "--port", "/nonexistent"], 10.0);
    assert_eq!(status.code(), Some(7), "{err}");
    assert!(
        err.contains("open publish file") && err.contains("a FIFO"),
        "{err}"
    );
    // the socket's path a regular file: named, kept
    let file = dir.path().join("p.sock");
    std::fs::write(&file, b"not a socket").unwrap();
    let cfg = daemon_config(
        dir.path(),
        "[0.4]",
        4,
        4,
        &format!("[publish]\nsocket = {:?}\n", file.to_str().unwrap()),
    );
    let cfg = cfg.to_str().unwrap();
    let (status, err) = exit_of(&["run", "--config", cfg, "--port", "/nonexistent"], 10.0);
    assert_eq!(status.code(), Some(7), "{err}");
    assert!(
        err.contains(file.to_str().unwrap()) && err.contains("a regular file, not a socket"),
        "{err}"
    );
    assert_eq!(std::fs::read(&file).unwrap(), b"not a socket");
    // the recording a FIFO nobody reads: refused before the stand is commanded
    let cfg = daemon_config(dir.path(), "[0.4]", 4, 4, "");
    let sim = sim_stand(200, |_| {});
    let port = sim.path().display().to_string();
    let d = Daemon::run(&cfg, &port, Some(&fifo));
    let (status, _, err) = d.finish(10.0);
    let report = sim.stop().unwrap();
    assert_eq!(status.code(), Some(7), "{err}");
    assert!(err.contains("FIFO with no reader"), "{err}");
    assert_eq!(report.firmware.executed, 0, "{report:?}");
}

#[test]
fn the_first_signal_ends_a_replay_waiting_for_a_fifo_writer() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("in.fifo");
    mkfifo(&fifo);
    let mut d = Daemon::start(&["replay", fifo.to_str().unwrap()]);
    std::thread::sleep(Duration::from_millis(500));
    assert!(d.child.try_wait().unwrap().is_none(), "waits for a writer");
    d.signal(libc::SIGTERM);
    let (status, _, err) = d.finish(5.0);
    assert_eq!(status.code(), Some(143), "{err}");
    assert!(err.contains("is a FIFO"), "{err}");
    assert!(err.contains("before the run started"), "{err}");
}
