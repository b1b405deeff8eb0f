//! The reference firmware (firmware/): its framing against the host's encoder and decoder, and
//! its ELF on an emulated ATmega328P (firmware/harness, simavr) in the loop with the simulated
//! motor, driven by the real `propid run`. Tests that need avr-gcc or simavr skip with a message
//! when they are missing (scripts/test.sh installs them).

#[path = "../daemon/daemon_proc.rs"]
mod daemon_proc;

use daemon_proc::{dropped_total, kind, of_type, stats, Daemon, KillOnDrop, BIN};
use propid_wire::protocol::message::msg_type;
use propid_wire::protocol::{encode_raw, AckResult, Decoder, Message, MAX_FRAME_LEN};
use rand::{Rng, SeedableRng};
use serde_json::Value;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `make -C firmware BUILD=build TARGETS`; false (with a message) when the tools are missing.
fn make(build: &Path, targets: &[&str], tools: &[&str]) -> bool {
    for t in tools {
        let found = Command::new("sh")
            .args(["-c", &format!("command -v {t} || test -e {t}")])
            .stdout(Stdio::null())
            .status()
            .map(|s| s.success())
            .unwrap_or(false);
        if !found {
            eprintln!("SKIPPED: {t} is missing (scripts/install_avr_tools.sh installs it)");
            return false;
        }
    }
    let out = Command::new("make")
        .arg("-s")
        .arg("-C")
        .arg(repo().join("firmware"))
        .arg(format!("BUILD={}", build.display()))
        .args(targets)
        .output()
        .expect("make");
    assert!(
        out.status.success(),
        "make {targets:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    true
}

#[test]
fn firmware_frames_are_byte_identical_to_the_host_encoder_and_decode_its_frames() {
    let dir = tempfile::tempdir().unwrap();
    if !make(dir.path(), &["frames"], &["cc", "make"]) {
        return;
    }
    let mut child = Command::new(dir.path().join("frames"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    let mut output = BufReader::new(child.stdout.take().unwrap());
    let mut ask = |line: String| {
        input.write_all(line.as_bytes()).unwrap();
        input.flush().unwrap();
        let mut answer = String::new();
        output.read_line(&mut answer).unwrap();
        answer.trim().to_string()
    };
    let mut rng = rand::rngs::StdRng::seed_from_u64(32);
    for case in 0..400 {
        // zeros are frequent (COBS's blocks), lengths up to the largest body, 0xFF runs
        let len = if case < 4 {
            250
        } else {
            rng.gen_range(0..=247)
        };
        let payload: Vec<u8> = (0..len)
            .map(|_| match rng.gen_range(0..4) {
                0 => 0,
                1 if case % 7 == 0 => 0xFF,
                _ => rng.gen(),
            })
            .collect();
        let (t, seq) = (rng.gen_range(1..=0x7F), rng.gen::<u16>());
        let mut frame = vec![0u8; MAX_FRAME_LEN + 8];
        let n = encode_raw(1, t, seq, &payload, &mut frame).unwrap_or(0);
        let hex_payload = hex(&payload);
        let c = ask(format!("E {t} {seq} {hex_payload}\n"));
        assert_eq!(c, hex(&frame[..n]), "type {t} seq {seq} len {len}");
        if n == 0 {
            continue;
        }
        let d = ask(format!("D {}\n", hex(&frame[..n - 1])));
        assert_eq!(d, format!("0 {t} {seq} {hex_payload}").trim_end());
    }
    // a flipped bit is a CRC error, never a frame
    let mut frame = [0u8; 32];
    let n = encode_raw(1, msg_type::STOP, 10, &[], &mut frame).unwrap();
    frame[2] ^= 0x04;
    assert!(ask(format!("D {}\n", hex(&frame[..n - 1]))).starts_with("-3 "));
    let _ = child.kill();
    let _ = child.wait();
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// The harness running the firmware's ELF, its stdout lines (ESC widths, stats) on a channel.
struct Stand {
    _child: KillOnDrop,
    link: PathBuf,
    rx: Receiver<Value>,
}

impl Stand {
    /// Builds the ELF and the harness into `dir` and starts it; `None` when the tools are missing.
    fn start(dir: &Path, seconds: f64) -> Option<Stand> {
        let tools = ["avr-gcc", "cc", "make", "/usr/include/simavr/sim_avr.h"];
        if !make(dir, &["firmware", "harness"], &tools) {
            return None;
        }
        let link = dir.join("stand");
        let plant = format!(
            "'{BIN}' sim --plant-pipe --config '{}'",
            repo().join("config/sim.toml").display()
        );
        let mut child = Command::new(dir.join("harness"))
            .arg(dir.join("propid-fw.elf"))
            .arg("--link")
            .arg(&link)
            .args(["--seconds", &seconds.to_string(), "--plant", &plant])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let out = BufReader::new(child.stdout.take().unwrap());
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for l in out.lines().map_while(Result::ok) {
                let v = serde_json::from_str(&l).unwrap_or(Value::String(l));
                if tx.send(v).is_err() {
                    return;
                }
            }
        });
        let guard = KillOnDrop(child);
        let t = Instant::now();
        while !link.exists() {
            assert!(t.elapsed() < Duration::from_secs(10), "no pty link");
            std::thread::sleep(Duration::from_millis(20));
        }
        Some(Stand {
            _child: guard,
            link,
            rx,
        })
    }

    /// ESC widths reported until `pred` holds for one (panics after `secs`): (t_s, µs) pairs.
    fn esc_until(&self, secs: f64, pred: impl Fn(f64) -> bool) -> Vec<(f64, f64)> {
        let end = Instant::now() + Duration::from_secs_f64(secs);
        let mut seen = Vec::new();
        loop {
            let left = end.saturating_duration_since(Instant::now());
            let v = self
                .rx
                .recv_timeout(left)
                .unwrap_or_else(|_| panic!("no matching ESC width; saw {seen:?}"));
            if let Some(us) = v["esc_us"].as_f64() {
                seen.push((v["t_s"].as_f64().unwrap(), us));
                if pred(us) {
                    return seen;
                }
            }
        }
    }
}

/// A daemon config: `levels`, `pulses` per level, 4 pulses per model, `device` lines added to
/// `[device]`.
fn config(dir: &Path, levels: &str, pulses: u32, device: &str) -> PathBuf {
    let p = dir.join("propid.toml");
    let text = format!(
        "[device]\nbaud = 250000\nreconnect_initial_ms = 50\nreconnect_max_ms = 500\n{device}\n\
         [identify]\npulses_per_model = 4\n\
         [experiment]\nlevels = {levels}\nramp_ms = 300\nsettle_ms = 500\n\
         pulse_amplitudes = [0.1, 0.15]\npulse_width_samples = 2\npulse_spacing_ms = 250\n\
         pulses_per_level = {pulses}\n"
    );
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn pulses_plan_on_the_emulated_firmware_publishes_models_and_disarms() {
    let dir = tempfile::tempdir().unwrap();
    let Some(stand) = Stand::start(dir.path(), 60.0) else {
        return;
    };
    let cfg = config(dir.path(), "[0.3, 0.5]", 8, "");
    let rec = dir.path().join("run.tsp");
    let d = Daemon::run(&cfg, &stand.link.display().to_string(), Some(&rec));
    let (status, lines, err) = d.finish(60.0);
    assert!(status.success(), "{status:?} {err}");
    assert_eq!(kind(&lines, "plan_finished").len(), 1, "{lines:#?}");
    assert!(!kind(&lines, "disarmed").is_empty(), "{lines:#?}");
    // the firmware's frames decode (its framing is the host's: see the test above); simavr's
    // pty bridge drops bytes when its thread waits more than ~20 ms (a 512-byte FIFO at 250
    // kbaud) on a loaded machine, so a few losses are the bridge's, not the firmware's
    let s = stats(&lines);
    assert!(s["frames_ok"].as_u64().unwrap() > 1000, "{s}");
    assert!(dropped_total(s) <= 4, "{s}");
    assert!(s["gaps"].as_u64().unwrap() <= 4, "{s}");
    // the models: the motor's small-signal gain at each level (as fitted to pulses of both
    // signs), within the tolerance of a 200 Hz stand with HX711 quantisation and noise
    let sim = propid_sim::SimConfig::load(&repo().join("config/sim.toml")).unwrap();
    let models = of_type(&lines, "model");
    assert_eq!(models.len(), 4, "{lines:#?}");
    for m in &models {
        let u0 = m["operating_point"].as_f64().unwrap();
        let truth = sim.plant.linearise(u0, 0.005, 5.0).unwrap();
        let g = truth.gain_n_per_throttle * truth.pulse_gain_factor;
        let got = m["dc_gain"].as_f64().unwrap();
        assert!(
            (got / g - 1.0).abs() < 0.15,
            "at {u0}: dc gain {got}, truth {g}"
        );
        let tau = m["time_constants_s"][0].as_f64().unwrap();
        let (lo, hi) = (truth.tau_up_s, truth.tau_down_s);
        assert!(
            tau > 0.7 * lo && tau < 1.3 * hi,
            "at {u0}: tau {tau} vs {lo}..{hi}"
        );
    }
    // the recording holds the firmware's ACK of the plan's closing DISARM, OK
    let bytes = std::fs::read(&rec).unwrap();
    let mut disarm_acked = false;
    Decoder::new().push(&bytes, |f| {
        if let Message::Ack(a) = f.msg {
            disarm_acked |= a.cmd_type == msg_type::DISARM && a.result == AckResult::Ok;
        }
    });
    assert!(disarm_acked, "no ACK of DISARM in the recording");
    // and the ESC is back at its minimum
    stand.esc_until(5.0, |us| us < 1010.0);
}

#[test]
fn csv_fallback_runs_the_plan_when_the_host_speaks_csv() {
    let dir = tempfile::tempdir().unwrap();
    let Some(stand) = Stand::start(dir.path(), 60.0) else {
        return;
    };
    // the daemon's CSV link sends text commands: the firmware answers in CSV from the first
    let cfg = config(dir.path(), "[0.4]", 8, "protocol = \"csv\"");
    let d = Daemon::run(&cfg, &stand.link.display().to_string(), None);
    let (status, lines, err) = d.finish(60.0);
    assert!(status.success(), "{status:?} {err}");
    assert_eq!(kind(&lines, "plan_finished").len(), 1, "{lines:#?}");
    assert!(!kind(&lines, "disarmed").is_empty(), "{lines:#?}");
    assert!(!of_type(&lines, "model").is_empty(), "{lines:#?}");
    let s = stats(&lines);
    assert_eq!(s["wire"], "csv", "{s}");
    stand.esc_until(5.0, |us| us < 1010.0);
}

#[test]
fn sigterm_stop_is_acknowledged_and_after_sigkill_the_firmware_watchdog_stops_the_motor() {
    let dir = tempfile::tempdir().unwrap();
    let Some(stand) = Stand::start(dir.path(), 90.0) else {
        return;
    };
    let cfg = config(dir.path(), "[0.4]", 1000, "");
    let port = stand.link.display().to_string();
    // SIGTERM: the daemon sends STOP until the firmware acknowledges it; the ESC is back at
    // its minimum
    let mut d = Daemon::run(&cfg, &port, None);
    d.wait_for(20.0, |l| l["kind"] == "level_reached");
    stand.esc_until(5.0, |us| us > 1300.0);
    d.signal(libc::SIGTERM);
    let (status, lines, err) = d.finish(10.0);
    assert!(status.success(), "{status:?} {err}");
    assert_eq!(
        kind(&lines, "shutdown_stop_acknowledged").len(),
        1,
        "{lines:#?}"
    );
    stand.esc_until(5.0, |us| us < 1010.0);
    // SIGKILL: nothing stops the motor but the firmware's own watchdog (500 ms without a
    // heartbeat), which the same stand, re-armed by a new daemon, then shows
    let mut d = Daemon::run(&cfg, &port, None);
    d.wait_for(20.0, |l| l["kind"] == "level_reached");
    let spun = stand.esc_until(5.0, |us| us > 1300.0);
    let t_spun = spun.last().unwrap().0;
    d.signal(libc::SIGKILL);
    let _ = d.finish(5.0);
    let back = stand.esc_until(5.0, |us| us < 1010.0);
    let (t_stop, _) = *back.last().unwrap();
    assert!(t_stop > t_spun, "{back:?}");
}

#[test]
fn a_storm_of_bad_frames_while_armed_stops_the_motor() {
    use propid_wire::protocol::{encode_frame, Arm, SetThrottle};
    let dir = tempfile::tempdir().unwrap();
    let Some(stand) = Stand::start(dir.path(), 60.0) else {
        return;
    };
    let mut port = serialport::new(stand.link.to_string_lossy(), 250_000)
        .timeout(Duration::from_millis(10))
        .open()
        .unwrap();
    let mut seq = 0u16;
    let mut send = |port: &mut Box<dyn serialport::SerialPort>, msg: Message| {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(seq, &msg, &mut buf);
        seq += 1;
        port.write_all(&buf[..n]).unwrap();
    };
    let drain = |port: &mut Box<dyn serialport::SerialPort>| {
        let mut sink = [0u8; 4096];
        let _ = port.read(&mut sink);
    };
    send(&mut port, Message::Arm(Arm::new(500)));
    send(
        &mut port,
        Message::SetThrottle(SetThrottle {
            level: 4000,
            ramp_ms: 0,
        }),
    );
    // heartbeats until the ESC runs at the level, then garbage: 20 frames with a bad CRC
    let t = Instant::now();
    let mut spun = Vec::new();
    while spun.is_empty() {
        assert!(t.elapsed() < Duration::from_secs(5), "the ESC never ran");
        send(&mut port, Message::Heartbeat);
        drain(&mut port);
        std::thread::sleep(Duration::from_millis(50));
        while let Ok(v) = stand.rx.try_recv() {
            if v["esc_us"].as_f64().is_some_and(|us| us > 1300.0) {
                spun.push(v);
            }
        }
    }
    for i in 0..20u8 {
        port.write_all(&[0x05, 0x01, 0x07, i, 0x99, 0x00]).unwrap();
    }
    // heartbeats go on (the watchdog is fed): only the storm can stop the motor
    let t = Instant::now();
    loop {
        assert!(
            t.elapsed() < Duration::from_secs(3),
            "the storm did not stop the motor"
        );
        send(&mut port, Message::Heartbeat);
        drain(&mut port);
        std::thread::sleep(Duration::from_millis(50));
        if stand
            .rx
            .try_iter()
            .any(|v| v["esc_us"].as_f64().is_some_and(|us| us < 1010.0))
        {
            break;
        }
    }
}

#[test]
fn a_current_limit_trips_through_the_emulated_firmware_and_the_motor_stops() {
    let dir = tempfile::tempdir().unwrap();
    let Some(stand) = Stand::start(dir.path(), 60.0) else {
        return;
    };
    // config/sim.toml's motor draws about 2 A at 0.3 and 8 A at 0.5 (0.4 + 8 (T/T_ref)^1.5),
    // read by the firmware on its ADC from the harness's current sensor
    let cfg = config(dir.path(), "[0.3, 0.5]", 8, "");
    let mut text = std::fs::read_to_string(&cfg).unwrap();
    text += "[limits]\nmax_current_a = 5.0\n";
    std::fs::write(&cfg, text).unwrap();
    let d = Daemon::run(&cfg, &stand.link.display().to_string(), None);
    let (status, lines, err) = d.finish(60.0);
    assert_eq!(status.code(), Some(8), "{err} {lines:#?}");
    let trips = kind(&lines, "limit_tripped");
    assert_eq!(trips.len(), 1, "{lines:#?}");
    assert_eq!(trips[0]["which"], "max_current_a");
    let value = trips[0]["value"].as_f64().unwrap();
    eprintln!("tripped: {}", trips[0]);
    assert!(value > 5.0 && value < 9.0, "{}", trips[0]);
    assert_eq!(kind(&lines, "level_done").len(), 1, "{lines:#?}");
    assert!(kind(&lines, "plan_finished").is_empty());
    assert!(!kind(&lines, "disarmed").is_empty(), "{lines:#?}");
    // the ESC is back at its minimum
    stand.esc_until(5.0, |us| us < 1010.0);
}

/// A staircase, a ramp and a chirp (`[experiment] kind`, the keys `scripts/firmware_loopback.sh`
/// uses, shortened) on the emulated firmware: each plan finishes and disarms, and publishes its
/// lines; the staircase's map follows the motor's steady thrust.
#[test]
fn each_experiment_kind_on_the_emulated_firmware_publishes_its_lines_and_disarms() {
    let sim = propid_sim::SimConfig::load(&repo().join("config/sim.toml")).unwrap();
    for (name, keys, wants) in [
        (
            "staircase",
            "kind = \"staircase\"\nlevels = [0.3, 0.5]\nhold_ms = 1500\n",
            "static_map",
        ),
        (
            "ramp",
            "kind = \"ramp\"\nlevels = [0.3, 0.5]\nramp_rate_per_s = 0.1\nhold_ms = 500\n",
            "static_map",
        ),
        (
            "chirp",
            "kind = \"chirp\"\nlevels = [0.4]\nchirp_f0_hz = 1.0\nchirp_f1_hz = 10.0\n\
             chirp_amplitude = 0.05\nchirp_s = 6.0\n",
            "frequency_response",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let Some(stand) = Stand::start(dir.path(), 40.0) else {
            return;
        };
        let p = dir.path().join("propid.toml");
        let text = format!(
            "[device]\nbaud = 250000\nreconnect_initial_ms = 50\nreconnect_max_ms = 500\n\
             [experiment]\nramp_ms = 300\nsettle_ms = 500\n{keys}"
        );
        std::fs::write(&p, text).unwrap();
        let d = Daemon::run(&p, &stand.link.display().to_string(), None);
        let (status, lines, err) = d.finish(40.0);
        assert!(status.success(), "{name}: {status:?} {err}");
        assert_eq!(kind(&lines, "plan_finished").len(), 1, "{name}: {lines:#?}");
        assert!(!kind(&lines, "disarmed").is_empty(), "{name}: {lines:#?}");
        let got = of_type(&lines, wants);
        assert!(!got.is_empty(), "{name}: {lines:#?}");
        if name == "staircase" {
            let map = got.iter().find(|m| m["output"] == "thrust").unwrap();
            for l in map["levels"].as_array().unwrap() {
                let u = l["throttle"].as_f64().unwrap();
                if u < 0.1 {
                    continue;
                }
                let want = propid_sim::plant::equilibrium(&sim.plant, u, 5.0).thrust_n;
                let mean = l["mean"].as_f64().unwrap();
                assert!(
                    (mean / want - 1.0).abs() < 0.1,
                    "at {u}: {mean} N, truth {want} N"
                );
            }
        }
        stand.esc_until(5.0, |us| us < 1010.0);
    }
}
