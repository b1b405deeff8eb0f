//! `[publish] mqtt` end to end through a real Mosquitto broker: simulated stands on ptys, one
//! daemon each, subscribers as `mosquitto_sub`. Every model arrives (at QoS 1), a late
//! subscriber gets the retained status and schedule, a daemon killed with SIGKILL turns
//! `offline` (its will), a broker restarted mid-run loses no model; `propid fleet` lists the
//! stands.

use crate::daemon_proc::{daemon_config, of_type, sim_stand, stats, Daemon};
use crate::mqtt_broker::{retained, Broker, Message, Subscriber};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// The device watchdog of these runs (the `[experiment]` key; 500 ms by default): several
/// stands and daemons share the test machine's cores, and these tests are about the broker,
/// not about a daemon starved of CPU for half a second.
const WATCHDOG: &str = "watchdog_ms = 3000\n";

/// A daemon config publishing to `broker` as `stand` (short plan: `levels`, 8 pulses each,
/// a model every 4).
fn mqtt_config(dir: &Path, broker: &Broker, stand: &str, levels: &str, extra: &str) -> String {
    let sub = dir.join(stand);
    std::fs::create_dir_all(&sub).unwrap();
    let p = daemon_config(
        &sub,
        levels,
        8,
        4,
        &format!(
            "{WATCHDOG}[publish]\nmqtt = \"{}\"\nstand = \"{stand}\"\nmqtt_keep_alive_s = 5\n{extra}",
            broker.url()
        ),
    );
    p.display().to_string()
}

/// The payloads on `topic`, parsed.
fn payloads(got: &[Message], topic: &str) -> Vec<Value> {
    got.iter()
        .filter(|m| m.topic == topic)
        .map(|m| serde_json::from_str(&m.payload).unwrap_or_else(|e| panic!("{m:?}: {e}")))
        .collect()
}

/// A model's identity: the device time and first sample of its window.
fn key(m: &Value) -> (String, u64) {
    (m["t_s"].to_string(), m["first_sample"].as_u64().unwrap())
}

/// Three stands, three daemons: every model line of each arrives on its stand's `model` topic
/// exactly once and byte-for-byte as published on stdout; status goes online → offline; a
/// subscriber that connects after the run gets every stand's retained status and schedule.
#[test]
fn three_stands_publish_every_model_once_and_leave_status_and_schedule_retained() {
    let dir = tempfile::tempdir().unwrap();
    let broker = Broker::start(dir.path());
    let mut sub = Subscriber::start(&broker, &["propid/#"], None);
    // the subscription is in place before any daemon starts
    std::thread::sleep(std::time::Duration::from_millis(300));
    let stands = ["bench-a", "bench-b", "bench-c"];
    let mut running = Vec::new();
    for name in stands {
        let sim = sim_stand(1000, |_| {});
        let cfg = mqtt_config(dir.path(), &broker, name, "[0.3, 0.45]", "");
        let d = Daemon::start(&[
            "run",
            "--config",
            &cfg,
            "--port",
            &sim.path().display().to_string(),
        ]);
        running.push((name, sim, d));
    }
    let mut published = BTreeMap::new();
    for (name, sim, d) in running {
        let (status, lines, err) = d.finish(90.0);
        let _ = sim.stop();
        assert!(status.success(), "{name}: {status:?} {err}");
        let s = stats(&lines);
        assert_eq!(s["mqtt_dropped"], 0, "{s}");
        assert!(s["mqtt_published"].as_u64().unwrap() > 0, "{s}");
        let models: Vec<Value> = of_type(&lines, "model").into_iter().cloned().collect();
        assert!(models.len() >= 2, "{name}: {lines:#?}");
        published.insert(name, (models, s.clone()));
    }
    let got = sub.drain(1.5).to_vec();
    for (name, (models, s)) in &published {
        let arrived = payloads(&got, &format!("propid/{name}/model"));
        // once each (no reconnect in this run), the same lines in the same order
        assert_eq!(&arrived, models, "{name}");
        // the stats line, the same as stdout's
        let stats_msgs = payloads(&got, &format!("propid/{name}/stats"));
        assert_eq!(stats_msgs.last(), Some(s), "{name}");
        // events and warnings on `event`, the run's first one the plan's handshake
        let events = payloads(&got, &format!("propid/{name}/event"));
        assert!(
            events.iter().any(|e| e["kind"] == "connected"),
            "{name}: {events:#?}"
        );
        let status: Vec<&str> = got
            .iter()
            .filter(|m| m.topic == format!("propid/{name}/status"))
            .map(|m| m.payload.as_str())
            .collect();
        assert_eq!(status.first(), Some(&"online"), "{name}");
        assert_eq!(
            status.last(),
            Some(&"offline"),
            "{name}: a clean end says so"
        );
    }
    // a subscriber that connects after the run
    let late = retained(&broker, &["propid/+/status", "propid/+/schedule/+"]);
    for (name, (models, _)) in &published {
        let status: Vec<&Message> = late
            .iter()
            .filter(|m| m.topic == format!("propid/{name}/status"))
            .collect();
        assert_eq!(status.len(), 1, "{name}: {late:#?}");
        assert_eq!(status[0].payload, "offline");
        // the last model of each operating point, retained under its level
        let mut last: BTreeMap<u64, &Value> = BTreeMap::new();
        for m in models {
            last.insert(m["level"].as_u64().unwrap(), m);
        }
        assert_eq!(last.len(), 2, "{name}");
        for (level, m) in last {
            let sched = payloads(&late, &format!("propid/{name}/schedule/{level}"));
            assert_eq!(sched, vec![m.clone()], "{name} level {level}");
        }
    }
}

