//! The server's threads: one accepts connections (refusing those over the cap at once), one
//! per connection answers its single request (a file, a refusal, or the event stream it then
//! writes), each counted so that closing can wait for them within a bound.

use crossbeam_channel::{bounded, Receiver, RecvTimeoutError};
use std::io::{ErrorKind, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::request::{self, Head};
use super::{lock, Shared, Stream};

/// Connections at once that are not event streams (reading their request, or answered);
/// one more is answered `503` and closed.
pub const PAGE_CONNECTIONS: usize = 16;

/// A request's whole head must arrive within this.
const HEAD_WITHIN: Duration = Duration::from_secs(5);

/// A write that sends nothing for this long ends the connection.
const WRITE_WITHIN: Duration = Duration::from_secs(5);

/// An idle event stream looks this often whether its browser left.
const PEER_CHECK: Duration = Duration::from_millis(500);

/// An event stream sends a comment line after this long without a line.
const KEEP_ALIVE: Duration = Duration::from_secs(10);

/// Queued lines written at once, at most about this many bytes.
const BATCH_BYTES: usize = 64 * 1024;

/// Starts the accepting thread.
pub(super) fn start(listener: TcpListener, shared: &Arc<Shared>) -> std::io::Result<()> {
    let live = Live::new(shared, None);
    std::thread::Builder::new()
        .name("propid-http".into())
        .spawn(move || accept(&listener, live))
        .map(drop)
}

/// One of the server's threads, counted while it lives (also when it panics); for a
/// connection, its handle (to shut it down at close) and its page slot until it streams.
struct Live {
    shared: Arc<Shared>,
    conn: Option<u64>,
    pending: bool,
}

impl Live {
    fn new(shared: &Arc<Shared>, conn: Option<(u64, &TcpStream)>) -> Live {
        *lock(&shared.threads) += 1;
        let pending = conn.is_some();
        if let Some((id, c)) = conn {
            shared.pending.fetch_add(1, Ordering::Relaxed);
            if let Ok(handle) = c.try_clone() {
                lock(&shared.conns).insert(id, handle);
            }
        }
        Live {
            shared: shared.clone(),
            conn: conn.map(|c| c.0),
            pending,
        }
    }

    /// The connection became an event stream: its page slot is free.
    fn streams(&mut self) {
        if std::mem::replace(&mut self.pending, false) {
            self.shared.pending.fetch_sub(1, Ordering::Relaxed);
        }
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        self.streams();
        if let Some(id) = self.conn {
            lock(&self.shared.conns).remove(&id);
        }
        *lock(&self.shared.threads) -= 1;
        self.shared.thread_ended.notify_all();
    }
}

/// Waits at most `t` for the server's threads to end: whether they all did.
pub(super) fn wait_threads(shared: &Shared, t: Duration) -> bool {
    let n = lock(&shared.threads);
    let (n, _) = shared
        .thread_ended
        .wait_timeout_while(n, t, |n| *n > 0)
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    *n == 0
}

/// Shuts every open connection down (`how`).
pub(super) fn shut_all(shared: &Shared, how: Shutdown) {
    for c in lock(&shared.conns).values() {
        let _ = c.shutdown(how);
    }
}

/// Wakes the accepting thread (blocked in `accept`) by connecting to it.
pub(super) fn wake(bound: SocketAddr) {
    let mut to = bound;
    if to.ip().is_unspecified() {
        to.set_ip(match to {
            SocketAddr::V4(_) => std::net::Ipv4Addr::LOCALHOST.into(),
            SocketAddr::V6(_) => std::net::Ipv6Addr::LOCALHOST.into(),
        });
    }
    let _ = TcpStream::connect_timeout(&to, Duration::from_millis(200));
}

/// Accepts connections until the sink closes: each gets a thread, unless
/// [`PAGE_CONNECTIONS`] are already pending (then `503`, at once, and counted).
fn accept(listener: &TcpListener, live: Live) {
    let shared = live.shared.clone();
    for conn in listener.incoming() {
        if shared.closing.load(Ordering::Relaxed) {
            return;
        }
        let conn = match conn {
            Ok(c) => c,
            Err(_) => {
                // out of descriptors, or a connection reset before it was accepted
                std::thread::sleep(Duration::from_millis(20));
                continue;
            }
        };
        if shared.pending.load(Ordering::Relaxed) >= PAGE_CONNECTIONS {
            shared.clients_refused.fetch_add(1, Ordering::Relaxed);
            // a fresh socket's send buffer takes the short answer without waiting
            let mut conn = conn;
            if conn.set_nonblocking(true).is_ok() {
                refuse(
                    &mut conn,
                    503,
                    "Service Unavailable",
                    "503 too many connections\n",
                );
            }
            continue;
        }
        let id = shared.next_id.fetch_add(1, Ordering::Relaxed);
        let live = Live::new(&shared, Some((id, &conn)));
        // without a thread, the connection and its count end here
        let _ = std::thread::Builder::new()
            .name("propid-http-conn".into())
            .spawn(move || connection(conn, live));
    }
}

/// Reads one request and answers it; the connection then closes.
fn connection(mut conn: TcpStream, live: Live) {
    let _ = conn.set_nodelay(true);
    if conn.set_write_timeout(Some(WRITE_WITHIN)).is_err() {
        return;
    }
    let head = match request::read_head(&mut conn, HEAD_WITHIN) {
        Ok(h) => h,
        Err(f) => {
            if let Some((code, reason)) = f.status() {
                refuse(&mut conn, code, reason, &format!("{code} {reason}\n"));
            }
            return;
        }
    };
    answer(conn, &head, live);
}

/// The answer to a request: a refusal, `/events`, a named stream of the site, a file of
/// the site, or `404`.
fn answer(mut conn: TcpStream, head: &Head, live: Live) {
    let shared = live.shared.clone();
    if let Some((code, reason)) = head.refusal(shared.bound) {
        return refuse(&mut conn, code, reason, &format!("{code} {reason}\n"));
    }
    if head.method != "GET" {
        let body = "405 method not allowed: this page is read-only\n";
        return respond(
            &mut conn,
            (405, "Method Not Allowed"),
            "text/plain; charset=utf-8",
            body.as_bytes(),
            "Allow: GET\r\n",
        );
    }
    if head.path == "/events" {
        return subscribe(conn, live, &shared.events);
    }
    if let Some(named) = shared.find_stream(&head.path) {
        return subscribe(conn, live, &named);
    }
    match (shared.site.asset)(&head.path) {
        Some(a) => respond(&mut conn, (200, "OK"), a.content_type, a.body, ""),
        None => refuse(&mut conn, 404, "Not Found", "404 not found\n"),
    }
}

/// Answers `code` with a short text.
fn refuse(conn: &mut TcpStream, code: u16, reason: &str, text: &str) {
    respond(
        conn,
        (code, reason),
        "text/plain; charset=utf-8",
        text.as_bytes(),
        "",
    );
}

/// Writes one whole response (the connection closes after it); `extra`: more header lines.
fn respond(
    conn: &mut TcpStream,
    (code, reason): (u16, &str),
    content_type: &str,
    body: &[u8],
    extra: &str,
) {
    let mut out = format!(
        "HTTP/1.1 {code} {reason}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n\
         {extra}\r\n",
        body.len()
    )
    .into_bytes();
    out.extend_from_slice(body);
    if conn.write_all(&out).and_then(|_| conn.flush()).is_ok() {
        let _ = conn.shutdown(Shutdown::Write);
    }
}

/// Registers a client of `on` (with its history queued first) and writes its stream until
/// it ends; then its place is free.
fn subscribe(mut conn: TcpStream, mut live: Live, on: &Stream) {
    let shared = live.shared.clone();
    let Some(id) = live.conn else { return };
    let rx = {
        let mut clients = lock(&on.clients);
        if clients.len() >= shared.max_clients || shared.closing.load(Ordering::Relaxed) {
            drop(clients);
            shared.clients_refused.fetch_add(1, Ordering::Relaxed);
            return refuse(
                &mut conn,
                503,
                "Service Unavailable",
                "503 too many clients\n",
            );
        }
        let snapshot = lock(&on.history).snapshot();
        let (tx, rx) = bounded(shared.queue_lines + snapshot.len());
        for line in snapshot {
            let _ = tx.try_send(line);
        }
        clients.push((id, tx));
        rx
    };
    live.streams();
    stream(&mut conn, &rx);
    lock(&on.clients).retain(|c| c.0 != id);
}

/// Writes the response head and then every queued line as an event, until the queue closes
/// (the client was dropped or the sink closed), a write fails or the browser leaves.
fn stream(conn: &mut TcpStream, rx: &Receiver<Arc<str>>) {
    // the body of an event stream is open-ended: it ends with the connection
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
                X-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n";
    if conn
        .write_all(head.as_bytes())
        .and_then(|_| conn.flush())
        .is_err()
    {
        return;
    }
    let mut ev = String::new();
    let mut written = Instant::now();
    loop {
        ev.clear();
        match rx.recv_timeout(PEER_CHECK) {
            Ok(line) => {
                push_event(&mut ev, &line);
                // what else is queued goes in the same write (fewer system calls when lines
                // come fast, as in a replay)
                while ev.len() < BATCH_BYTES {
                    match rx.try_recv() {
                        Ok(line) => push_event(&mut ev, &line),
                        Err(_) => break,
                    }
                }
            }
            Err(RecvTimeoutError::Timeout) => {
                if peer_gone(conn) {
                    return;
                }
                if written.elapsed() < KEEP_ALIVE {
                    continue;
                }
                ev.push_str(": keep-alive\n\n");
            }
            Err(RecvTimeoutError::Disconnected) => return,
        }
        if conn
            .write_all(ev.as_bytes())
            .and_then(|_| conn.flush())
            .is_err()
        {
            return;
        }
        written = Instant::now();
    }
}

/// Whether an event stream's browser closed its side (or the connection failed), without
/// waiting; what it sent after its request is read and ignored (a bounded amount per call).
fn peer_gone(conn: &mut TcpStream) -> bool {
    if conn.set_nonblocking(true).is_err() {
        return true;
    }
    let mut buf = [0u8; 4096];
    let mut gone = false;
    for _ in 0..16 {
        match conn.read(&mut buf) {
            Ok(0) => {
                gone = true;
                break;
            }
            Ok(_) => {}
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if e.kind() == ErrorKind::WouldBlock => break,
            Err(_) => {
                gone = true;
                break;
            }
        }
    }
    gone || conn.set_nonblocking(false).is_err()
}

/// Appends one server-sent event carrying `line` (one JSON line: no newline inside).
fn push_event(ev: &mut String, line: &str) {
    ev.push_str("data: ");
    ev.push_str(line);
    ev.push_str("\n\n");
}
