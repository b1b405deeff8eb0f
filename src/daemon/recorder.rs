//! The raw-byte recording of a live run (`propid run --record FILE`, `[daemon] record`): every
//! byte received, for `propid replay`.
//!
//! - **The sampler never does file I/O.** It copies each read into one of [`CHUNKS`]
//!   preallocated chunks of [`CHUNK`] bytes and hands full (or [`HAND_OFF`]-old) chunks to the
//!   recorder thread, which opens, writes and rotates the files and hands the chunks back. No
//!   allocation per read, no wait: when every chunk is still queued (a stalled pipe reader, a
//!   slow disk), the bytes are dropped, counted (`record_bytes_dropped` in the stats line) and
//!   reported once as an `output_failed` warning (sink `record`); the run ends with exit 7.
//!   Heartbeats and STOP go on whatever the disk does. At the end of the run the recorder gets
//!   at most [`CLOSE_TIMEOUT`] to write what waits; what it has not written then is dropped.
//! - **Never overwrites, never follows a link into a file.** Each file is created with
//!   `create_new` (`O_EXCL`: an existing name, a symlink too, is never opened): when `rec.tsp`
//!   exists (the systemd unit restarts on the same path) the recording goes to the first free
//!   of `rec.1.tsp`, `rec.2.tsp`, ... ([`numbered`]); every file opened is announced as a
//!   `recording` event line with its path. Only the named path itself may be a character
//!   device or a FIFO (`/dev/null`, `>(gzip > r.gz)`): it is written to, opened non-blocking,
//!   never rotated; a FIFO without a reader is refused at start (it would block the open), a
//!   block device always.
//! - **Flushed within [`FLUSH_EVERY`]**: a chunk is handed over when full or [`HAND_OFF`] after
//!   its first byte (checked every turn of the sampler, at most 50 ms apart) and written at
//!   once, so a SIGKILL or a crash loses at most the last 100 ms.
//! - **Rotated at a size limit** (`[daemon] record_max_bytes`, `--record-max-bytes`): a read
//!   that would take the file past the limit starts the next free numbered file instead (files
//!   break between reads, at most 4 KiB apart; none is overwritten; a FIFO or anything else at
//!   a numbered name is skipped, never written to).
//! - **Write failures are reported, never fatal.** The first failure (a full disk, `/dev/full`)
//!   ends the recording, is published as an `output_failed` warning (sink `record`, the path,
//!   the OS error) and kept: the run goes on, nothing published is lost, and the run exits 7 at
//!   the end. `record_bytes_written` in the stats line counts the bytes the OS accepted (the
//!   `bytes` counter counts those received).

use crossbeam_channel::{bounded, unbounded, Receiver, Sender};
use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Longest time received bytes wait in memory before they are written.
pub const FLUSH_EVERY: Duration = Duration::from_millis(100);

/// A chunk is handed to the recorder thread this long after its first byte (or when full);
/// the sampler looks at least every 50 ms, so no byte waits longer than [`FLUSH_EVERY`].
pub const HAND_OFF: Duration = Duration::from_millis(50);

/// Bytes of one chunk.
pub const CHUNK: usize = 64 * 1024;

/// Chunks in circulation between the sampler and the recorder thread: at most
/// `CHUNKS × CHUNK` (2 MiB, ~1.7 s of a 31 k samples/s stream) wait for the disk.
pub const CHUNKS: usize = 32;

/// Longest wait at the end of a run for the recorder thread to write what waits.
pub const CLOSE_TIMEOUT: Duration = Duration::from_secs(1);

/// How often a recorder waiting for a pipe's reader looks whether it was given up.
const POLL_MS: i32 = 50;

/// Highest file number tried before giving up (`rec.N.tsp`).
const MAX_NUMBER: u32 = 1_000_000;

pub use propid_session::record_note::{RecordNote, DROPPED_MESSAGE};

/// One preallocated buffer of received bytes.
#[derive(Debug)]
struct Chunk {
    bytes: Vec<u8>,
    /// Start the next numbered file before writing these bytes.
    new_file: bool,
}

/// Counters the recorder thread keeps and the sampler reads.
#[derive(Debug, Default)]
struct Shared {
    /// Bytes the OS accepted, over every file.
    written: AtomicU64,
    /// Bytes handed over after the recording failed (not written, not dropped: the failure
    /// is the report).
    discarded: AtomicU64,
    /// The run is over and the recorder was given up: stop waiting for a pipe's reader.
    abandon: AtomicBool,
}

