//! Where the daemon's bytes come from: the [`Source`] trait and its implementations.
//!
//! # Contract of [`Source::read`]
//! - `Ok(n)` with `n > 0`: `n` bytes were placed at the front of the buffer.
//! - `Ok(0)`: **no data yet** (the read timed out). It never means end of file.
//! - `Err(SourceError::Disconnected)`: the link is gone (unplug: `BrokenPipe`, `EIO`, EOF on a
//!   port). The caller may [`Source::reconnect`].
//! - `Err(SourceError::Finished)`: the source has no more data and never will (the end of a
//!   recording). Serial ports never return it.
//!
//! Reads block for at most the source's timeout, so a sampler loop built on them never hangs and
//! can send heartbeats between reads. Implementations: [`SerialSource`] (a serial port or the
//! simulated stand's pseudo-terminal, opened by path with `serialport`, timeout always set),
//! [`RecordingSource`] (a raw-byte recording, read and delivered in chunks of a chosen size) and
//! [`ScriptedSource`] (an in-memory fake that stalls, delivers partially and fails on cue).

use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Why a source cannot deliver.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// The link is gone; reconnecting may help.
    #[error("disconnected from {what}: {source}")]
    Disconnected {
        /// The source.
        what: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// Opening the device failed.
    #[error("cannot open {what}: {source}")]
    Open {
        /// The source.
        what: String,
        /// What the OS (or the serial port library) said.
        source: std::io::Error,
    },
    /// The source is exhausted (end of a recording).
    #[error("end of {what}")]
    Finished {
        /// The source.
        what: String,
    },
}

/// A byte stream from the stand (or a recording of it). See the module docs for the contract.
pub trait Source: Send {
    /// Reads available bytes; `Ok(0)` = nothing yet (timeout), never EOF.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, SourceError>;
    /// Writes all of `bytes` (a command frame) or fails with `Disconnected`.
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), SourceError>;
    /// Reopens the link after a disconnection (one attempt; the caller backs off).
    fn reconnect(&mut self) -> Result<(), SourceError>;
    /// Closes the link (a stalled one, before [`Source::reconnect`] reopens it); reads and
    /// writes then fail with `Disconnected`. Nothing to close by default.
    fn close(&mut self) {}
    /// Whether commands reach a device (false for a recording).
    fn is_live(&self) -> bool;
    /// A short description for messages (`/dev/ttyACM0`, `recording run.tsp`).
    fn describe(&self) -> String;
    /// The device node the link's path is now (a symlink resolved), when it has one.
    fn device_node(&self) -> Option<String> {
        None
    }
}

/// The error of a link used while it is closed.
fn not_connected() -> std::io::Error {
    std::io::Error::new(ErrorKind::NotConnected, "not connected")
}

/// Whether an I/O error from a port read only means "no data yet" (a timeout); the rest
/// disconnects.
fn no_data(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
    )
}

/// A serial port (or pty slave) opened by path. Reconnects by reopening the same path, which
/// resolves a symlink again: a udev link (`/dev/propid-stand`, `/dev/serial/by-id/...`) that
/// points at a new device node after re-enumeration (`ttyACM0` gone, `ttyACM1` back) is
/// followed.
pub struct SerialSource {
    path: String,
    baud: u32,
    timeout: Duration,
    port: Option<Box<dyn serialport::SerialPort>>,
}

impl SerialSource {
    /// Opens `path` at `baud` with a read timeout (never zero: zero would spin).
    pub fn open(path: &str, baud: u32, timeout: Duration) -> Result<SerialSource, SourceError> {
        let mut s = SerialSource {
            path: path.to_string(),
            baud,
            timeout: timeout.max(Duration::from_millis(1)),
            port: None,
        };
        s.reconnect()?;
        Ok(s)
    }

    /// The device path.
    pub fn path(&self) -> &str {
        &self.path
    }

    fn disconnected(&mut self, source: std::io::Error) -> SourceError {
        self.port = None;
        SourceError::Disconnected {
            what: self.path.clone(),
            source,
        }
    }
}

