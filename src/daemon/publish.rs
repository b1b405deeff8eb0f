//! Publishing: JSON lines fanned out to stdout, a file and a UNIX socket.
//!
//! One object per line. Every sink gets every line, in order:
//! - **stdout**: written and flushed per line. A closed pipe (`propid run | head`: EPIPE)
//!   quietly disables the sink, as coreutils end quietly ([`crate::cli::stdout`]); the daemon
//!   keeps running for the other sinks. Any other write error (`> /dev/full`) disables it too,
//!   is published to the other sinks as an `output_failed` warning, and is kept: the run goes
//!   on, and ends with `write error: stdout: ...` and exit 7 ([`Publisher::take_error`]).
//! - **file**: opened for append, each line written with one `write_all` and flushed, so a crash
//!   loses nothing already published.
//! - **UNIX socket**: an accept thread registers clients; each client has a bounded queue of
//!   lines and a writer thread. [`Publisher::publish`] only does `try_send` on every queue: a
//!   client whose queue is full is dropped (its connection closed), so a slow subscriber never
//!   blocks the worker. At most `[publish] max_clients` clients are served: one more is sent a
//!   `too_many_clients` warning line, closed and counted (`clients_refused` in the stats line),
//!   so idle clients cannot exhaust the descriptors the serial port needs to reopen. A client's
//!   place is freed at the first line after it left.
//!
//!   The socket file is the daemon's own: a socket file at the path that answers `connect()`
//!   belongs to a live daemon and is an error (`socket ... is in use`, exit 7: the configuration
//!   is valid, the path is busy now), one that refuses is stale and replaced. It is created with
//!   mode 0600 (owner only; umask 0177 while binding), or 0660 and the group `[publish]
//!   socket_group`; it is removed at exit only while it is still the one this daemon bound.
//!
//! - **MQTT** (`[publish] mqtt`): [`super::mqtt::MqttSink`], its own thread and bounded
//!   queue; never waits.
//!
//! Lines come in typed ([`Line`]) and are serialised here, once ([`Line::to_json`]). A *tap*
//! ([`Publisher::with_tap`]) sees every typed line beside its bytes, in order, on the publishing
//! thread: how `propid demo` prints models without re-parsing the JSON.

use crossbeam_channel::{bounded, Sender, TrySendError};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use super::config::PublishConfig;
use super::http::{HttpSink, Kind};
use super::line::Event;
use super::line::{Line, Warning};
use super::mqtt::MqttSink;
use super::stats::MqttStats;
use super::DaemonError;