/// The recording as the sampler holds it: the chunk being filled, the queue to the recorder
/// thread, the counters.
#[derive(Debug)]
pub struct Recorder {
    /// Full chunks to the recorder thread (None once the run is over).
    full: Option<Sender<Chunk>>,
    /// Written chunks back from it.
    free: Receiver<Chunk>,
    notes: Receiver<RecordNote>,
    current: Option<Chunk>,
    /// When the current chunk got its first byte.
    since: Instant,
    max_bytes: Option<u64>,
    /// Bytes handed over (or in the current chunk) for the current file.
    file_bytes: u64,
    /// The next chunk starts a new file.
    rotate: bool,
    /// Bytes handed to the recorder thread.
    handed: u64,
    /// Bytes dropped because no chunk was free.
    dropped: u64,
    /// The [`RecordNote::Dropped`] note was sent.
    dropped_noted: bool,
    /// The current (or last) file, as the notes said.
    path: Arc<Path>,
    /// The first write failure (the recording stopped there).
    failed: Option<Arc<io::Error>>,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Recorder {
    /// Opens the first file (the first free of `base`, `base.1`, `base.2`, ..., numbers before
    /// the extension; or `base` itself when it is a character device or a FIFO with a reader)
    /// and starts the recorder thread; `max_bytes` rotates to the next free name.
    pub fn create(base: &Path, max_bytes: Option<u64>) -> io::Result<Recorder> {
        let (file, path, special) = open_first(base)?;
        // a device or a FIFO is not rotated (its numbered names are not files of ours)
        let max_bytes = max_bytes.filter(|_| !special);
        let path: Arc<Path> = Arc::from(path);
        let (full_tx, full_rx) = bounded(CHUNKS);
        let (free_tx, free_rx) = bounded(CHUNKS);
        for _ in 0..CHUNKS {
            let chunk = Chunk {
                bytes: Vec::with_capacity(CHUNK),
                new_file: false,
            };
            free_tx
                .try_send(chunk)
                .expect("the free queue holds every chunk");
        }
        let (notes_tx, notes_rx) = unbounded();
        let _ = notes_tx.send(RecordNote::File { path: path.clone() });
        let shared = Arc::new(Shared::default());
        let writer = Writer {
            base: base.to_path_buf(),
            file: Some(file),
            path: path.clone(),
            shared: shared.clone(),
            notes: notes_tx,
        };
        let thread = std::thread::Builder::new()
            .name("propid-recorder".into())
            .spawn(move || writer.run(full_rx, free_tx))?;
        Ok(Recorder {
            full: Some(full_tx),
            free: free_rx,
            notes: notes_rx,
            current: None,
            since: Instant::now(),
            max_bytes,
            file_bytes: 0,
            rotate: false,
            handed: 0,
            dropped: 0,
            dropped_noted: false,
            path,
            failed: None,
            shared,
            thread: Some(thread),
        })
    }

    /// Appends received bytes (copied into a chunk: no file I/O, no allocation, no wait);
    /// bytes no chunk is free for are dropped and counted.
    pub fn write(&mut self, bytes: &[u8]) {
        if self.failed.is_some() || self.full.is_none() || bytes.is_empty() {
            return;
        }
        if let Some(max) = self.max_bytes {
            if self.file_bytes > 0 && self.file_bytes + bytes.len() as u64 > max {
                self.hand_off();
                self.rotate = true;
                self.file_bytes = 0;
            }
        }
        let mut rest = bytes;
        while !rest.is_empty() {
            if self.current.is_none() {
                let Ok(mut chunk) = self.free.try_recv() else {
                    self.dropped += rest.len() as u64;
                    break;
                };
                chunk.new_file = std::mem::take(&mut self.rotate);
                self.current = Some(chunk);
                self.since = Instant::now();
            }
            let Some(chunk) = self.current.as_mut() else {
                break;
            };
            let n = rest.len().min(CHUNK - chunk.bytes.len());
            chunk.bytes.extend_from_slice(&rest[..n]);
            self.file_bytes += n as u64;
            rest = &rest[n..];
            if chunk.bytes.len() == CHUNK {
                self.hand_off();
            }
        }
    }

    /// Hands the current chunk to the recorder thread (never waits: the queue holds every
    /// chunk there is).
    fn hand_off(&mut self) {
        let Some(chunk) = self.current.take() else {
            return;
        };
        let n = chunk.bytes.len() as u64;
        match self.full.as_ref().map(|tx| tx.try_send(chunk)) {
            Some(Ok(())) => self.handed += n,
            // the recorder thread is gone (a bug): the bytes are lost, counted
            _ => self.dropped += n,
        }
    }

    /// Called every turn of the sampler: hands over a chunk that waited [`HAND_OFF`], and
    /// gives `note` what the recording reports (files opened, a failure, bytes dropped).
    pub fn tick(&mut self, note: &mut dyn FnMut(RecordNote)) {
        if self.current.is_some() && self.since.elapsed() >= HAND_OFF {
            self.hand_off();
        }
        self.take_notes(note);
    }

    fn take_notes(&mut self, note: &mut dyn FnMut(RecordNote)) {
        while let Ok(n) = self.notes.try_recv() {
            match &n {
                RecordNote::File { path } => self.path = path.clone(),
                RecordNote::Failed { error, .. } => self.failed = Some(error.clone()),
                RecordNote::Dropped { .. } => {}
            }
            note(n);
        }
        if self.dropped > 0 && !self.dropped_noted && self.failed.is_none() {
            self.dropped_noted = true;
            note(RecordNote::Dropped {
                path: self.path.clone(),
            });
        }
    }

    /// The end of the run: hands over what waits and gives the recorder thread at most
    /// `timeout` to write it (what it has not written then is dropped and counted); then the
    /// last notes.
    pub fn finish(&mut self, timeout: Duration, note: &mut dyn FnMut(RecordNote)) {
        self.hand_off();
        self.full = None; // the recorder thread ends once the queue is empty
        if let Some(t) = self.thread.take() {
            let end = Instant::now() + timeout;
            while !t.is_finished() && Instant::now() < end {
                std::thread::sleep(Duration::from_millis(2));
            }
            if !t.is_finished() {
                // a pipe whose reader stopped reading: stop waiting for it (a write blocked in
                // the kernel, on a regular file, is left to the end of the process)
                self.shared.abandon.store(true, Ordering::SeqCst);
                let end = Instant::now() + Duration::from_millis(2 * POLL_MS as u64);
                while !t.is_finished() && Instant::now() < end {
                    std::thread::sleep(Duration::from_millis(2));
                }
            }
            if t.is_finished() {
                let _ = t.join();
            }
        }
        let settled = self.shared.written.load(Ordering::SeqCst)
            + self.shared.discarded.load(Ordering::SeqCst);
        self.dropped += self.handed.saturating_sub(settled);
        self.handed = settled;
        self.take_notes(note);
    }

    /// Bytes the OS accepted, over every file.
    pub fn bytes_written(&self) -> u64 {
        self.shared.written.load(Ordering::SeqCst)
    }

    /// Bytes received that the recording dropped because it fell behind.
    pub fn bytes_dropped(&self) -> u64 {
        self.dropped
    }

    /// The current (or last) file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The write failure that ended the recording, if one did.
    pub fn failure(&self) -> Option<(&Path, &io::Error)> {
        self.failed.as_deref().map(|e| (&*self.path, e))
    }

    /// The failure (or the bytes dropped) as the error the run ends with (exit 7), if there
    /// was one.
    pub fn error(&self) -> Option<super::DaemonError> {
        let sink = format!("recording {}", self.path.display());
        if let Some((_, e)) = self.failure() {
            let source = match e.raw_os_error() {
                Some(code) => io::Error::from_raw_os_error(code),
                None => io::Error::new(e.kind(), e.to_string()),
            };
            return Some(super::DaemonError::Output { sink, source });
        }
        (self.dropped > 0).then(|| super::DaemonError::Output {
            sink,
            source: io::Error::new(
                io::ErrorKind::WouldBlock,
                format!(
                    "the recording fell behind: {} received bytes dropped",
                    self.dropped
                ),
            ),
        })
    }
}

/// The recorder thread: opens, writes and rotates the files.
struct Writer {
    base: PathBuf,
    file: Option<File>,
    path: Arc<Path>,
    shared: Arc<Shared>,
    notes: Sender<RecordNote>,
}

impl Writer {
    /// Writes every chunk handed over, in order, and hands it back; ends when the sampler
    /// drops its end of the queue (or gives the recorder up).
    fn run(mut self, full: Receiver<Chunk>, free: Sender<Chunk>) {
        while let Ok(mut chunk) = full.recv() {
            if self.shared.abandon.load(Ordering::SeqCst) {
                return;
            }
            if chunk.new_file {
                self.rotate();
            }
            if !self.write_all(&chunk.bytes) {
                return; // given up
            }
            chunk.bytes.clear();
            chunk.new_file = false;
            let _ = free.try_send(chunk);
        }
    }

