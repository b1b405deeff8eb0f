//! Publishing: JSON lines fanned out to stdout, a file and a UNIX socket.
//!
//! One object per line. Every sink gets every line, in order:
//! - **stdout**: written and flushed per line. A closed pipe (`propid run | head`) silently
//!   disables the sink; the daemon keeps running for the other sinks.
//! - **file**: opened for append, each line written with one `write_all` and flushed, so a crash
//!   loses nothing already published.
//! - **UNIX socket**: an accept thread registers clients; each client has a bounded queue of
//!   lines and a writer thread. [`Publisher::publish`] only does `try_send` on every queue: a
//!   client whose queue is full is dropped (its connection closed), so a slow subscriber never
//!   blocks the worker.
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
use super::line::Line;
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
}

/// The UNIX socket sink.
struct SocketSink {
    path: PathBuf,
    shared: Arc<SocketShared>,
    accept: Option<JoinHandle<()>>,
}

/// Fans every published line out to the configured sinks.
pub struct Publisher {
    stdout: bool,
    file: Option<File>,
    socket: Option<SocketSink>,
    capture: Option<Arc<Mutex<Vec<String>>>>,
    tap: Option<Tap>,
    lines: u64,
}

impl Publisher {
    /// Opens the configured sinks (creates the file, binds the socket).
    pub fn open(cfg: &PublishConfig) -> Result<Publisher, DaemonError> {
        let file = match &cfg.file {
            Some(p) => Some(
                OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(p)
                    .map_err(|e| {
                        DaemonError::io(format!("open publish file {}", p.display()), e)
                    })?,
            ),
            None => None,
        };
        let socket = match &cfg.socket {
            Some(p) => Some(SocketSink::bind(p, cfg.client_queue_lines)?),
            None => None,
        };
        Ok(Publisher {
            stdout: cfg.stdout,
            file,
            socket,
            capture: None,
            tap: None,
            lines: 0,
        })
    }

    /// A publisher with no sinks that keeps every line in memory (tests).
    pub fn capture() -> (Publisher, Arc<Mutex<Vec<String>>>) {
        let lines = Arc::new(Mutex::new(Vec::new()));
        let p = Publisher {
            stdout: false,
            file: None,
            socket: None,
            capture: Some(lines.clone()),
            tap: None,
            lines: 0,
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
        self.publish(&text)
    }

    /// Publishes one line of text (without its newline) to every sink.
    fn publish(&mut self, line: &str) -> Result<(), DaemonError> {
        self.lines += 1;
        if self.stdout {
            let mut out = std::io::stdout().lock();
            let r = writeln!(out, "{line}").and_then(|_| out.flush());
            if r.is_err() {
                // A closed stdout (reader went away) is not a daemon failure.
                self.stdout = false;
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

    /// Socket clients dropped because they fell behind.
    pub fn dropped_clients(&self) -> u64 {
        self.socket
            .as_ref()
            .map_or(0, |s| s.shared.dropped_clients.load(Ordering::Relaxed))
    }

    /// Flushes every sink and closes the socket (queued lines are still delivered).
    pub fn close(&mut self) {
        if let Some(f) = &mut self.file {
            let _ = f.sync_data();
        }
        if let Some(s) = self.socket.take() {
            s.close();
        }
    }
}

impl Drop for Publisher {
    fn drop(&mut self) {
        self.close();
    }
}

impl SocketSink {
    fn bind(path: &Path, queue_lines: usize) -> Result<SocketSink, DaemonError> {
        // A stale socket file from an earlier run would make bind fail; only remove sockets.
        if let Ok(meta) = std::fs::symlink_metadata(path) {
            use std::os::unix::fs::FileTypeExt;
            if meta.file_type().is_socket() {
                let _ = std::fs::remove_file(path);
            }
        }
        let listener = UnixListener::bind(path)
            .map_err(|e| DaemonError::io(format!("bind socket {}", path.display()), e))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| DaemonError::io("socket nonblocking", e))?;
        let shared = Arc::new(SocketShared {
            clients: Mutex::new(Vec::new()),
            queue_lines,
            closing: AtomicBool::new(false),
            dropped_clients: AtomicU64::new(0),
        });
        let sh = shared.clone();
        let accept = std::thread::Builder::new()
            .name("propid-accept".into())
            .spawn(move || accept_loop(listener, sh))
            .map_err(|e| DaemonError::io("spawn the socket thread", e))?;
        Ok(SocketSink {
            path: path.to_path_buf(),
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
        let _ = std::fs::remove_file(&self.path);
    }
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

/// Registers a client and starts its writer thread.
fn add_client(stream: UnixStream, shared: &SocketShared) {
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
            let kind = matches!(line, Line::Event(Event::Reconnected));
            s2.lock().unwrap().push((kind, text.to_string()));
        }));
        p.publish_line(&Line::Event(Event::Reconnected)).unwrap();
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