/// Sees every published line, typed and as published (without the newline).
pub type Tap = Box<dyn FnMut(&Line<'_>, &str) + Send>;

/// A connected socket subscriber: the sending end of its queue.
struct Client {
    tx: Sender<Arc<str>>,
}

/// State shared between the publisher and the socket's accept thread.
struct SocketShared {
    clients: Mutex<Vec<Client>>,
    queue_lines: usize,
    closing: AtomicBool,
    dropped_clients: AtomicU64,
    max_clients: usize,
    clients_refused: AtomicU64,
}

/// The UNIX socket sink.
struct SocketSink {
    path: PathBuf,
    /// (device, inode) of the socket file bound, so only it is removed at exit.
    file_id: Option<(u64, u64)>,
    shared: Arc<SocketShared>,
    accept: Option<JoinHandle<()>>,
}

/// Fans every published line out to the configured sinks.
pub struct Publisher {
    stdout: bool,
    /// Why the stdout sink failed (not for a closed pipe), until [`Publisher::take_error`].
    stdout_error: Option<std::io::Error>,
    file: Option<File>,
    socket: Option<SocketSink>,
    capture: Option<Arc<Mutex<Vec<String>>>>,
    tap: Option<Tap>,
    lines: u64,
    /// The live web page's server (`--http`), when configured.
    http: Option<HttpSink>,
    /// The MQTT broker's client (`[publish] mqtt`), when configured.
    mqtt: Option<MqttSink>,
}

impl Publisher {
    /// Opens the configured sinks (creates the file, binds the socket).
    pub fn open(cfg: &PublishConfig) -> Result<Publisher, DaemonError> {
        let file =
            match &cfg.file {
                Some(p) => Some(open_publish_file(p).map_err(|e| {
                    DaemonError::io(format!("open publish file {}", p.display()), e)
                })?),
                None => None,
            };
        let socket = match &cfg.socket {
            Some(p) => Some(SocketSink::bind(p, cfg)?),
            None => None,
        };
        let http = match cfg.http {
            Some(a) => Some(HttpSink::bind(a, cfg.client_queue_lines, cfg.max_clients)?),
            None => None,
        };
        let mqtt = match &cfg.mqtt {
            Some(m) => Some(MqttSink::start(m)?),
            None => None,
        };
        Ok(Publisher {
            stdout: cfg.stdout,
            stdout_error: None,
            file,
            socket,
            capture: None,
            tap: None,
            lines: 0,
            http,
            mqtt,
        })
    }

    /// A publisher with no sinks that keeps every line in memory (tests).
    pub fn capture() -> (Publisher, Arc<Mutex<Vec<String>>>) {
        let lines = Arc::new(Mutex::new(Vec::new()));
        let p = Publisher {
            stdout: false,
            stdout_error: None,
            file: None,
            socket: None,
            capture: Some(lines.clone()),
            tap: None,
            lines: 0,
            http: None,
            mqtt: None,
        };
        (p, lines)
    }

    /// Also hands every line to `tap` (in addition to the configured sinks).
    pub fn with_tap(mut self, tap: Tap) -> Publisher {
        self.tap = Some(tap);
        self
    }

    /// Serialises `line` (the one place a line becomes bytes) and publishes it.
    pub fn publish_line(&mut self, line: &Line<'_>) -> Result<(), DaemonError> {
        let text = line.to_json().map_err(DaemonError::Serialize)?;
        if let Some(tap) = self.tap.as_mut() {
            tap(line, &text);
        }
        let had_failed = self.stdout_error.is_some();
        self.publish(&text)?;
        if let Some(h) = &self.http {
            h.send(http_kind(line), &text);
        }
        if let Some(m) = &mut self.mqtt {
            m.send(line, &text);
        }
        if let (false, Some(e)) = (had_failed, &self.stdout_error) {
            let message = e.to_string();
            let warning = Line::Warning(Warning::OutputFailed {
                sink: "stdout",
                path: None,
                message: &message,
            });
            let text = warning.to_json().map_err(DaemonError::Serialize)?;
            self.publish(&text)?;
            if let Some(h) = &self.http {
                h.send(Kind::Log, &text);
            }
            if let Some(m) = &mut self.mqtt {
                m.send(&warning, &text);
            }
        }
        Ok(())
    }

    /// Publishes a line to the web page's clients only ([`super::live`]), and its `samples`
    /// lines to MQTT with `mqtt_samples`; nothing without either (check
    /// [`Publisher::is_live`] before building one).
    pub fn publish_live(&mut self, line: &Line<'_>) -> Result<(), DaemonError> {
        let mqtt = match &mut self.mqtt {
            Some(m) if m.wants_samples() && matches!(line, Line::Samples(_)) => Some(m),
            _ => None,
        };
        if self.http.is_none() && mqtt.is_none() {
            return Ok(());
        }
        let text = line.to_json().map_err(DaemonError::Serialize)?;
        if let Some(m) = mqtt {
            m.send(line, &text);
        }
        if let Some(h) = &self.http {
            h.send(http_kind(line), &text);
        }
        Ok(())
    }

    /// Whether a web page is served, or MQTT takes live samples (the worker then builds the
    /// [`super::live`] lines).
    pub fn is_live(&self) -> bool {
        self.http.is_some() || self.mqtt.as_ref().is_some_and(MqttSink::wants_samples)
    }

    /// The MQTT sink's counters (with `[publish] mqtt`).
    pub fn mqtt_stats(&self) -> Option<MqttStats> {
        self.mqtt.as_ref().map(MqttSink::stats)
    }

    /// A handle that sends lines to the web page's clients only, from outside the publisher
    /// (`propid demo`'s `truth` line), when it is served.
    pub fn live_sender(&self) -> Option<super::http::LiveSender> {
        self.http.as_ref().map(HttpSink::sender)
    }

    /// The web page's URL, when it is served.
    pub fn http_url(&self) -> Option<String> {
        self.http.as_ref().map(HttpSink::url)
    }

    /// The failure of an output that the run went on without (stdout, not a closed pipe), once.
    pub fn take_error(&mut self) -> Option<DaemonError> {
        self.stdout_error.take().map(|source| DaemonError::Output {
            sink: "stdout".into(),
            source,
        })
    }

    /// Publishes one line of text (without its newline) to every sink.
    fn publish(&mut self, line: &str) -> Result<(), DaemonError> {
        self.lines += 1;
        if self.stdout {
            let mut out = std::io::stdout().lock();
            let r = writeln!(out, "{line}").and_then(|_| out.flush());
            if let Err(e) = r {
                self.stdout = false;
                // A closed pipe (the reader went away) is not a failure; anything else is.
                if e.kind() != std::io::ErrorKind::BrokenPipe {
                    self.stdout_error = Some(e);
                }
            }
        }
        if let Some(f) = &mut self.file {
            let mut buf = String::with_capacity(line.len() + 1);
            buf.push_str(line);
            buf.push('\n');
            f.write_all(buf.as_bytes())
                .and_then(|_| f.flush())
                .map_err(|e| DaemonError::io("append to the publish file", e))?;
        }
        if let Some(s) = &self.socket {
            s.send(line);
        }
        if let Some(c) = &self.capture {
            if let Ok(mut v) = c.lock() {
                v.push(line.to_string());
            }
        }
        Ok(())
    }

    /// Lines published so far.
    pub fn lines(&self) -> u64 {
        self.lines
    }

    /// Socket and web-page clients dropped because they fell behind.
    pub fn dropped_clients(&self) -> u64 {
        self.socket
            .as_ref()
            .map_or(0, |s| s.shared.dropped_clients.load(Ordering::Relaxed))
            + self.http.as_ref().map_or(0, HttpSink::dropped_clients)
    }

    /// Socket and web-page clients refused because `max_clients` were connected (`None`
    /// without a socket or a web page).
    pub fn clients_refused(&self) -> Option<u64> {
        let socket = self
            .socket
            .as_ref()
            .map(|s| s.shared.clients_refused.load(Ordering::Relaxed));
        let http = self.http.as_ref().map(HttpSink::clients_refused);
        match (socket, http) {
            (None, None) => None,
            (a, b) => Some(a.unwrap_or(0) + b.unwrap_or(0)),
        }
    }

    /// Flushes every sink and closes the socket (queued lines are still delivered).
    pub fn close(&mut self) {
        if let Some(f) = &mut self.file {
            let _ = f.sync_data();
        }
        if let Some(s) = self.socket.take() {
            s.close();
        }
        if let Some(h) = self.http.take() {
            h.close();
        }
        if let Some(m) = self.mqtt.take() {
            m.close();
        }
    }
}

/// How the web page's history keeps a line.
fn http_kind(line: &Line<'_>) -> Kind {
    match line {
        Line::Model(_) | Line::Kind(propid_kinds::Published::Model(_)) => Kind::State("model"),
        Line::Schedule(_) => Kind::State("schedule"),
        Line::Stats(_) => Kind::State("stats"),
        Line::LiveStats(_) => Kind::State("live_stats"),
        Line::Response(_) => Kind::State("response"),
        Line::Stabilization(_) => Kind::State("stabilization"),
        Line::Event(Event::Http { .. }) => Kind::State("http"),
        Line::Samples(_) => Kind::Samples,
        Line::Kind(propid_kinds::Published::FrequencyResponse(_)) => {
            Kind::State("frequency_response")
        }
        Line::Event(_) | Line::Warning(_) | Line::Kind(_) => Kind::Log,
    }
}

impl Drop for Publisher {
    fn drop(&mut self) {
        self.close();
    }
}

impl SocketSink {
    fn bind(path: &Path, cfg: &PublishConfig) -> Result<SocketSink, DaemonError> {
        let bind_err = |e| DaemonError::io(format!("bind socket {}", path.display()), e);
        replace_stale_socket(path).map_err(bind_err)?;
        // owner only from the start: no moment where the umask's mode lets others connect
        // (the umask is process-wide; no other thread runs yet)
        let old = unsafe { libc::umask(0o177) };
        let bound = UnixListener::bind(path);
        unsafe { libc::umask(old) };
        let listener = bound.map_err(bind_err)?;
        set_access(path, cfg.socket_group).map_err(|e| {
            let _ = std::fs::remove_file(path);
            DaemonError::io(format!("set the mode of socket {}", path.display()), e)
        })?;
        let file_id = file_id(path);
        listener
            .set_nonblocking(true)
            .map_err(|e| DaemonError::io("socket nonblocking", e))?;
        let shared = Arc::new(SocketShared {
            clients: Mutex::new(Vec::new()),
            queue_lines: cfg.client_queue_lines,
            closing: AtomicBool::new(false),
            dropped_clients: AtomicU64::new(0),
            max_clients: cfg.max_clients,
            clients_refused: AtomicU64::new(0),
        });
        let sh = shared.clone();
        let accept = std::thread::Builder::new()
            .name("propid-accept".into())
            .spawn(move || accept_loop(listener, sh))
            .map_err(|e| DaemonError::io("spawn the socket thread", e))?;
        Ok(SocketSink {
            path: path.to_path_buf(),
            file_id,
            shared,
            accept: Some(accept),
        })
    }

    /// Offers the line to every client; drops the ones whose queue is full or closed.
    fn send(&self, line: &str) {
        let Ok(mut clients) = self.shared.clients.lock() else {
            return;
        };
        if clients.is_empty() {
            return;
        }
        let line: Arc<str> = Arc::from(line);
        let before = clients.len();
        clients.retain(|c| match c.tx.try_send(line.clone()) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) | Err(TrySendError::Disconnected(_)) => false,
        });
        let dropped = (before - clients.len()) as u64;
        self.shared
            .dropped_clients
            .fetch_add(dropped, Ordering::Relaxed);
    }

    fn close(mut self) {
        self.shared.closing.store(true, Ordering::Relaxed);
        if let Some(h) = self.accept.take() {
            let _ = h.join();
        }
        if let Ok(mut c) = self.shared.clients.lock() {
            c.clear(); // writers drain their queues, then close
        }
        // another daemon may have replaced a socket it found stale: leave its file alone
        if self.file_id.is_some() && file_id(&self.path) == self.file_id {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// A socket file at `path` that refuses connections is stale (its daemon is gone): removed. One
/// that accepts belongs to a live daemon: `AddrInUse`. Anything that is not a socket is left
/// for `bind` to refuse.
fn replace_stale_socket(path: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::FileTypeExt;
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    if !meta.file_type().is_socket() {
        // never removed: it is not ours (bind would only say "Address already in use")
        return Err(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!(
                "it exists and is {}, not a socket: remove it or set another [publish] socket",
                kind_of(&meta.file_type())
            ),
        ));
    }
    match UnixStream::connect(path) {
        Ok(_) => Err(std::io::Error::new(
            std::io::ErrorKind::AddrInUse,
            "in use: another process (a second propid?) serves it; stop it or set another [publish] socket",
        )),
        Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => {
            std::fs::remove_file(path)
        }
        Err(_) => Ok(()),
    }
}

/// What a file type is, for messages.
fn kind_of(t: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_file() {
        "a regular file"
    } else if t.is_dir() {
        "a directory"
    } else if t.is_symlink() {
        "a symbolic link"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else {
        "a socket"
    }
}

/// Opens the publish file for append: a regular file (created when missing) or a character
/// device (`/dev/null`, a terminal). A FIFO or a socket is refused: opening a FIFO blocks
/// until a reader appears, and a reader that stops reading would block every line (the
/// socket is the sink for subscribers: it drops a slow one).
fn open_publish_file(p: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::FileTypeExt;
    if let Ok(meta) = std::fs::metadata(p) {
        let t = meta.file_type();
        if !(t.is_file() || t.is_char_device()) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "it is {}: the publish file must be a regular file (subscribe through [publish] socket instead)",
                    kind_of(&t)
                ),
            ));
        }
    }
    OpenOptions::new().create(true).append(true).open(p)
}

