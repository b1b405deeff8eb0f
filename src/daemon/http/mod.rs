//! The live web page's sink (`--http ADDR`, `[publish] http`): a read-only HTTP server of one
//! page that updates from the published lines by server-sent events.
//!
//! - **Its own threads.** `tiny_http` (a small synchronous HTTP/1.1 server; no hand-written
//!   request parser here) accepts and parses requests on its threads; one *serve* thread
//!   answers them; each event-stream client has its own writer thread and a bounded queue.
//!   [`HttpSink::send`] (on the worker's thread, like every sink) only does `try_send` on every
//!   queue: a client whose queue is full is dropped and counted (`dropped_clients` in the stats
//!   line), exactly as a slow socket client, so a browser that stops reading never blocks the
//!   worker, and the sampler never sees the sink at all. At most `[publish] max_clients`
//!   event streams at once; one more is answered `503` and counted (`clients_refused`).
//!   A dropped client's writer ends; its TCP connection is closed when the browser goes.
//! - **Read-only, embedded.** `GET` only (anything else `405`, with `Allow: GET`); the paths
//!   are the fixed table of [`assets`] (compiled into the binary: the page works with no
//!   network) and `/events`; anything else is `404`. No file is ever read from disk.
//! - **Loopback by default** ([`crate::daemon::config::http_address`]).
//! - **History.** A browser that connects late first gets the last [`RECENT_LINES`] events
//!   and warnings, the last [`RECENT_SAMPLES`] samples lines and the latest line of each state
//!   kind (model, response, stabilization, schedule, live stats, stats), then the live lines.
//! - **Other sites** ([`site`]): `propid fleet` serves its own file table and named event
//!   streams (one per stand) through the same server ([`HttpSink::bind_site`]).

pub mod assets;
pub mod site;

use crossbeam_channel::{bounded, Receiver, RecvTimeoutError, Sender, TrySendError};
use std::collections::VecDeque;
use std::io::Write;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use super::DaemonError;

/// Event and warning lines kept for a browser that connects late.
pub const RECENT_LINES: usize = 300;

/// `samples` lines kept for a browser that connects late (about 10 s).
pub const RECENT_SAMPLES: usize = 100;

/// A comment line is sent after this long without a line, so that a vanished browser is found.
const KEEP_ALIVE: Duration = Duration::from_secs(10);

/// Which kind of line, for the history.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A state: only the latest of its name is kept.
    State(&'static str),
    /// Kept among the recent lines.
    Log,
    /// Kept among the recent samples.
    Samples,
}

/// What the history holds.
#[derive(Default)]
struct History {
    states: Vec<(&'static str, Arc<str>)>,
    recent: VecDeque<Arc<str>>,
    samples: VecDeque<Arc<str>>,
}

/// State shared by the publisher's side and the serve thread.
struct Shared {
    /// Lock order: `clients`, then `history`.
    clients: Mutex<Vec<Sender<Arc<str>>>>,
    history: Mutex<History>,
    queue_lines: usize,
    max_clients: usize,
    closing: AtomicBool,
    dropped_clients: AtomicU64,
    clients_refused: AtomicU64,
}

/// The HTTP sink of a [`super::Publisher`].
pub struct HttpSink {
    addr: SocketAddr,
    shared: Arc<Shared>,
    server: Arc<tiny_http::Server>,
    serve: Option<JoinHandle<()>>,
    /// The site's file table and named streams ([`site`]).
    streams: Arc<site::Streams>,
}

impl Shared {
    fn new(queue_lines: usize, max_clients: usize) -> Shared {
        Shared {
            clients: Mutex::new(Vec::new()),
            history: Mutex::new(History::default()),
            queue_lines,
            max_clients,
            closing: AtomicBool::new(false),
            dropped_clients: AtomicU64::new(0),
            clients_refused: AtomicU64::new(0),
        }
    }
}

impl HttpSink {
    /// Binds `addr` (port 0: a free port, see [`HttpSink::addr`]) and starts serving the live
    /// page.
    pub fn bind(
        addr: SocketAddr,
        queue_lines: usize,
        max_clients: usize,
    ) -> Result<HttpSink, DaemonError> {
        HttpSink::bind_site(addr, queue_lines, max_clients, site::Site::LIVE)
    }