    /// Writes `bytes` to the current file (waiting for a pipe's reader, unless given up);
    /// false when given up. The first error ends the recording.
    fn write_all(&mut self, mut bytes: &[u8]) -> bool {
        let Some(f) = self.file.as_mut() else {
            self.shared
                .discarded
                .fetch_add(bytes.len() as u64, Ordering::SeqCst);
            return true;
        };
        while !bytes.is_empty() {
            match f.write(bytes) {
                Ok(0) => return self.fail(io::ErrorKind::WriteZero.into(), bytes.len()),
                Ok(n) => {
                    self.shared.written.fetch_add(n as u64, Ordering::SeqCst);
                    bytes = &bytes[n..];
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    if self.shared.abandon.load(Ordering::SeqCst) {
                        return false;
                    }
                    wait_writable(f);
                }
                Err(e) => return self.fail(e, bytes.len()),
            }
        }
        true
    }

    /// The next free numbered file after the current one.
    fn rotate(&mut self) {
        if self.file.is_none() {
            return;
        }
        self.file = None;
        let after = number_of(&self.base, &self.path).map_or(1, |n| n + 1);
        match create_free(&self.base, after) {
            Ok((file, path)) => {
                self.path = Arc::from(path);
                self.file = Some(file);
                let _ = self.notes.send(RecordNote::File {
                    path: self.path.clone(),
                });
            }
            Err(e) => {
                self.fail(e, 0);
            }
        }
    }

