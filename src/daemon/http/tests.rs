use super::*;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::time::Instant;

fn sink(queue: usize, max_clients: usize) -> HttpSink {
    HttpSink::bind("127.0.0.1:0".parse().unwrap(), queue, max_clients).unwrap()
}

/// Sends a request by hand and returns the connection (the test's client, not the server's
/// parser).
fn request(s: &HttpSink, method: &str, path: &str) -> TcpStream {
    let mut c = TcpStream::connect(s.addr()).unwrap();
    c.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(c, "{method} {path} HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    c
}

/// The status code of the response to `method path`.
fn status(s: &HttpSink, method: &str, path: &str) -> u16 {
    let mut line = String::new();
    BufReader::new(request(s, method, path))
        .read_line(&mut line)
        .unwrap();
    line.split(' ').nth(1).unwrap().parse().unwrap()
}

fn wait_clients(s: &HttpSink, n: usize) {
    for _ in 0..400 {
        if s.shared.clients.lock().unwrap().len() == n {
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    panic!("clients never connected");
}

#[test]
fn binds_a_free_loopback_port_and_serves_only_gets_of_the_table() {
    let s = sink(16, 4);
    assert!(s.addr().ip().is_loopback() && s.addr().port() != 0);
    assert_eq!(s.url(), format!("http://127.0.0.1:{}/", s.addr().port()));
    assert_eq!(status(&s, "GET", "/"), 200);
    assert_eq!(status(&s, "GET", "/vendor/uplot/uPlot.iife.min.js"), 200);
    assert_eq!(status(&s, "GET", "/nope"), 404);
    assert_eq!(status(&s, "GET", "/../Cargo.toml"), 404);
    for m in ["POST", "PUT", "DELETE", "HEAD", "OPTIONS"] {
        assert_eq!(status(&s, m, "/"), 405, "{m}");
    }
}

/// A late browser gets the history (recent lines, then the latest state of each kind), then
/// the live lines, each as one `data:` event.
#[test]
fn a_late_client_gets_the_history_then_the_live_lines() {
    let s = sink(16, 4);
    s.send(Kind::State("model"), r#"{"type":"model","n":1}"#);
    s.send(Kind::Log, r#"{"type":"event","kind":"a"}"#);
    s.send(Kind::State("model"), r#"{"type":"model","n":2}"#);
    let c = request(&s, "GET", "/events");
    wait_clients(&s, 1);
    s.send(Kind::Log, r#"{"type":"event","kind":"b"}"#);
    let mut data = Vec::new();
    for line in BufReader::new(c).lines() {
        let line = line.unwrap();
        if let Some(d) = line.strip_prefix("data: ") {
            data.push(d.to_string());
            if data.len() == 3 {
                break;
            }
        }
    }
    assert_eq!(
        data,
        [
            r#"{"type":"event","kind":"a"}"#,
            r#"{"type":"model","n":2}"#,
            r#"{"type":"event","kind":"b"}"#
        ]
    );
}

/// A browser that never reads is dropped and counted, and sending never waits for it; one
/// more than `max_clients` is refused with 503 and counted.
#[test]
fn a_client_that_never_reads_is_dropped_and_never_blocks() {
    let s = sink(2, 1);
    let _never_reads = request(&s, "GET", "/events");
    wait_clients(&s, 1);
    assert_eq!(status(&s, "GET", "/events"), 503);
    assert_eq!(s.clients_refused(), 1);
    let big = "x".repeat(64 * 1024);
    let t = Instant::now();
    for _ in 0..200 {
        s.send(Kind::Log, &big);
    }
    assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());
    assert_eq!(s.dropped_clients(), 1);
    assert_eq!(s.shared.clients.lock().unwrap().len(), 0);
    // its place is free again
    let mut c = request(&s, "GET", "/events");
    let mut head = [0u8; 15];
    c.read_exact(&mut head).unwrap();
    assert_eq!(&head, b"HTTP/1.1 200 OK");
}