/// A daemon killed with SIGKILL (no clean end) turns `offline` by its will, within its
/// keep-alive; a subscriber that connects later gets `offline` retained.
#[test]
fn a_daemon_killed_with_sigkill_turns_offline() {
    let dir = tempfile::tempdir().unwrap();
    let broker = Broker::start(dir.path());
    let mut sub = Subscriber::start(&broker, &["propid/+/status"], None);
    let sim = sim_stand(1000, |_| {});
    let cfg = mqtt_config(dir.path(), &broker, "killed", "[0.4]", "");
    let mut d = Daemon::start(&[
        "run",
        "--config",
        &cfg,
        "--port",
        &sim.path().display().to_string(),
    ]);
    sub.wait_for(20.0, |m| {
        m.topic == "propid/killed/status" && m.payload == "online"
    });
    d.wait_for(20.0, |l| l["kind"] == "level_reached");
    d.signal(libc::SIGKILL);
    // keep-alive 5 s: the broker gives up on a silent client after 1.5 × that; a killed
    // process's socket is closed by the kernel, which the broker sees at once
    sub.wait_for(7.5 + 5.0, |m| {
        m.topic == "propid/killed/status" && m.payload == "offline"
    });
    let _ = d.finish(5.0);
    let _ = sim.stop();
    let late = retained(&broker, &["propid/+/status"]);
    assert_eq!(
        late,
        vec![Message {
            topic: "propid/killed/status".into(),
            payload: "offline".into()
        }]
    );
}

/// The broker stopped and started again while a daemon runs: the daemon keeps running,
/// queues, reconnects, and every model line reaches a subscriber with a persistent session
/// (at least once: a model the broker had not acknowledged is sent again, and told apart by
/// its window's `t_s` and `first_sample`).
#[test]
fn a_broker_restarted_mid_run_loses_no_model() {
    let dir = tempfile::tempdir().unwrap();
    let mut broker = Broker::start(dir.path());
    let mut sub = Subscriber::start(&broker, &["propid/+/model"], Some("restart-test"));
    std::thread::sleep(std::time::Duration::from_millis(300));
    let sim = sim_stand(1000, |_| {});
    let cfg = mqtt_config(dir.path(), &broker, "restarted", "[0.3, 0.4, 0.5]", "");
    let mut d = Daemon::start(&[
        "run",
        "--config",
        &cfg,
        "--port",
        &sim.path().display().to_string(),
    ]);
    d.wait_for(30.0, |l| l["type"] == "model");
    broker.stop();
    // models are identified and queued while the broker is away
    d.wait_for(30.0, |l| l["type"] == "model");
    broker.restart();
    let (status, lines, err) = d.finish(90.0);
    let _ = sim.stop();
    assert!(status.success(), "{status:?} {err}");
    let s = stats(&lines);
    assert!(s["mqtt_reconnects"].as_u64().unwrap() >= 1, "{s}");
    assert_eq!(s["mqtt_dropped"], 0, "{s}");
    let models: Vec<&Value> = of_type(&lines, "model");
    assert!(models.len() >= 4, "{lines:#?}");
    let got = sub.drain(3.0).to_vec();
    let arrived = payloads(&got, "propid/restarted/model");
    let mut seen: BTreeMap<(String, u64), usize> = BTreeMap::new();
    for m in &arrived {
        *seen.entry(key(m)).or_default() += 1;
    }
    for m in &models {
        assert!(
            seen.contains_key(&key(m)),
            "model {m} lost; arrived {arrived:#?}"
        );
    }
    assert_eq!(seen.len(), models.len(), "{arrived:#?}");
}