impl Source for SerialSource {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, SourceError> {
        let Some(port) = self.port.as_mut() else {
            return Err(self.disconnected(not_connected()));
        };
        match port.read(buf) {
            // EOF on a port is an unplug, never "no data".
            Ok(0) if !buf.is_empty() => {
                let eof = std::io::Error::new(ErrorKind::UnexpectedEof, "end of file");
                Err(self.disconnected(eof))
            }
            Ok(n) => Ok(n),
            Err(e) if no_data(&e) => Ok(0),
            Err(e) => Err(self.disconnected(e)),
        }
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), SourceError> {
        let Some(port) = self.port.as_mut() else {
            return Err(self.disconnected(not_connected()));
        };
        match port.write_all(bytes) {
            Ok(()) => Ok(()),
            Err(e) => Err(self.disconnected(e)),
        }
    }

    fn close(&mut self) {
        self.port = None;
    }

    fn reconnect(&mut self) -> Result<(), SourceError> {
        self.port = None;
        let port = serialport::new(&self.path, self.baud)
            .timeout(self.timeout)
            .open()
            .map_err(|e| SourceError::Open {
                what: self.path.clone(),
                source: e.into(),
            })?;
        self.port = Some(port);
        Ok(())
    }

    fn is_live(&self) -> bool {
        true
    }

    fn describe(&self) -> String {
        self.path.clone()
    }

    fn device_node(&self) -> Option<String> {
        std::fs::canonicalize(&self.path)
            .ok()
            .map(|p| p.display().to_string())
    }
}

/// A raw-byte recording, delivered in chunks of at most `chunk` bytes (1 = byte at a time):
/// read from its file as it is delivered (memory: one chunk, whatever the file's size), or
/// from bytes already in memory.
pub struct RecordingSource {
    path: PathBuf,
    reader: Box<dyn Read + Send>,
    pos: u64,
    total: u64,
    chunk: usize,
}

impl RecordingSource {
    /// Opens the recording at `path`, to be read as it is delivered.
    pub fn open(path: &Path, chunk: usize) -> Result<RecordingSource, SourceError> {
        let open = |source| SourceError::Open {
            what: path.display().to_string(),
            source,
        };
        let file = std::fs::File::open(path).map_err(open)?;
        let total = file.metadata().map_err(open)?.len();
        Ok(RecordingSource {
            path: path.to_path_buf(),
            reader: Box::new(file),
            pos: 0,
            total,
            chunk: chunk.max(1),
        })
    }

    /// A recording already in memory.
    pub fn from_bytes(path: &Path, bytes: Vec<u8>, chunk: usize) -> RecordingSource {
        RecordingSource {
            path: path.to_path_buf(),
            total: bytes.len() as u64,
            reader: Box::new(std::io::Cursor::new(bytes)),
            pos: 0,
            chunk: chunk.max(1),
        }
    }

    /// Bytes delivered so far and the total (the file's size when it was opened), for
    /// progress.
    pub fn progress(&self) -> (u64, u64) {
        (self.pos, self.total)
    }
}

impl Source for RecordingSource {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, SourceError> {
        let n = self.chunk.min(buf.len());
        loop {
            match self.reader.read(&mut buf[..n]) {
                Ok(0) if n > 0 => {
                    return Err(SourceError::Finished {
                        what: self.describe(),
                    })
                }
                Ok(got) => {
                    self.pos += got as u64;
                    return Ok(got);
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                // a file that cannot be read on: the link is gone, and `reconnect` ends it
                Err(source) => {
                    return Err(SourceError::Disconnected {
                        what: self.describe(),
                        source,
                    })
                }
            }
        }
    }

    fn write_all(&mut self, _bytes: &[u8]) -> Result<(), SourceError> {
        Ok(()) // a recording has no device to command
    }

    fn reconnect(&mut self) -> Result<(), SourceError> {
        Err(SourceError::Finished {
            what: self.describe(),
        })
    }