/// Mode 0600, or 0660 with the group `gid`.
fn set_access(path: &Path, gid: Option<u32>) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    if let Some(gid) = gid {
        std::os::unix::fs::chown(path, None, Some(gid))?;
    }
    let mode = if gid.is_some() { 0o660 } else { 0o600 };
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode))
}

/// (device, inode) of `path`, if it exists.
fn file_id(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::symlink_metadata(path)
        .ok()
        .map(|m| (m.dev(), m.ino()))
}

/// Accepts clients until the sink closes; polls so that closing needs no wake-up connection.
fn accept_loop(listener: UnixListener, shared: Arc<SocketShared>) {
    while !shared.closing.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => add_client(stream, &shared),
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(20))
            }
            Err(_) => std::thread::sleep(Duration::from_millis(20)),
        }
    }
}

/// What a refused client reads before its connection is closed.
const REFUSED_LINE: &[u8] = b"{\"kind\":\"too_many_clients\",\"message\":\"publish.max_clients clients are connected; try again later\",\"type\":\"warning\"}\n";

/// Registers a client and starts its writer thread; refuses it (counted) when `max_clients`
/// are connected.
fn add_client(mut stream: UnixStream, shared: &SocketShared) {
    let full = shared
        .clients
        .lock()
        .map_or(true, |c| c.len() >= shared.max_clients);
    if full {
        shared.clients_refused.fetch_add(1, Ordering::Relaxed);
        let _ = stream.write_all(REFUSED_LINE); // non-blocking: best effort
        return; // dropped: closed
    }
    if stream.set_nonblocking(false).is_err() {
        return;
    }
    // A client that stops reading blocks only its own writer, and only this long.
    let _ = stream.set_write_timeout(Some(Duration::from_secs(2)));
    let (tx, rx) = bounded::<Arc<str>>(shared.queue_lines);
    let spawned = std::thread::Builder::new()
        .name("propid-client".into())
        .spawn(move || {
            let mut stream = stream;
            for line in rx.iter() {
                if stream
                    .write_all(line.as_bytes())
                    .and_then(|_| stream.write_all(b"\n"))
                    .is_err()
                {
                    return;
                }
            }
        });
    if spawned.is_ok() {
        if let Ok(mut c) = shared.clients.lock() {
            c.push(Client { tx });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daemon::line::Event;
    use std::io::{BufRead, BufReader};

    fn cfg(file: Option<PathBuf>, socket: Option<PathBuf>, q: usize) -> PublishConfig {
        PublishConfig {
            stdout: false,
            file,
            socket,
            client_queue_lines: q,
            max_clients: 64,
            socket_group: None,
            http: None,
            http_hold: false,
            mqtt: None,
        }
    }

    #[test]
    fn file_sink_appends_every_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.jsonl");
        std::fs::write(&path, "old\n").unwrap();
        let mut p = Publisher::open(&cfg(Some(path.clone()), None, 4)).unwrap();
        p.publish_line(&Line::Event(Event::Segment { boot_id: 1 }))
            .unwrap();
        p.publish("{\"type\":\"stats\"}").unwrap();
        // flushed per line: visible before close
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            "old\n{\"boot_id\":1,\"kind\":\"segment\",\"type\":\"event\"}\n{\"type\":\"stats\"}\n"
        );
        assert_eq!(p.lines(), 2);
    }

    fn wait_clients(p: &Publisher, n: usize) {
        let s = p.socket.as_ref().unwrap();
        for _ in 0..200 {
            if s.shared.clients.lock().unwrap().len() == n {
                return;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        panic!("clients never connected");
    }

    #[test]
    fn every_socket_client_gets_every_line() {
        let dir = tempfile::tempdir().unwrap();
        let sock = dir.path().join("p.sock");
        let mut p = Publisher::open(&cfg(None, Some(sock.clone()), 64)).unwrap();
        let a = UnixStream::connect(&sock).unwrap();
        let b = UnixStream::connect(&sock).unwrap();
        wait_clients(&p, 2);
        for i in 0..10 {
            p.publish(&format!("{{\"i\":{i}}}")).unwrap();
        }
        p.close();
        for s in [a, b] {
            let lines: Vec<String> = BufReader::new(s).lines().map(|l| l.unwrap()).collect();
            assert_eq!(lines.len(), 10);
            assert_eq!(lines[9], "{\"i\":9}");
        }
    }

    #[test]
    fn slow_client_is_dropped_and_never_blocks() {
        let dir = tempfile::tempdir().unwrap();
        let sock = dir.path().join("p.sock");
        let mut p = Publisher::open(&cfg(None, Some(sock.clone()), 2)).unwrap();
        let _never_reads = UnixStream::connect(&sock).unwrap();
        wait_clients(&p, 1);
        let big = "x".repeat(64 * 1024);
        let t = std::time::Instant::now();
        for _ in 0..200 {
            p.publish(&big).unwrap();
        }
        assert!(t.elapsed() < Duration::from_secs(1));
        assert_eq!(p.dropped_clients(), 1);
        assert_eq!(
            p.socket
                .as_ref()
                .unwrap()
                .shared
                .clients
                .lock()
                .unwrap()
                .len(),
            0
        );
    }

    #[test]
    fn the_tap_sees_every_typed_line_with_its_bytes() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let s2 = seen.clone();
        let (p, lines) = Publisher::capture();
        let mut p = p.with_tap(Box::new(move |line, text| {
            let kind = matches!(line, Line::Event(Event::Reconnected { .. }));
            s2.lock().unwrap().push((kind, text.to_string()));
        }));
        p.publish_line(&Line::Event(Event::Reconnected { device_node: None }))
            .unwrap();
        p.publish_line(&Line::Event(Event::CsvLink)).unwrap();
        let seen = seen.lock().unwrap();
        assert_eq!(seen.len(), 2);
        assert!(seen[0].0 && !seen[1].0);
        assert_eq!(seen[0].1, r#"{"kind":"reconnected","type":"event"}"#);
        assert_eq!(
            *lines.lock().unwrap(),
            seen.iter().map(|s| s.1.clone()).collect::<Vec<_>>()
        );
    }

    #[test]
    fn capture_keeps_lines() {
        let (mut p, lines) = Publisher::capture();
        p.publish("a").unwrap();
        p.publish("b").unwrap();
        assert_eq!(
            *lines.lock().unwrap(),
            vec!["a".to_string(), "b".to_string()]
        );
    }
}
