//! Issue 27's hostile HTTP clients against the binary's page: `propid replay --http` answers
//! them all, keeps serving, keeps its threads bounded and ends with its exit code on the first
//! SIGTERM while clients stall; `propid run --http` ends at its plan's end while clients stall.

use crate::daemon_http::{host, request, url_of};
use crate::daemon_proc::{daemon_config, sim_stand, Daemon};
use propid::daemon::http::request::MAX_HEAD;
use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::time::Duration;

/// Threads of process `pid` (Linux).
fn threads(pid: u32) -> usize {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    s.lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

/// Sends `text` as is on a new connection to the page at `url`.
fn send(url: &str, text: &str) -> TcpStream {
    let mut c = TcpStream::connect(host(url)).unwrap();
    c.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    c.write_all(text.as_bytes()).unwrap();
    c
}

/// The status code answered on `c`.
fn code(c: TcpStream) -> u16 {
    let mut line = String::new();
    BufReader::new(c).read_line(&mut line).unwrap();
    line.split(' ').nth(1).unwrap_or("0").parse().unwrap_or(0)
}

/// Clients that hold a connection: a head never finished, `/events` with a request
/// pipelined behind it and never read, 300 pipelined requests never read.
fn stall(url: &str) -> Vec<TcpStream> {
    let h = host(url);
    let piped: String = (0..300)
        .map(|_| format!("GET /app.js HTTP/1.1\r\nHost: {h}\r\n\r\n"))
        .collect();
    vec![
        send(url, &format!("GET / HTTP/1.1\r\nHost: {h}\r\n")),
        send(
            url,
            &format!(
                "GET /events HTTP/1.1\r\nHost: {h}\r\n\r\nGET / HTTP/1.1\r\nHost: {h}\r\n\r\n"
            ),
        ),
        send(url, &piped),
    ]
}

#[test]
fn replay_over_http_outlives_hostile_clients_and_ends_on_the_first_sigterm() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("stand.tsp");
    let mut bytes = Vec::new();
    propid_sim::record::record(&propid_sim::SimConfig::default(), 20.0, &mut bytes).unwrap();
    std::fs::write(&rec, bytes).unwrap();
    let mut d = Daemon::start(&["replay", rec.to_str().unwrap(), "--http", "127.0.0.1:0"]);
    let url = url_of(&mut d);
    let h = host(&url).to_string();
    let port = h.rsplit(':').next().unwrap();
    // the request that ended the daemon (its body drained into a buffer of that length)
    let huge = format!("GET / HTTP/1.1\r\nHost: {h}\r\nContent-Length: 100000000000000\r\n\r\n");
    assert_eq!(code(send(&url, &huge)), 413);
    let _stalled = stall(&url);
    // each of these leaked a thread for good (300 here, 1 000 in the unit test: this test
    // shares the machine with real-time runs of the simulated stand)
    for _ in 0..300 {
        assert_eq!(code(send(&url, "GET / HTTP/2.0\r\n\r\n")), 505);
    }
    // a page of another site whose name resolves here (DNS rebinding)
    let rebound = format!("GET /events HTTP/1.1\r\nHost: rebound.example:{port}\r\n\r\n");
    assert_eq!(code(send(&url, &rebound)), 421);
    // a head of exactly the limit, unfinished (all of it is read, so the answer is not cut
    // by a reset)
    let start = format!("GET / HTTP/1.1\r\nHost: {h}\r\nX: ");
    let over = start.clone() + &"y".repeat(MAX_HEAD - start.len());
    assert_eq!(code(send(&url, &over)), 431);
    let stats = d.wait_for(60.0, |l| l["type"] == "stats");
    assert!(stats["clients_refused"].as_u64().is_some(), "{stats}");
    // the final page: more than max_clients (64) streams come and go, no line is sent
    for i in 0..80 {
        let ok = (0..50).any(|_| {
            let c = code(send(
                &url,
                &format!("GET /events HTTP/1.1\r\nHost: {h}\r\n\r\n"),
            ));
            c == 200 || {
                std::thread::sleep(Duration::from_millis(100));
                false
            }
        });
        assert!(ok, "cycle {i}: /events refused for good");
    }
    assert_eq!(request(&url, "GET", "/").0, 200);
    let n = threads(d.child.id());
    assert!(n < 64, "{n} threads");
    d.signal(libc::SIGTERM);
    let (status, _, err) = d.finish(10.0);
    assert!(status.success(), "{status}: {err}");
}

#[test]
fn a_run_over_http_ends_at_its_plans_end_while_clients_stall() {
    let dir = tempfile::tempdir().unwrap();
    let sim = sim_stand(1000, |_| {});
    let cfg = daemon_config(dir.path(), "[0.4]", 8, 4, "");
    let mut d = Daemon::start(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--port",
        &sim.path().display().to_string(),
        "--http",
        "127.0.0.1:0",
    ]);
    let url = url_of(&mut d);
    let _stalled = stall(&url);
    let _never_reads = send(
        &url,
        &format!("GET /events HTTP/1.1\r\nHost: {}\r\n\r\n", host(&url)),
    );
    let (status, lines, err) = d.finish(60.0);
    let _ = sim.stop();
    assert!(status.success(), "{status}: {err}");
    assert_eq!(lines.last().unwrap()["type"], "stats");
}