    /// Binds `addr` and serves `site`'s files and streams ([`site`]).
    pub fn bind_site(
        addr: SocketAddr,
        queue_lines: usize,
        max_clients: usize,
        site: site::Site,
    ) -> Result<HttpSink, DaemonError> {
        let bind_err = |e: String| {
            DaemonError::io(
                format!("bind http {addr}"),
                std::io::Error::new(std::io::ErrorKind::AddrNotAvailable, e),
            )
        };
        let server = tiny_http::Server::http(addr).map_err(|e| bind_err(e.to_string()))?;
        let bound = server
            .server_addr()
            .to_ip()
            .ok_or_else(|| bind_err("not an IP address".into()))?;
        let server = Arc::new(server);
        let shared = Arc::new(Shared::new(queue_lines, max_clients));
        let streams = Arc::new(site::Streams::new(site, queue_lines, max_clients));
        let (sv, sh, st) = (server.clone(), shared.clone(), streams.clone());
        let serve = std::thread::Builder::new()
            .name("propid-http".into())
            .spawn(move || serve_loop(&sv, &sh, &st))
            .map_err(|e| DaemonError::io("spawn the http thread", e))?;
        Ok(HttpSink {
            addr: bound,
            shared,
            server,
            serve: Some(serve),
            streams,
        })
    }

    /// The address bound (with the port the OS chose for port 0).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Queues `line` to every event-stream client (never waits); a client whose queue is full
    /// is dropped and counted.
    pub fn send(&self, kind: Kind, line: &str) {
        self.shared.send(kind, line);
    }

    /// A handle that sends lines to this sink's clients from another owner (e.g. `propid
    /// demo`'s own `truth` line, sent from the publisher's tap).
    pub fn sender(&self) -> LiveSender {
        LiveSender(self.shared.clone())
    }

    /// Event-stream clients dropped for falling behind.
    pub fn dropped_clients(&self) -> u64 {
        self.shared.dropped_clients.load(Ordering::Relaxed)
            + self
                .streams
                .sum(|s| s.dropped_clients.load(Ordering::Relaxed))
    }

    /// Event-stream clients refused because `max_clients` were connected.
    pub fn clients_refused(&self) -> u64 {
        self.shared.clients_refused.load(Ordering::Relaxed)
            + self
                .streams
                .sum(|s| s.clients_refused.load(Ordering::Relaxed))
    }

    /// Stops serving: the event streams end after their queued lines, the server closes.
    pub fn close(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.shared.closing.store(true, Ordering::Relaxed);
        if let Ok(mut c) = self.shared.clients.lock() {
            c.clear();
        }
        self.streams.close();
        self.server.unblock();
        if let Some(t) = self.serve.take() {
            let _ = t.join();
        }
    }
}

impl Drop for HttpSink {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Sends lines to an [`HttpSink`]'s clients, exactly as [`HttpSink::send`] (kept in the
/// history, never waits); after the sink closed, nothing.
#[derive(Clone)]
pub struct LiveSender(Arc<Shared>);

impl LiveSender {
    /// Queues `line` to every event-stream client, as [`HttpSink::send`].
    pub fn send(&self, kind: Kind, line: &str) {
        if !self.0.closing.load(Ordering::Relaxed) {
            self.0.send(kind, line);
        }
    }
}

impl Shared {
    fn send(&self, kind: Kind, line: &str) {
        let text: Arc<str> = Arc::from(line);
        let Ok(mut clients) = self.clients.lock() else {
            return;
        };
        if let Ok(mut h) = self.history.lock() {
            h.keep(kind, &text);
        }
        clients.retain(|tx| match tx.try_send(text.clone()) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                self.dropped_clients.fetch_add(1, Ordering::Relaxed);
                false
            }
            Err(TrySendError::Disconnected(_)) => false,
        });
    }
}

impl History {
    fn keep(&mut self, kind: Kind, text: &Arc<str>) {
        match kind {
            Kind::State(name) => match self.states.iter_mut().find(|s| s.0 == name) {
                Some(s) => s.1 = text.clone(),
                None => self.states.push((name, text.clone())),
            },
            Kind::Log => ring(&mut self.recent, RECENT_LINES, text),
            Kind::Samples => ring(&mut self.samples, RECENT_SAMPLES, text),
        }
    }

    fn snapshot(&self) -> Vec<Arc<str>> {
        self.recent
            .iter()
            .chain(&self.samples)
            .chain(self.states.iter().map(|s| &s.1))
            .cloned()
            .collect()
    }
}

