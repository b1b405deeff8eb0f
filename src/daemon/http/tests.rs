//! The server against hostile clients on loopback: every client here is the test's own,
//! written by hand (not the server's parser).

use super::assets::Asset;
use super::*;
use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::Instant;

fn sink(queue: usize, max_clients: usize) -> HttpSink {
    HttpSink::bind("127.0.0.1:0".parse().unwrap(), queue, max_clients).unwrap()
}

/// A connection to the sink (reads time out after 10 s: a stalled server fails the test).
fn connect(s: &HttpSink) -> TcpStream {
    let c = TcpStream::connect(s.addr()).unwrap();
    c.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    c
}

/// Sends `text` on a new connection and returns the connection.
fn send_raw(s: &HttpSink, text: &str) -> TcpStream {
    let mut c = connect(s);
    c.write_all(text.as_bytes()).unwrap();
    c
}

/// Sends a request by hand (with the right `Host`) and returns the connection.
fn request(s: &HttpSink, method: &str, path: &str) -> TcpStream {
    send_raw(
        s,
        &format!("{method} {path} HTTP/1.1\r\nHost: {}\r\n\r\n", s.addr()),
    )
}

/// The status code of the response on `c`.
fn code(c: TcpStream) -> u16 {
    let mut line = String::new();
    BufReader::new(c).read_line(&mut line).unwrap();
    line.split(' ')
        .nth(1)
        .unwrap_or_else(|| panic!("{line:?}"))
        .parse()
        .unwrap()
}

/// The status code of the response to `method path`.
fn status(s: &HttpSink, method: &str, path: &str) -> u16 {
    code(request(s, method, path))
}

/// The status code of the response to `text`, sent as is.
fn raw(s: &HttpSink, text: &str) -> u16 {
    code(send_raw(s, text))
}