    /// Ends the recording on `e` (`left` bytes not written); true (not given up).
    fn fail(&mut self, e: io::Error, left: usize) -> bool {
        self.file = None;
        self.shared
            .discarded
            .fetch_add(left as u64, Ordering::SeqCst);
        let _ = self.notes.send(RecordNote::Failed {
            path: self.path.clone(),
            error: Arc::new(e),
        });
        true
    }
}

/// Waits until `f` (a non-blocking FIFO or device) takes bytes, at most [`POLL_MS`].
fn wait_writable(f: &File) {
    use std::os::fd::AsRawFd;
    let mut fds = libc::pollfd {
        fd: f.as_raw_fd(),
        events: libc::POLLOUT,
        revents: 0,
    };
    // SAFETY: one valid pollfd, its count 1; the descriptor stays open during the call.
    unsafe { libc::poll(&mut fds, 1, POLL_MS) };
}

/// `base` with number `n` before its extension: `rec.tsp` → `rec.3.tsp`, `rec` → `rec.3`;
/// `n = 0` is `base` itself.
pub fn numbered(base: &Path, n: u32) -> PathBuf {
    if n == 0 {
        return base.to_path_buf();
    }
    let stem = base.file_stem().unwrap_or_default().to_string_lossy();
    let name = match base.extension() {
        Some(ext) => format!("{stem}.{n}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{n}"),
    };
    base.with_file_name(name)
}

/// The number of `path` among the names of `base` (0 for `base`).
fn number_of(base: &Path, path: &Path) -> Option<u32> {
    if path == base {
        return Some(0);
    }
    (1..MAX_NUMBER).find(|&n| numbered(base, n) == path)
}

/// The first file: `base` itself when it is a character device or a FIFO (followed through
/// links: `>(...)` is `/dev/fd/N`), opened non-blocking; else the first free name. True when
/// special.
fn open_first(base: &Path) -> io::Result<(File, PathBuf, bool)> {
    let Ok(meta) = std::fs::metadata(base) else {
        let (f, p) = create_free(base, 0)?;
        return Ok((f, p, false));
    };
    let t = meta.file_type();
    if t.is_block_device() || t.is_socket() {
        let what = if t.is_socket() {
            "a socket"
        } else {
            "a block device"
        };
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{what}: record to a regular file"),
        ));
    }
    if !(t.is_char_device() || t.is_fifo()) {
        let (f, p) = create_free(base, 0)?;
        return Ok((f, p, false));
    }
    match OpenOptions::new()
        .write(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(base)
    {
        Ok(f) => Ok((f, base.to_path_buf(), true)),
        Err(e) if e.raw_os_error() == Some(libc::ENXIO) && t.is_fifo() => Err(io::Error::new(
            io::ErrorKind::NotConnected,
            "a FIFO with no reader: start its reader first, or record to a regular file",
        )),
        Err(e) => Err(e),
    }
}

/// Creates the first name of `base` numbered `from` or higher that does not exist yet
/// (`O_EXCL`: never an existing file, FIFO or link).
fn create_free(base: &Path, from: u32) -> io::Result<(File, PathBuf)> {
    for n in from..MAX_NUMBER {
        let path = numbered(base, n);
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(f) => return Ok((f, path)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::new(
        io::ErrorKind::AlreadyExists,
        format!("{} and {MAX_NUMBER} numbered names exist", base.display()),
    ))
}

#[cfg(test)]
mod tests;
