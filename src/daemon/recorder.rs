//! The raw-byte recording of a live run (`propid run --record FILE`, `[daemon] record`): every
//! byte received, for `propid replay`.
//!
//! - **Never overwrites.** Each file is created with `create_new`: when `rec.tsp` exists (the
//!   systemd unit restarts on the same path) the recording goes to the first free of
//!   `rec.1.tsp`, `rec.2.tsp`, ... ([`numbered`]); every file opened is announced as a
//!   `recording` event line with its path.
//! - **Flushed at least every [`FLUSH_EVERY`]** (and whenever [`BUFFER`] bytes wait), so a
//!   SIGKILL or a crash loses at most the last 100 ms.
//! - **Rotated at a size limit** (`[daemon] record_max_bytes`, `--record-max-bytes`): a read
//!   that would take the file past the limit starts the next numbered file instead (files break
//!   between reads, at most 4 KiB apart; none is overwritten).
//! - **Write failures are reported, never fatal.** The first failure (a full disk, `/dev/full`)
//!   ends the recording, is published as an `output_failed` warning (sink `record`, the path,
//!   the OS error) and kept: the run goes on, nothing published is lost, and the run exits 7 at
//!   the end. `record_bytes_written` in the stats line counts the bytes the OS accepted (the
//!   `bytes` counter counts those received).

use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Longest time received bytes wait in memory before they are written.
pub const FLUSH_EVERY: Duration = Duration::from_millis(100);

/// Bytes kept in memory at most before they are written.
pub const BUFFER: usize = 64 * 1024;

/// Highest file number tried before giving up (`rec.N.tsp`).
const MAX_NUMBER: u32 = 1_000_000;

/// What the recording reports to the worker, published as a line.
#[derive(Debug, Clone)]
pub enum RecordNote {
    /// A file was opened: a `recording` event line.
    File {
        /// The file's path.
        path: Arc<Path>,
    },
    /// Writing failed; the recording is over: an `output_failed` warning line.
    Failed {
        /// The file's path.
        path: Arc<Path>,
        /// The OS error.
        error: Arc<io::Error>,
    },
}

/// Notes compare by path and, for a failure, by the error's kind and text.
impl PartialEq for RecordNote {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (RecordNote::File { path: a }, RecordNote::File { path: b }) => a == b,
            (
                RecordNote::Failed { path: a, error: x },
                RecordNote::Failed { path: b, error: y },
            ) => a == b && x.kind() == y.kind() && x.to_string() == y.to_string(),
            _ => false,
        }
    }
}

/// The recording: a buffer, the current file, the counters.
#[derive(Debug)]
pub struct Recorder {
    base: PathBuf,
    max_bytes: Option<u64>,
    file: Option<File>,
    path: Arc<Path>,
    /// Bytes in the current file.
    file_bytes: u64,
    /// Bytes the OS accepted, over every file.
    written: u64,
    buf: Vec<u8>,
    last_flush: Instant,
    /// The first write failure (the recording stopped there).
    failed: Option<Arc<io::Error>>,
    notes: Vec<RecordNote>,
}

impl Recorder {
    /// Creates the first free file of `base`, `base.1`, `base.2`, ... (numbers before the
    /// extension); `max_bytes` rotates to the next free one.
    pub fn create(base: &Path, max_bytes: Option<u64>) -> io::Result<Recorder> {
        let (file, path) = create_free(base, 0)?;
        // a device or a FIFO is not rotated (its numbered names are not files of ours)
        let max_bytes = max_bytes.filter(|_| !is_special(&path));
        let path: Arc<Path> = Arc::from(path);
        Ok(Recorder {
            base: base.to_path_buf(),
            max_bytes,
            file: Some(file),
            path: path.clone(),
            file_bytes: 0,
            written: 0,
            buf: Vec::with_capacity(BUFFER),
            last_flush: Instant::now(),
            failed: None,
            notes: vec![RecordNote::File { path }],
        })
    }

    /// Appends received bytes (written within [`FLUSH_EVERY`], or at once past [`BUFFER`]).
    pub fn write(&mut self, bytes: &[u8]) {
        if self.file.is_none() {
            return;
        }
        if let Some(max) = self.max_bytes {
            let pending = self.file_bytes + self.buf.len() as u64;
            if pending > 0 && pending + bytes.len() as u64 > max {
                self.flush();
                self.rotate();
                if self.file.is_none() {
                    return;
                }
            }
        }
        self.buf.extend_from_slice(bytes);
        if self.buf.len() >= BUFFER {
            self.flush();
        }
    }

    /// Writes what waits when it has waited [`FLUSH_EVERY`] (called every turn of the loop).
    pub fn tick(&mut self) {
        if !self.buf.is_empty() && self.last_flush.elapsed() >= FLUSH_EVERY {
            self.flush();
        }
    }

    /// Writes everything that waits (counting what the OS accepted); the first error ends the
    /// recording.
    pub fn flush(&mut self) {
        self.last_flush = Instant::now();
        let Some(f) = self.file.as_mut() else {
            self.buf.clear();
            return;
        };
        let mut done = 0;
        let mut error = None;
        while done < self.buf.len() {
            match f.write(&self.buf[done..]) {
                Ok(0) => {
                    error = Some(io::Error::from(io::ErrorKind::WriteZero));
                    break;
                }
                Ok(n) => done += n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => {
                    error = Some(e);
                    break;
                }
            }
        }
        self.file_bytes += done as u64;
        self.written += done as u64;
        self.buf.clear();
        if let Some(e) = error {
            self.fail(e);
        }
    }

