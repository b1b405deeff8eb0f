//! The live web page's sink (`--http ADDR`, `[publish] http`): a read-only HTTP server of one
//! page that updates from the published lines by server-sent events.
//!
//! - **Its own threads, none waiting on a client.** One thread accepts; each connection has a
//!   thread of its own that reads one request head ([`request`]: at most [`request::MAX_HEAD`]
//!   bytes within a few seconds, parsed by `httparse`), answers it and closes the connection
//!   (`Connection: close`, no pipelining). At most [`PAGE_CONNECTIONS`] connections
//!   wait for or get a page answer at once; one more is answered `503` and closed at once by
//!   the accepting thread, and counted (`clients_refused`). Every read and write on a
//!   connection has a time limit. Closing the sink ([`HttpSink::close`], on drop) waits about
//!   a second for the event streams to send their queued lines, then shuts every connection
//!   down and returns at most a moment later, whatever a client does.
//! - **Never by a client's number.** Only HTTP/1.0 and 1.1 (else `505`); a head over the
//!   limit is `431`; a request with a body (`Content-Length` other than 0, any
//!   `Transfer-Encoding`) is `413` and its body is never read; a `Host` that is not this
//!   server (its port with `localhost`, a loopback address or the address bound: a DNS name
//!   that a hostile page made resolve here is refused) is `421`.
//! - **Event streams.** [`HttpSink::send`] (on the worker's thread, like every sink) only does
//!   `try_send` on every stream's bounded queue: a client whose queue is full is dropped and
//!   counted (`dropped_clients` in the stats line), exactly as a slow socket client, so a
//!   browser that stops reading never blocks the worker, and the sampler never sees the sink
//!   at all. At most `[publish] max_clients` event streams at once; one more is answered `503`
//!   and counted (`clients_refused`). A stream whose browser left (its connection closed, or a
//!   write failed) ends within a second and frees its place, lines or not.
//! - **Read-only, embedded.** `GET` only (anything else `405`, with `Allow: GET`); the paths
//!   are the fixed table of [`assets`] (compiled into the binary: the page works with no
//!   network) and `/events`; anything else is `404`. No file is ever read from disk.
//! - **Loopback by default** ([`crate::daemon::config::http_address`]).
//! - **History.** A browser that connects late first gets the last [`RECENT_LINES`] events
//!   and warnings, the last [`RECENT_SAMPLES`] samples lines and the latest line of each state
//!   kind (model, response, stabilization, schedule, live stats, stats), then the live lines.
//! - **Other sites** ([`site`]): `propid fleet` serves its own file table and named event
//!   streams (one per stand) through the same server ([`HttpSink::bind_site`]), each stream
//!   under the same rules as `/events`.

pub mod assets;
pub mod request;
mod server;
pub mod site;

pub use server::PAGE_CONNECTIONS;

use crossbeam_channel::{Sender, TrySendError};
use std::collections::{HashMap, VecDeque};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use super::DaemonError;
use site::Site;

/// Event and warning lines kept for a browser that connects late.
pub const RECENT_LINES: usize = 300;

/// `samples` lines kept for a browser that connects late (about 10 s).
pub const RECENT_SAMPLES: usize = 100;

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

/// One event stream (`/events`, or a named stream of [`site`]): its clients and history.
#[derive(Default)]
struct Stream {
    /// The clients' queues, by connection. Lock order: `clients`, then `history`.
    clients: Mutex<Vec<(u64, Sender<Arc<str>>)>>,
    history: Mutex<History>,
}

/// State shared by the publisher's side and the server's threads.
struct Shared {
    /// `/events`.
    events: Stream,
    /// The site's named streams, by name (created by their first line).
    named: Mutex<Vec<(String, Arc<Stream>)>>,
    queue_lines: usize,
    /// Clients of each stream at most.
    max_clients: usize,
    closing: AtomicBool,
    dropped_clients: AtomicU64,
    clients_refused: AtomicU64,
    /// The address bound (for the `Host` check).
    bound: SocketAddr,
    /// The files and named streams served.
    site: Site,
    /// Connections not (yet) event streams.
    pending: AtomicUsize,
    /// The server's live threads (the accepting one and one per connection) ...
    threads: Mutex<usize>,
    /// ... signalled when one ends.
    thread_ended: Condvar,
    /// A handle on every open connection, to shut it down at close.
    conns: Mutex<HashMap<u64, TcpStream>>,
    next_id: AtomicU64,
}

