//! Faults of the host, through the real binary (issue 12): stdout full or closed, bad and
//! unbounded inputs, exit codes that agree between `identify` and `replay`.

use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_propid");

/// A clean simulated-stand recording (4 s) in `dir`.
fn recording(dir: &Path) -> std::path::PathBuf {
    let rec = dir.join("rec.tsp");
    let cfg = crate::support::second_order_sim(dir);
    let out = Command::new(BIN)
        .args(["sim", "--config", &cfg, "--seconds", "4", "--record"])
        .arg(&rec)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    rec
}

/// `propid ARGS` with stdout to `/dev/full` (every write fails with ENOSPC).
fn to_dev_full(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .stdout(File::options().write(true).open("/dev/full").unwrap())
        .output()
        .unwrap()
}

/// `propid ARGS` whose stdout reader has gone away before it writes (EPIPE).
fn to_closed_pipe(args: &[&str]) -> (Option<i32>, String) {
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader leaves at once
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    (child.wait().unwrap().code(), err)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_full_stdout_is_exit_7_with_write_error_for_every_subcommand() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let rec = rec.to_str().unwrap();
    let walk = dir.path().join("walk");
    for args in [
        vec!["identify", "--json", rec],
        vec!["identify", rec],
        vec!["diagnose", "--json", rec],
        vec!["diagnose", rec],
        vec!["replay", rec],
        vec!["sim", "--seconds", "1", "--record", "/dev/null"],
        vec!["walkthrough", "--out", walk.to_str().unwrap()],
    ] {
        let o = to_dev_full(&args);
        assert_eq!(o.status.code(), Some(7), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("write error"),
            "{args:?}: {}",
            stderr(&o)
        );
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    }
}

#[test]
fn a_closed_pipe_ends_quietly_with_exit_0() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let rec = rec.to_str().unwrap();
    for args in [
        vec!["identify", "--json", rec],
        vec!["diagnose", "--json", rec],
        vec!["replay", rec],
    ] {
        let (code, err) = to_closed_pipe(&args);
        assert_eq!(code, Some(0), "{args:?}: {err}");
        assert_eq!(err, "", "{args:?}");
    }
}

#[test]
fn a_sample_period_read_in_the_wrong_unit_is_an_input_error() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("ns.csv");
    // a nanosecond time column read as µs: 1e6 s between samples
    let mut s = String::from("t_us,throttle,thrust_N\n");
    for k in 0..3000u64 {
        let u = 3000 + if (k / 50) % 2 == 1 { 500 } else { 0 };
        s += &format!("{},{u},{}\n", k * 1_000_000_000_000, u as f64 / 1000.0);
    }
    std::fs::write(&csv, s).unwrap();
    let o = Command::new(BIN)
        .args(["diagnose", csv.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("sample period 1000000 s"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn identify_and_replay_agree_on_missing_empty_and_undecodable_files() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.tsp");
    let empty = dir.path().join("empty.tsp");
    std::fs::write(&empty, b"").unwrap();
    let random = dir.path().join("random.bin");
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let bytes: Vec<u8> = (0..100_000)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // never 0x00 (no frame boundary to sync on), never `\r` nor `\n` (odd bytes, and
            // a CR, a line end since classic Mac text is read, made 0x0F): no line to read
            match (x >> 24) as u8 | 1 {
                b'\r' => 0x0f,
                b => b,
            }
        })
        .collect();
    std::fs::write(&random, bytes).unwrap();
    for (file, code) in [(&missing, 7), (&empty, 3), (&random, 3)] {
        for cmd in ["identify", "replay"] {
            let o = Command::new(BIN).arg(cmd).arg(file).output().unwrap();
            assert_eq!(
                o.status.code(),
                Some(code),
                "{cmd} {file:?}: {}",
                stderr(&o)
            );
        }
    }
}

#[test]
fn a_stream_of_zero_bytes_is_counted_and_refused() {
    let dir = tempfile::tempdir().unwrap();
    let zeros = dir.path().join("zeros.bin");
    std::fs::write(&zeros, vec![0u8; 1 << 20]).unwrap();
    let o = Command::new(BIN)
        .arg("replay")
        .arg(&zeros)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("no TSP/1 frame"), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let stats: serde_json::Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(stats["type"], "stats");
    assert_eq!(stats["empty_frames"], 1 << 20);
}

#[test]
fn an_endless_input_is_read_within_the_bound() {
    for cmd in ["identify", "replay"] {
        let o = Command::new(BIN).args([cmd, "/dev/zero"]).output().unwrap();
        assert_eq!(o.status.code(), Some(3), "{cmd}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("larger than 1073741824 bytes"),
            "{}",
            stderr(&o)
        );
    }
}

#[test]
fn a_bad_record_size_limit_is_a_usage_error() {
    let o = Command::new(BIN)
        .args(["run", "--port", "/nonexistent", "--record-max-bytes", "100"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--record-max-bytes 100"),
        "{}",
        stderr(&o)
    );
}