/// `data:` lines of the event stream at `path` of the server on `port`, parsed, on a channel.
fn stream(port: u16, path: &str) -> std::sync::mpsc::Receiver<Value> {
    use std::io::{BufRead, BufReader, Write};
    let mut c = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
    write!(c, "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n").unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(c).lines() {
            let Ok(line) = line else { return };
            if let Some(d) = line.strip_prefix("data: ") {
                let v: Value = serde_json::from_str(d).unwrap_or_else(|e| panic!("{d}: {e}"));
                if tx.send(v).is_err() {
                    return;
                }
            }
        }
    });
    rx
}

/// The first line on `rx` that `pred` accepts within `secs`.
fn first(rx: &std::sync::mpsc::Receiver<Value>, secs: f64, pred: impl Fn(&Value) -> bool) -> Value {
    let end = std::time::Instant::now() + std::time::Duration::from_secs_f64(secs);
    let mut seen = Vec::new();
    loop {
        let left = end.saturating_duration_since(std::time::Instant::now());
        match rx.recv_timeout(left) {
            Ok(v) if pred(&v) => return v,
            Ok(v) => seen.push(v),
            Err(_) => panic!("no matching line within {secs} s; got {seen:#?}"),
        }
    }
}

/// `mosquitto_pub` of one message (retained with `retain`).
fn publish(broker: &Broker, topic: &str, payload: &str, retain: bool) {
    let mut cmd = std::process::Command::new("mosquitto_pub");
    cmd.args(["-h", "127.0.0.1", "-p", &broker.port.to_string(), "-q", "1"]);
    cmd.args(["-t", topic, "-m", payload]);
    if retain {
        cmd.arg("-r");
    }
    assert!(cmd.status().unwrap().success());
}