/// Locks `m`, also after a thread panicked holding it (every value behind these locks stays
/// valid between two statements).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The HTTP sink of a [`super::Publisher`].
pub struct HttpSink {
    addr: SocketAddr,
    shared: Arc<Shared>,
    closed: bool,
}

/// How long closing waits for the event streams to send their queued lines.
const CLOSE_GRACE: Duration = Duration::from_secs(1);

/// How long closing waits then for the connections it shut down.
const CLOSE_FORCED: Duration = Duration::from_millis(200);

impl HttpSink {
    /// Binds `addr` (port 0: a free port, see [`HttpSink::addr`]) and starts serving the
    /// live page ([`Site::LIVE`]: the files of [`assets::get`] and `/events`).
    pub fn bind(
        addr: SocketAddr,
        queue_lines: usize,
        max_clients: usize,
    ) -> Result<HttpSink, DaemonError> {
        HttpSink::bind_site(addr, queue_lines, max_clients, Site::LIVE)
    }

    /// [`HttpSink::bind`] serving another site: its table of embedded files and its named
    /// streams ([`site`]); `/events` is always the event stream, `max_clients` is per stream.
    pub fn bind_site(
        addr: SocketAddr,
        queue_lines: usize,
        max_clients: usize,
        site: Site,
    ) -> Result<HttpSink, DaemonError> {
        let err = |e| DaemonError::io(format!("bind http {addr}"), e);
        let listener = TcpListener::bind(addr).map_err(err)?;
        let bound = listener.local_addr().map_err(err)?;
        let shared = Arc::new(Shared {
            events: Stream::default(),
            named: Mutex::new(Vec::new()),
            queue_lines,
            max_clients,
            closing: AtomicBool::new(false),
            dropped_clients: AtomicU64::new(0),
            clients_refused: AtomicU64::new(0),
            bound,
            site,
            pending: AtomicUsize::new(0),
            threads: Mutex::new(0),
            thread_ended: Condvar::new(),
            conns: Mutex::new(HashMap::new()),
            next_id: AtomicU64::new(0),
        });
        server::start(listener, &shared)
            .map_err(|e| DaemonError::io("spawn the http thread", e))?;
        Ok(HttpSink {
            addr: bound,
            shared,
            closed: false,
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
        self.shared.send(&self.shared.events, kind, line);
    }

    /// A handle that sends lines to this sink's clients from another owner (e.g. `propid
    /// demo`'s own `truth` line, sent from the publisher's tap).
    pub fn sender(&self) -> LiveSender {
        LiveSender(self.shared.clone())
    }

    /// Event-stream clients dropped for falling behind (of every stream).
    pub fn dropped_clients(&self) -> u64 {
        self.shared.dropped_clients.load(Ordering::Relaxed)
    }

    /// Clients refused: event streams because `max_clients` were connected (to that stream),
    /// connections
    /// because [`PAGE_CONNECTIONS`] were waiting for an answer.
    pub fn clients_refused(&self) -> u64 {
        self.shared.clients_refused.load(Ordering::Relaxed)
    }

    /// Stops serving: the event streams end after their queued lines (given about a second),
    /// every connection is shut down; returns within [`CLOSE_GRACE`] and [`CLOSE_FORCED`]
    /// whatever the clients do (a thread still running then ends on its own).
    pub fn close(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        if std::mem::replace(&mut self.closed, true) {
            return;
        }
        let sh = &self.shared;
        {
            let mut clients = lock(&sh.events.clients);
            sh.closing.store(true, Ordering::Relaxed);
            clients.clear();
        }
        // a stream subscribing now sees `closing` under its lock, or its queue is cleared here
        for (_, s) in lock(&sh.named).iter() {
            lock(&s.clients).clear();
        }
        server::wake(sh.bound);
        // requests not yet read end at once; the streams end after their queues
        server::shut_all(sh, std::net::Shutdown::Read);
        if !server::wait_threads(sh, CLOSE_GRACE) {
            server::shut_all(sh, std::net::Shutdown::Both);
            server::wait_threads(sh, CLOSE_FORCED);
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
            self.0.send(&self.0.events, kind, line);
        }
    }
}

impl Shared {
    /// Queues `line` to `stream`'s clients (never waits) and keeps it in its history.
    fn send(&self, stream: &Stream, kind: Kind, line: &str) {
        let text: Arc<str> = Arc::from(line);
        let mut clients = lock(&stream.clients);
        lock(&stream.history).keep(kind, &text);
        clients.retain(|(_, tx)| match tx.try_send(text.clone()) {
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

#[cfg(test)]
mod tests;