    fn is_live(&self) -> bool {
        false
    }

    fn describe(&self) -> String {
        format!("recording {}", self.path.display())
    }
}

/// One step of a [`ScriptedSource`].
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// Deliver these bytes (possibly over several reads if the buffer is small).
    Data(Vec<u8>),
    /// One read that returns `Ok(0)` (a timeout).
    Stall,
    /// One read that fails with `Disconnected`.
    Hangup,
}

/// An in-memory fake source for tests: plays a script of data, stalls and hang-ups, records
/// what was written, and can refuse a number of reconnect attempts.
#[derive(Debug, Default)]
pub struct ScriptedSource {
    steps: VecDeque<Step>,
    /// Everything written to the source.
    pub written: Vec<u8>,
    /// Reconnect attempts still to refuse.
    pub refuse_reconnects: u32,
    /// Successful reconnects.
    pub reconnects: u32,
    connected: bool,
}

impl ScriptedSource {
    /// A fake that plays `steps` and then reports `Finished`.
    pub fn new(steps: Vec<Step>) -> ScriptedSource {
        ScriptedSource {
            steps: steps.into(),
            connected: true,
            ..Default::default()
        }
    }
}

impl Source for ScriptedSource {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, SourceError> {
        if !self.connected {
            return Err(SourceError::Disconnected {
                what: "script".into(),
                source: not_connected(),
            });
        }
        match self.steps.pop_front() {
            None => Err(SourceError::Finished {
                what: "script".into(),
            }),
            Some(Step::Stall) => Ok(0),
            Some(Step::Hangup) => {
                self.connected = false;
                Err(SourceError::Disconnected {
                    what: "script".into(),
                    source: std::io::Error::other("hang-up"),
                })
            }
            Some(Step::Data(mut d)) => {
                let n = d.len().min(buf.len());
                buf[..n].copy_from_slice(&d[..n]);
                if n < d.len() {
                    self.steps.push_front(Step::Data(d.split_off(n)));
                }
                Ok(n)
            }
        }
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), SourceError> {
        if !self.connected {
            return Err(SourceError::Disconnected {
                what: "script".into(),
                source: not_connected(),
            });
        }
        self.written.extend_from_slice(bytes);
        Ok(())
    }

    fn close(&mut self) {
        self.connected = false;
    }

    fn reconnect(&mut self) -> Result<(), SourceError> {
        if self.refuse_reconnects > 0 {
            self.refuse_reconnects -= 1;
            return Err(SourceError::Open {
                what: "script".into(),
                source: std::io::Error::new(ErrorKind::NotFound, "no such device"),
            });
        }
        self.connected = true;
        self.reconnects += 1;
        Ok(())
    }

    fn is_live(&self) -> bool {
        true
    }

    fn describe(&self) -> String {
        "script".into()
    }
}

/// Exponential reconnect backoff: `initial`, `2·initial`, … capped at `max`; reset on success.
#[derive(Debug, Clone)]
pub struct Backoff {
    initial: Duration,
    max: Duration,
    next: Duration,
}

impl Backoff {
    /// A backoff starting at `initial`, never above `max`.
    pub fn new(initial: Duration, max: Duration) -> Backoff {
        Backoff {
            initial,
            max: max.max(initial),
            next: initial,
        }
    }

    /// The delay before the next attempt; doubles the one after.
    pub fn next_delay(&mut self) -> Duration {
        let d = self.next;
        self.next = (self.next * 2).min(self.max);
        d
    }

