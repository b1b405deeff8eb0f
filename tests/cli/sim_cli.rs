//! `propid sim` as a process: record mode, the pty with --link, SIGINT, refused configs.

use std::io::{BufRead, BufReader, Read};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use propid_wire::protocol::{encode_frame, Decoder, EventCode, Message, MAX_FRAME_LEN};

fn propid() -> Command {
    Command::new(env!("CARGO_BIN_EXE_propid"))
}

#[test]
fn record_writes_a_decodable_recording_of_the_whole_experiment() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("run.tsp");
    let out = propid()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["sim", "--record"])
        .arg(&file)
        .args(["--seconds", "30"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["type"], "sim_record");
    assert_eq!(summary["finished"], true);
    let bytes = std::fs::read(&file).unwrap();
    let mut dec = Decoder::new();
    let mut starts = 0;
    dec.push(&bytes, |f| {
        if matches!(f.msg, Message::Event(e) if e.code == EventCode::ImpulseStart) {
            starts += 1;
        }
    });
    assert_eq!(starts, 24, "3 levels x 8 pulses (config/sim.toml)");
    assert_eq!(summary["pulses"], 24);
    assert_eq!(dec.stats().dropped.total(), 0);
}

#[test]
fn pty_with_link_answers_and_sigint_ends_with_the_stats_line() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("stand");
    let mut child = propid()
        .args(["sim", "--seconds", "20", "--link"])
        .arg(&link)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    stdout.read_line(&mut first).unwrap();
    assert_eq!(first.trim_end(), link.to_str().unwrap());
    let mut port = serialport::new(link.to_string_lossy(), 921_600)
        .timeout(Duration::from_millis(20))
        .open()
        .unwrap();
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(5, &Message::HelloReq, &mut buf);
    port.write_all(&buf[..n]).unwrap();
    let mut dec = Decoder::new();
    let mut acked = false;
    let t0 = Instant::now();
    let mut rx = [0u8; 1024];
    while !acked && t0.elapsed() < Duration::from_secs(3) {
        if let Ok(n) = port.read(&mut rx) {
            dec.push(&rx[..n], |f| {
                acked |= matches!(f.msg, Message::Ack(a) if a.cmd_seq == 5);
            });
        }
    }
    assert!(acked, "ACK of HELLO_REQ through the binary's pty");
    drop(port);
    std::thread::sleep(Duration::from_millis(50)); // some samples
                                                   // SAFETY: signalling our own child process.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGINT);
    }
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = child.wait().unwrap();
    assert!(status.success(), "{status:?}");
    let stats: serde_json::Value = serde_json::from_str(rest.trim()).unwrap();
    assert_eq!(stats["type"], "sim_stats");
    assert_eq!(stats["ended"], "stopped");
    assert!(
        stats["firmware"]["samples"].as_u64().unwrap() > 0,
        "{stats}"
    );
    assert!(!link.exists(), "the link is removed at the end");
}

#[test]
fn refused_config_names_the_key_and_exits_5() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("bad.toml");
    for (text, key) in [
        ("[stand]\nsample_rte_hz = 100\n", "sample_rte_hz"),
        (
            "[faults]\nbit_flip_per_byte = nan\n",
            "faults.bit_flip_per_byte",
        ),
        (
            "[experiment]\nlevels = [0.3, 1.5]\n",
            "experiment.levels[1]",
        ),
        ("[plant]\nzeta = -1.0\n", "plant.zeta"),
    ] {
        std::fs::write(&cfg, text).unwrap();
        let out = propid()
            .args(["sim", "--seconds", "1", "--config"])
            .arg(&cfg)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(5), "{err}");
        assert!(err.contains(key), "{key}: {err}");
    }
    let out = propid()
        .args(["sim", "--seconds", "1", "--bit-flips", "0.5"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(5));
    let out = propid()
        .args(["sim", "--record", "x.tsp"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "--record needs --seconds");
}