    /// The next numbered file after the current one.
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
                self.file_bytes = 0;
                self.notes.push(RecordNote::File {
                    path: self.path.clone(),
                });
            }
            Err(e) => self.fail(e),
        }
    }

    fn fail(&mut self, e: io::Error) {
        self.file = None;
        let error = Arc::new(e);
        self.failed = Some(error.clone());
        self.notes.push(RecordNote::Failed {
            path: self.path.clone(),
            error,
        });
    }

    /// What happened since the last call (files opened, the failure), to publish.
    pub fn take_notes(&mut self) -> std::vec::Drain<'_, RecordNote> {
        self.notes.drain(..)
    }

    /// Bytes the OS accepted, over every file.
    pub fn bytes_written(&self) -> u64 {
        self.written
    }

    /// The current (or last) file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The write failure that ended the recording, if one did.
    pub fn failure(&self) -> Option<(&Path, &io::Error)> {
        self.failed.as_deref().map(|e| (&*self.path, e))
    }

    /// The failure as the error the run ends with (exit 7), if there was one.
    pub fn error(&self) -> Option<super::DaemonError> {
        let (path, e) = self.failure()?;
        let source = match e.raw_os_error() {
            Some(code) => io::Error::from_raw_os_error(code),
            None => io::Error::new(e.kind(), e.to_string()),
        };
        Some(super::DaemonError::Output {
            sink: format!("recording {}", path.display()),
            source,
        })
    }
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

/// Creates the first name of `base` numbered `from` or higher that does not exist yet.
fn create_free(base: &Path, from: u32) -> io::Result<(File, PathBuf)> {
    for n in from..MAX_NUMBER {
        let path = numbered(base, n);
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(f) => return Ok((f, path)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {
                // a device (/dev/full, /dev/null) or a FIFO is written to, not numbered
                if is_special(&path) {
                    let f = OpenOptions::new().write(true).open(&path)?;
                    return Ok((f, path));
                }
            }
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::new(
        io::ErrorKind::AlreadyExists,
        format!("{} and {MAX_NUMBER} numbered names exist", base.display()),
    ))
}

/// A character device or a FIFO: not a file a recording could overwrite.
fn is_special(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::metadata(path).is_ok_and(|m| {
        let t = m.file_type();
        t.is_char_device() || t.is_fifo() || t.is_block_device()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_go_before_the_extension() {
        let p = Path::new("/x/rec.tsp");
        assert_eq!(numbered(p, 0), Path::new("/x/rec.tsp"));
        assert_eq!(numbered(p, 1), Path::new("/x/rec.1.tsp"));
        assert_eq!(numbered(Path::new("/x/rec"), 2), Path::new("/x/rec.2"));
        assert_eq!(number_of(p, Path::new("/x/rec.7.tsp")), Some(7));
    }

    #[test]
    fn an_existing_record_is_never_overwritten() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().join("rec.tsp");
        std::fs::write(&base, b"old").unwrap();
        let mut r = Recorder::create(&base, None).unwrap();
        assert_eq!(r.path(), dir.path().join("rec.1.tsp"));
        r.write(b"new");
        r.flush();
        assert_eq!(std::fs::read(&base).unwrap(), b"old");
        assert_eq!(std::fs::read(dir.path().join("rec.1.tsp")).unwrap(), b"new");
        assert_eq!(r.bytes_written(), 3);
        let notes: Vec<_> = r.take_notes().collect();
        assert!(matches!(&notes[..], [RecordNote::File { path }] if path.ends_with("rec.1.tsp")));
    }

    #[test]
    fn rotation_numbers_every_file_and_loses_no_byte() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().join("r.tsp");
        std::fs::write(dir.path().join("r.2.tsp"), b"keep").unwrap();
        let mut r = Recorder::create(&base, Some(10)).unwrap();
        for k in 0..7u8 {
            r.write(&[k; 4]);
        }
        r.flush();
        // 4 bytes per read, at most 10 per file: two reads per file
        let sizes: Vec<_> = ["r.tsp", "r.1.tsp", "r.2.tsp", "r.3.tsp", "r.4.tsp"]
            .iter()
            .map(|n| std::fs::read(dir.path().join(n)).unwrap().len())
            .collect();
        assert_eq!(sizes, [8, 8, 4, 8, 4]);
        assert_eq!(std::fs::read(dir.path().join("r.2.tsp")).unwrap(), b"keep");
        assert_eq!(r.bytes_written(), 28);
        assert_eq!(r.take_notes().count(), 4);
    }

    #[test]
    fn a_full_disk_is_reported_once_and_counted() {
        let mut r = Recorder::create(Path::new("/dev/full"), None).unwrap();
        r.write(&[1; 100]);
        r.flush();
        r.write(&[1; 100]);
        r.flush();
        assert_eq!(r.bytes_written(), 0);
        let (path, e) = r.failure().unwrap();
        assert_eq!(path, Path::new("/dev/full"));
        assert_eq!(e.raw_os_error(), Some(28));
        let notes: Vec<_> = r.take_notes().collect();
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(matches!(notes[1], RecordNote::Failed { .. }));
    }

    #[test]
    fn bytes_wait_at_most_the_flush_period() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().join("r.tsp");
        let mut r = Recorder::create(&base, None).unwrap();
        r.write(b"abc");
        assert_eq!(std::fs::read(&base).unwrap().len(), 0);
        std::thread::sleep(FLUSH_EVERY);
        r.tick();
        assert_eq!(std::fs::read(&base).unwrap(), b"abc");
    }
}