    /// Back to the initial delay (after a successful reconnect).
    pub fn reset(&mut self) {
        self.next = self.initial;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serialport::{SerialPort, TTYPort};

    #[test]
    fn backoff_doubles_up_to_max_and_resets() {
        let ms = Duration::from_millis;
        let mut b = Backoff::new(ms(100), ms(350));
        let got: Vec<_> = (0..4).map(|_| b.next_delay()).collect();
        assert_eq!(got, vec![ms(100), ms(200), ms(350), ms(350)]);
        b.reset();
        assert_eq!(b.next_delay(), ms(100));
    }

    #[test]
    fn recording_delivers_in_chunks_then_finishes() {
        let mut r = RecordingSource::from_bytes(Path::new("x"), vec![1, 2, 3, 4, 5], 2);
        let mut buf = [0u8; 8];
        assert_eq!(r.read(&mut buf).unwrap(), 2);
        assert_eq!(r.read(&mut buf).unwrap(), 2);
        assert_eq!(r.read(&mut buf).unwrap(), 1);
        assert_eq!(buf[0], 5);
        assert!(matches!(
            r.read(&mut buf),
            Err(SourceError::Finished { .. })
        ));
        assert!(!r.is_live());
    }

    #[test]
    fn a_recording_file_is_read_as_it_is_delivered() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("r.tsp");
        let bytes: Vec<u8> = (0..=255u8).cycle().take(1000).collect();
        std::fs::write(&f, &bytes).unwrap();
        let mut r = RecordingSource::open(&f, 300).unwrap();
        assert_eq!(r.progress(), (0, 1000));
        let (mut got, mut buf) = (Vec::new(), [0u8; 512]);
        loop {
            match r.read(&mut buf) {
                Ok(n) => {
                    assert!((1..=300).contains(&n), "{n}");
                    got.extend_from_slice(&buf[..n]);
                }
                Err(SourceError::Finished { .. }) => break,
                Err(e) => panic!("{e}"),
            }
        }
        assert_eq!(got, bytes);
        assert_eq!(r.progress(), (1000, 1000));
    }

    #[test]
    fn scripted_source_plays_stalls_partial_reads_and_hangups() {
        let mut s = ScriptedSource::new(vec![
            Step::Data(vec![1, 2, 3]),
            Step::Stall,
            Step::Hangup,
            Step::Data(vec![9]),
        ]);
        s.refuse_reconnects = 1;
        let mut buf = [0u8; 2];
        assert_eq!(s.read(&mut buf).unwrap(), 2);
        assert_eq!(s.read(&mut buf).unwrap(), 1);
        assert_eq!(s.read(&mut buf).unwrap(), 0);
        assert!(matches!(
            s.read(&mut buf),
            Err(SourceError::Disconnected { .. })
        ));
        assert!(s.write_all(&[1]).is_err());
        assert!(s.reconnect().is_err());
        s.reconnect().unwrap();
        assert_eq!(s.read(&mut buf).unwrap(), 1);
        assert!(matches!(
            s.read(&mut buf),
            Err(SourceError::Finished { .. })
        ));
    }

    #[test]
    fn serial_source_over_pty_times_out_reads_and_detects_hangup() {
        let (mut master, slave) = TTYPort::pair().unwrap();
        let path = slave.name().unwrap();
        let mut src = SerialSource::open(&path, 921_600, Duration::from_millis(5)).unwrap();
        let mut buf = [0u8; 16];
        assert_eq!(src.read(&mut buf).unwrap(), 0, "no data = Ok(0)");
        master.write_all(b"abc").unwrap();
        let mut got = Vec::new();
        for _ in 0..100 {
            let n = src.read(&mut buf).unwrap();
            got.extend_from_slice(&buf[..n]);
            if got.len() == 3 {
                break;
            }
        }
        assert_eq!(got, b"abc");
        src.write_all(b"cmd").unwrap();
        let mut back = [0u8; 3];
        master.read_exact(&mut back).unwrap();
        assert_eq!(&back, b"cmd");
        drop(master);
        drop(slave);
        let mut saw = false;
        for _ in 0..100 {
            match src.read(&mut buf) {
                Ok(_) => continue,
                Err(SourceError::Disconnected { .. }) => {
                    saw = true;
                    break;
                }
                Err(e) => panic!("unexpected {e}"),
            }
        }
        assert!(saw, "closing the master must disconnect the source");
    }
}