/// Waits (at most 10 s) until `what` of the sink holds.
fn wait_until(s: &HttpSink, what: &str, ok: impl Fn(&Shared) -> bool) {
    for _ in 0..2000 {
        if ok(&s.shared) {
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    panic!("never: {what}");
}

fn wait_clients(s: &HttpSink, n: usize) {
    wait_until(s, &format!("{n} clients"), |sh| {
        lock(&sh.events.clients).len() == n
    });
}

/// The next `data:` line of an event stream.
fn next_data(r: &mut impl BufRead) -> String {
    let mut line = String::new();
    loop {
        line.clear();
        assert!(r.read_line(&mut line).unwrap() > 0, "the stream ended");
        if let Some(d) = line.strip_prefix("data: ") {
            return d.trim_end().to_string();
        }
    }
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
    // the whole file, and the connection closes after it
    let mut text = Vec::new();
    request(&s, "GET", "/app.js")
        .read_to_end(&mut text)
        .unwrap();
    assert!(text.ends_with(assets::get("/app.js").unwrap().body));
}

/// Another table of files (the fleet page's, say) is served the same way.
#[test]
fn another_table_of_files_can_be_served() {
    fn table(path: &str) -> Option<Asset> {
        (path == "/fleet").then_some(Asset {
            content_type: "text/plain",
            body: b"fleet",
        })
    }
    let site = site::Site {
        asset: table,
        stream: site::no_stream,
    };
    let s = HttpSink::bind_site("127.0.0.1:0".parse().unwrap(), 4, 4, site).unwrap();
    assert_eq!(status(&s, "GET", "/fleet"), 200);
    assert_eq!(status(&s, "GET", "/"), 404);
    assert_eq!(status(&s, "GET", "/events"), 200);
}

/// A late browser gets the history (recent lines, then the latest state of each kind), then
/// the live lines, each as one `data:` event.
#[test]
fn a_late_client_gets_the_history_then_the_live_lines() {
    let s = sink(16, 4);
    s.send(Kind::State("model"), r#"{"type":"model","n":1}"#);
    s.send(Kind::Log, r#"{"type":"event","kind":"a"}"#);
    s.send(Kind::State("model"), r#"{"type":"model","n":2}"#);
    let mut c = BufReader::new(request(&s, "GET", "/events"));
    wait_clients(&s, 1);
    s.send(Kind::Log, r#"{"type":"event","kind":"b"}"#);
    let data: Vec<String> = (0..3).map(|_| next_data(&mut c)).collect();
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
    assert_eq!(lock(&s.shared.events.clients).len(), 0);
    // its place is free again
    let mut c = request(&s, "GET", "/events");
    let mut head = [0u8; 15];
    c.read_exact(&mut head).unwrap();
    assert_eq!(&head, b"HTTP/1.1 200 OK");
}

/// Issue 27 (1): a declared body, of any length, is refused from the head alone, never read
/// nor waited for; the server goes on.
#[test]
fn a_declared_body_is_refused_unread() {
    let s = sink(16, 4);
    let h = s.addr();
    for field in [
        "Content-Length: 100000000000000",
        "Content-Length: 18446744073709551616",
        "Content-Length: 5",
        "Transfer-Encoding: chunked",
    ] {
        for path in ["/", "/events"] {
            let r = raw(
                &s,
                &format!("GET {path} HTTP/1.1\r\nHost: {h}\r\n{field}\r\n\r\n"),
            );
            assert_eq!(r, 413, "{field}");
        }
    }
    assert_eq!(status(&s, "GET", "/"), 200);
}

/// Issue 27 (10): a head never finished, `/events` with a request pipelined behind it, and
/// 300 pipelined requests never read hold no other request; the stream still streams.
#[test]
fn stalled_clients_never_hold_the_other_requests() {
    let s = sink(16, 4);
    let h = s.addr();
    let _unfinished = send_raw(&s, &format!("GET / HTTP/1.1\r\nHost: {h}\r\n"));
    let ev = send_raw(
        &s,
        &format!("GET /events HTTP/1.1\r\nHost: {h}\r\n\r\nGET / HTTP/1.1\r\nHost: {h}\r\n\r\n"),
    );
    let big = "/vendor/uplot/uPlot.iife.min.js";
    let piped: String = (0..300)
        .map(|_| format!("GET {big} HTTP/1.1\r\nHost: {h}\r\n\r\n"))
        .collect();
    let _unread = send_raw(&s, &piped);
    wait_clients(&s, 1);
    for _ in 0..5 {
        assert_eq!(status(&s, "GET", "/"), 200);
    }
    s.send(Kind::Log, r#"{"type":"event","kind":"a"}"#);
    let mut ev = BufReader::new(ev);
    assert_eq!(next_data(&mut ev), r#"{"type":"event","kind":"a"}"#);
    // the stream looked whether its browser left (it did not): still there
    std::thread::sleep(Duration::from_millis(1200));
    s.send(Kind::Log, r#"{"type":"event","kind":"b"}"#);
    assert_eq!(next_data(&mut ev), r#"{"type":"event","kind":"b"}"#);
}

/// Issue 27 (11): every `HTTP/2.0` request line is answered 505 and its thread ends.
#[test]
fn other_http_versions_are_refused_and_leave_no_thread() {
    let s = sink(16, 4);
    for line in [
        "GET / HTTP/2.0",
        "PRI * HTTP/2.0",
        "GET / HTTP/1.2",
        "GET / HTTP/0.9",
    ] {
        assert_eq!(raw(&s, &format!("{line}\r\n\r\n")), 505, "{line}");
    }
    for _ in 0..1000 {
        assert_eq!(raw(&s, "GET / HTTP/2.0\r\n\r\n"), 505);
    }
    // the accepting thread alone
    wait_until(&s, "one thread", |sh| *lock(&sh.threads) == 1);
    assert_eq!(status(&s, "GET", "/"), 200);
}

/// Issue 27 (12): streams whose browser left free their place though no line is ever sent
/// (a replay's final page): after 64+ connect/close cycles, `/events` is still 200.
#[test]
fn event_streams_whose_browser_left_free_their_place_without_a_line() {
    let s = sink(16, 64);
    for i in 0..80 {
        let mut ok = false;
        for _ in 0..50 {
            if status(&s, "GET", "/events") == 200 {
                ok = true;
                break;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        assert!(ok, "cycle {i}: 503 for good");
    }
    wait_clients(&s, 0);
    assert_eq!(status(&s, "GET", "/events"), 200);
}

/// Issue 27 (13): a head over the limit is 431, whatever follows is never kept; a head sent
/// for ever is cut off.
#[test]
fn a_head_over_the_limit_is_refused() {
    let s = sink(16, 4);
    let start = format!("GET / HTTP/1.1\r\nHost: {}\r\nX-Pad: ", s.addr());
    let exact = start.clone() + &"y".repeat(request::MAX_HEAD - start.len());
    assert_eq!(raw(&s, &exact), 431);
    let mut c = send_raw(&s, &start);
    c.set_write_timeout(Some(Duration::from_secs(10))).unwrap();
    let chunk = vec![b'y'; 64 * 1024];
    let mut sent = 0usize;
    let cut = loop {
        match c.write(&chunk) {
            Ok(n) => sent += n,
            Err(e) => break e,
        }
        assert!(sent < 64 << 20, "64 MB of head taken");
    };
    assert!(
        !matches!(cut.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut),
        "{cut}"
    );
    assert_eq!(status(&s, "GET", "/"), 200);
}

/// Issue 27 (13): connections that send nothing hold at most [`PAGE_CONNECTIONS`] places;
/// one more is answered 503 at once and counted; the event streams are not among them.
#[test]
fn connections_over_the_cap_are_refused_at_once() {
    let s = sink(16, 2);
    let mut ev = BufReader::new(request(&s, "GET", "/events"));
    wait_clients(&s, 1);
    let slow: Vec<TcpStream> = (0..PAGE_CONNECTIONS).map(|_| connect(&s)).collect();
    wait_until(&s, "all pending", |sh| {
        sh.pending.load(Ordering::Relaxed) == PAGE_CONNECTIONS
    });
    assert_eq!(code(connect(&s)), 503);
    assert_eq!(s.clients_refused(), 1);
    s.send(Kind::Log, "1");
    assert_eq!(next_data(&mut ev), "1");
    drop(slow);
    wait_until(&s, "none pending", |sh| {
        sh.pending.load(Ordering::Relaxed) == 0
    });
    assert_eq!(status(&s, "GET", "/"), 200);
}

/// Issue 27 (14): a request naming another host (DNS rebinding), or none, is refused.
#[test]
fn only_requests_naming_this_server_are_answered() {
    let s = sink(16, 4);
    let port = s.addr().port();
    for host in [
        format!("evil.example:{port}"),
        format!("127.0.0.1:{}", port.wrapping_add(1)),
        "127.0.0.1".to_string(),
        "x".to_string(),
    ] {
        for path in ["/", "/events"] {
            let r = raw(&s, &format!("GET {path} HTTP/1.1\r\nHost: {host}\r\n\r\n"));
            assert_eq!(r, 421, "{host}");
        }
    }
    assert_eq!(raw(&s, "GET / HTTP/1.0\r\n\r\n"), 421);
    for host in [format!("localhost:{port}"), format!("127.0.0.1:{port}")] {
        let r = raw(&s, &format!("GET / HTTP/1.0\r\nHost: {host}\r\n\r\n"));
        assert_eq!(r, 200, "{host}");
    }
    assert_eq!(lock(&s.shared.events.clients).len(), 0);
}

/// Issue 27 (10): closing returns within its bound while clients stall (a head never
/// finished, a stream that never reads), and every thread of the server ends.
#[test]
fn closing_never_waits_on_a_stalled_client() {
    let s = sink(4, 4);
    let _unfinished = send_raw(&s, &format!("GET / HTTP/1.1\r\nHost: {}\r\n", s.addr()));
    let _never_reads = request(&s, "GET", "/events");
    wait_clients(&s, 1);
    // the stream's writer is stuck on a full socket
    let big = "x".repeat(1 << 20);
    for _ in 0..4 {
        s.send(Kind::Log, &big);
    }
    let shared = s.shared.clone();
    let t = Instant::now();
    s.close();
    // CLOSE_GRACE and CLOSE_FORCED, far below the clients' own time limits
    assert!(t.elapsed() < Duration::from_secs(3), "{:?}", t.elapsed());
    for _ in 0..400 {
        if *lock(&shared.threads) == 0 {
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    panic!("{} threads left", *lock(&shared.threads));
}
