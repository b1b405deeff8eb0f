//! `propid run` end to end, through the real binary over the real pty loopback: a worker slower
//! than the sampler (a tiny queue) is counted as overflows and lost samples, never waited for;
//! SIGTERM stops the stand like Ctrl-C; a second Ctrl-C while STOP is pending exits at once.

use crate::daemon_proc;

use daemon_proc::{
    daemon_config, dropped_total, kind, of_type, replay, sim_process, sim_stand, stats,
    stopped_by_signal, Daemon,
};
use std::time::{Duration, Instant};

#[test]
fn tiny_queue_overflows_are_counted_as_lost_samples_and_the_run_completes() {
    let dir = tempfile::tempdir().unwrap();
    // the smallest queue the config allows (16 items); the stand's 150 ms stalls may swallow
    // a command's ACK: re-sends cover 1 s, not 200 ms (a loaded machine stretches a stall)
    let cfg = daemon_config(
        dir.path(),
        "[0.4]",
        8,
        4,
        "retry_ms = 100\nmax_retries = 10\n[daemon]\nqueue_capacity = 16\n",
    );
    let rec = dir.path().join("run.tsp");
    // Stalls release 150 ms of samples at once: the sampler decodes a burst far faster than
    // the worker can take it from a 16-item queue.
    let sim = sim_stand(4000, |c| {
        c.faults.stalls_per_s = 4.0;
        c.faults.stall_ms = 150;
    });
    let port = sim.path().display().to_string();
    let d = Daemon::run(&cfg, &port, Some(&rec));
    let (status, lines, err) = d.finish(60.0);
    let report = sim.stop().unwrap();
    assert!(status.success(), "{status:?} {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(report.faults.stalls > 0, "{:?}", report.faults);
    let s = stats(&lines);
    let overflows = s["overflows"].as_u64().unwrap();
    let lost = s["samples_lost"].as_u64().unwrap();
    assert!(overflows > 0, "{s}");
    // the link lost nothing: every lost sample is a queued sample the worker never got
    assert_eq!(dropped_total(s), 0, "{s}");
    assert_eq!(s["gaps"], 0, "{s}");
    assert!(lost > 0 && lost <= overflows, "{s}");
    // the worker found the holes from the sample index and masked them (never bridged)
    let masked: u64 = kind(&lines, "overflow_gap")
        .iter()
        .map(|l| l["count"].as_u64().unwrap())
        .sum();
    assert!(masked > 0 && masked <= lost, "masked {masked}, {s}");
    // the replay of the recording is lossless and has every sample the sampler received
    let replayed = replay(&rec, &cfg);
    let r = stats(&replayed);
    assert_eq!(r["samples"], s["samples"]);
    assert_eq!(r["frames_ok"], s["frames_ok"]);
    assert_eq!(
        (r["samples_lost"].as_u64(), r["overflows"].as_u64()),
        (Some(0), Some(0))
    );
}

#[test]
fn sigterm_sends_stop_until_acknowledged_and_exits_zero_with_stats() {
    // exit 0 within 3 s, STOP acknowledged once, stats last, the stand executed commands
    let (lines, _) = stopped_by_signal(libc::SIGTERM);
    // the stand executed the STOP: it disarmed (its EVENT arrived before the ACK)
    assert!(!kind(&lines, "disarmed").is_empty(), "{lines:#?}");
    let s = stats(&lines);
    assert!(s["samples"].as_u64().unwrap() > 0);
    assert_eq!(of_type(&lines, "stats").len(), 1);
}

#[test]
fn second_ctrl_c_while_stop_is_pending_exits_at_once_keeping_what_was_published() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let cfg = daemon_config(dir.path(), "[0.4]", 1000, 4, "");
    // the stand in its own process, so that it can be frozen: STOP then goes unanswered and
    // the daemon would wait the whole stop timeout (1 s) for its ACK
    let stand = sim_process(&link, 30.0, &[]);
    let mut d = Daemon::run(&cfg, link.to_str().unwrap(), None);
    d.wait_for(10.0, |l| l["kind"] == "level_reached");
    daemon_proc::signal(stand.0.id(), libc::SIGSTOP);
    let t = Instant::now();
    d.signal(libc::SIGINT);
    std::thread::sleep(Duration::from_millis(100));
    d.signal(libc::SIGINT);
    let status = daemon_proc::wait_exit(&mut d.child, 5.0).expect("no exit");
    let elapsed = t.elapsed();
    daemon_proc::signal(stand.0.id(), libc::SIGCONT);
    drop(stand);
    let (_, lines, err) = d.finish(5.0);
    // shutdown.rs: a second signal exits at once with status 130
    assert_eq!(status.code(), Some(130), "{status:?} {err}");
    assert!(
        elapsed < Duration::from_millis(800),
        "exited after {elapsed:?}, not at once (stop timeout 1 s)"
    );
    // what was published before the signals is on stdout, every line whole
    assert_eq!(kind(&lines, "arm_acknowledged").len(), 1, "{lines:#?}");
    assert_eq!(kind(&lines, "level_reached").len(), 1, "{lines:#?}");
    // it did not wait for the ACK, nor write the stats line
    assert!(kind(&lines, "shutdown_stop_acknowledged").is_empty());
    assert!(of_type(&lines, "stats").is_empty(), "{lines:#?}");
}