/// `propid fleet`: one page listing every stand the broker knows (retained status and
/// schedule of a stand that ran before it started, a live one's model and warning), and each
/// stand's own page fed from the broker.
#[test]
fn fleet_lists_every_stand_and_serves_each_stand_page() {
    let dir = tempfile::tempdir().unwrap();
    let broker = Broker::start(dir.path());
    let model = |level: u32, op: f64, gain: f64| {
        serde_json::json!({"type": "model", "t_s": 1.5, "level": level, "operating_point": op,
            "first_sample": 100, "order": 2, "fn_hz": 25.0, "zeta": 0.5, "dc_gain": gain,
            "time_constants_s": [], "pulses": 4, "uncertainty": null})
        .to_string()
    };
    publish(&broker, "propid/old/status", "offline", true);
    publish(&broker, "propid/old/schedule/1", &model(1, 0.3, 7.0), true);
    publish(&broker, "propid/old/schedule/2", &model(2, 0.45, 8.0), true);
    let port = crate::mqtt_broker::free_port();
    let fleet = std::process::Command::new(crate::daemon_proc::BIN)
        .args([
            "fleet",
            "--mqtt",
            &broker.url(),
            "--http",
            &port.to_string(),
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let _fleet = crate::daemon_proc::KillOnDrop(fleet);
    let t = std::time::Instant::now();
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(t.elapsed().as_secs() < 10, "propid fleet does not serve");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let page = stream(port, "/events");
    let f = first(&page, 10.0, |v| {
        v["type"] == "fleet"
            && v["stands"][0]["schedule"]
                .as_array()
                .is_some_and(|s| s.len() == 2)
    });
    let old = &f["stands"][0];
    assert_eq!(
        (&old["stand"], &old["status"]),
        (&"old".into(), &"offline".into())
    );
    assert_eq!(old["schedule"][0]["dc_gain"], 7.0);
    assert_eq!(old["schedule"][1]["operating_point"], 0.45);
    // a stand that comes online now
    publish(&broker, "propid/live/status", "online", true);
    publish(
        &broker,
        "propid/live/event",
        r#"{"type":"event","kind":"level_reached","index":0,"operating_point":0.3}"#,
        false,
    );
    publish(&broker, "propid/live/model", &model(1, 0.3, 6.5), false);
    publish(
        &broker,
        "propid/live/event",
        r#"{"type":"warning","kind":"link_stalled","silent_ms":1000,"stop_acknowledged":true}"#,
        false,
    );
    let f = first(&page, 10.0, |v| {
        v["stands"].as_array().is_some_and(|s| {
            s.iter().any(|s| {
                s["stand"] == "live" && s["warnings"].as_array().is_some_and(|w| !w.is_empty())
            })
        })
    });
    let live = f["stands"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["stand"] == "live")
        .unwrap();
    assert_eq!(live["status"], "online");
    assert_eq!(live["phase"], "level 0 (0.300): pulses");
    assert_eq!(live["model"]["dc_gain"], 6.5);
    assert_eq!(live["warnings"][0]["kind"], "link_stalled");
    // each stand's page: the live page's files, its stream the stand's lines from the broker
    let (code, body) = get(port, "/stand/old/");
    assert_eq!(code, 200);
    assert!(body.contains("live stand"), "{body}");
    assert_eq!(get(port, "/app.js").0, 200);
    assert_eq!(get(port, "/stand/nobody/events").0, 404);
    let old = stream(port, "/stand/old/events");
    let sched = first(&old, 10.0, |v| v["type"] == "schedule");
    assert_eq!(sched["models"].as_array().unwrap().len(), 2);
    let live = stream(port, "/stand/live/events");
    let m = first(&live, 10.0, |v| v["type"] == "model");
    assert_eq!(m["dc_gain"], 6.5);
    publish(&broker, "propid/live/model", &model(2, 0.45, 9.5), false);
    let m = first(&live, 10.0, |v| v["type"] == "model" && v["dc_gain"] == 9.5);
    assert_eq!(m["operating_point"], 0.45);
}

/// Status and body of `GET path` on the server at `port`.
fn get(port: u16, path: &str) -> (u16, String) {
    use std::io::{Read, Write};
    let mut c = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
    c.set_read_timeout(Some(std::time::Duration::from_secs(5)))
        .unwrap();
    write!(
        c,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut text = String::new();
    let _ = c.read_to_string(&mut text);
    let code = text.split(' ').nth(1).unwrap_or("0").parse().unwrap_or(0);
    let body = text.split_once("\r\n\r\n").map_or("", |b| b.1).to_string();
    (code, body)
}

/// `mqtts://` with a CA and a client certificate (a PKI made by openssl; the broker requires
/// the certificate): the daemon's models arrive.
#[test]
fn mqtts_with_a_client_certificate_publishes_the_models() {
    let dir = tempfile::tempdir().unwrap();
    let pki = crate::mqtt_broker::pki(dir.path());
    let (broker, tls_port) = Broker::start_tls(dir.path(), &pki);
    let mut sub = Subscriber::start(&broker, &["propid/+/model"], None);
    std::thread::sleep(std::time::Duration::from_millis(300));
    let sim = sim_stand(1000, |_| {});
    let sub_dir = dir.path().join("tls");
    std::fs::create_dir_all(&sub_dir).unwrap();
    let cfg = daemon_config(
        &sub_dir,
        "[0.4]",
        8,
        4,
        &format!(
            "{WATCHDOG}[publish]\nmqtt = \"mqtts://127.0.0.1:{tls_port}\"\nstand = \"tls\"\n\
             mqtt_ca = {:?}\nmqtt_cert = {:?}\nmqtt_key = {:?}\n",
            pki.ca, pki.client.0, pki.client.1
        ),
    );
    let cfg = cfg.display().to_string();
    let d = Daemon::start(&[
        "run",
        "--config",
        &cfg,
        "--port",
        &sim.path().display().to_string(),
    ]);
    let (status, lines, err) = d.finish(60.0);
    let _ = sim.stop();
    assert!(status.success(), "{status:?} {err}");
    let models: Vec<Value> = of_type(&lines, "model").into_iter().cloned().collect();
    assert!(!models.is_empty(), "{lines:#?}");
    let got = sub.drain(1.5).to_vec();
    assert_eq!(payloads(&got, "propid/tls/model"), models, "{err}");
}

/// The binary refuses an MQTT configuration it cannot use, before it touches a stand, with the
/// key named and exit 5: `mqtts://` without a CA, a password file others may read.
#[test]
fn unusable_mqtt_settings_are_refused_with_exit_5() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let pw = dir.path().join("pw");
    std::fs::write(&pw, "secret\n").unwrap();
    std::fs::set_permissions(&pw, std::fs::Permissions::from_mode(0o644)).unwrap();
    for (publish, key) in [
        ("mqtt = \"mqtts://127.0.0.1:1\"\nstand = \"s\"\n", "publish.mqtt_ca"),
        ("mqtt = \"mqtt://u:p@127.0.0.1\"\nstand = \"s\"\n", "publish.mqtt"),
        (
            &format!("mqtt = \"mqtt://127.0.0.1:1\"\nstand = \"s\"\nmqtt_username = \"u\"\nmqtt_password_file = {pw:?}\n"),
            "publish.mqtt_password_file",
        ),
    ] {
        let cfg = dir.path().join("bad.toml");
        std::fs::write(&cfg, format!("[publish]\n{publish}")).unwrap();
        let out = std::process::Command::new(crate::daemon_proc::BIN)
            .args(["run", "--config", cfg.to_str().unwrap(), "--port", "/nonexistent/port"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(5), "{publish}: {err}");
        assert!(err.contains(key), "{publish}: {err}");
    }
}