/// Appends to a ring of at most `cap` lines.
fn ring(r: &mut VecDeque<Arc<str>>, cap: usize, text: &Arc<str>) {
    if r.len() == cap {
        r.pop_front();
    }
    r.push_back(text.clone());
}

/// Answers requests until the sink closes.
fn serve_loop(server: &tiny_http::Server, shared: &Arc<Shared>, streams: &site::Streams) {
    while !shared.closing.load(Ordering::Relaxed) {
        let request = match server.recv_timeout(Duration::from_millis(200)) {
            Ok(Some(r)) => r,
            Ok(None) => continue,
            Err(_) => break,
        };
        answer(request, shared, streams);
    }
}

/// One request: an asset, the event stream, or a refusal.
fn answer(request: tiny_http::Request, shared: &Arc<Shared>, streams: &site::Streams) {
    use tiny_http::{Method, Response};
    if *request.method() != Method::Get {
        let r = Response::from_string("405 method not allowed: this page is read-only\n")
            .with_status_code(405)
            .with_header(header("Allow", "GET"));
        let _ = request.respond(r);
        return;
    }
    let path = request.url().split('?').next().unwrap_or("").to_string();
    if path == "/events" {
        return subscribe(request, shared);
    }
    if let Some(named) = streams.find(&path) {
        return subscribe(request, &named);
    }
    let response = match (streams.site.asset)(&path) {
        Some(a) => Response::from_data(a.body)
            .with_header(header("Content-Type", a.content_type))
            .with_header(header("Cache-Control", "no-store"))
            .with_header(header("X-Content-Type-Options", "nosniff")),
        None => Response::from_string("404 not found\n").with_status_code(404),
    };
    let _ = request.respond(response);
}

/// A header from two constant strings (always valid).
fn header(name: &str, value: &str) -> tiny_http::Header {
    tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes())
        .unwrap_or_else(|()| unreachable!("constant header {name}"))
}

/// Registers an event-stream client (with the history queued first) and starts its writer.
fn subscribe(request: tiny_http::Request, shared: &Arc<Shared>) {
    let rx = {
        let Ok(mut clients) = shared.clients.lock() else {
            return;
        };
        if clients.len() >= shared.max_clients {
            drop(clients);
            shared.clients_refused.fetch_add(1, Ordering::Relaxed);
            let r =
                tiny_http::Response::from_string("503 too many clients\n").with_status_code(503);
            let _ = request.respond(r);
            return;
        }
        let snapshot = match shared.history.lock() {
            Ok(h) => h.snapshot(),
            Err(_) => Vec::new(),
        };
        let (tx, rx) = bounded(shared.queue_lines + snapshot.len());
        for line in snapshot {
            let _ = tx.try_send(line);
        }
        clients.push(tx);
        rx
    };
    // without a thread the receiver is gone with the closure: the place is freed at the next
    // line, as when a browser leaves
    let _ = std::thread::Builder::new()
        .name("propid-http-client".into())
        .spawn(move || stream(request.into_writer(), &rx));
}

/// Writes the response head and then every queued line as an event, until the queue closes
/// (the client was dropped or the sink closed) or the browser goes.
fn stream(mut w: Box<dyn Write + Send>, rx: &Receiver<Arc<str>>) {
    // tiny_http parsed the request; the body of an event stream is open-ended, so the head
    // says so and the connection ends with the stream
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
                X-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n";
    if w.write_all(head.as_bytes())
        .and_then(|_| w.flush())
        .is_err()
    {
        return;
    }
    let mut ev = String::new();
    loop {
        ev.clear();
        match rx.recv_timeout(KEEP_ALIVE) {
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
            Err(RecvTimeoutError::Timeout) => ev.push_str(": keep-alive\n\n"),
            Err(RecvTimeoutError::Disconnected) => return,
        }
        if w.write_all(ev.as_bytes()).and_then(|_| w.flush()).is_err() {
            return;
        }
    }
}

/// Queued lines written at once, at most about this many bytes.
const BATCH_BYTES: usize = 64 * 1024;

/// Appends one server-sent event carrying `line` (one JSON line: no newline inside).
fn push_event(ev: &mut String, line: &str) {
    ev.push_str("data: ");
    ev.push_str(line);
    ev.push_str("\n\n");
}

#[cfg(test)]
mod tests;
