//! `propid replay FILE [--config F]`: a recording through the daemon's decoder and worker.
//!
//! The same sampler (without commands) and the same worker as `propid run`, so the replay of a
//! run's recording publishes the same model lines. Progress goes to stderr when stderr is a
//! terminal. A regular file is read as it is replayed, chunk by chunk (memory bounded by the
//! daemon's windows, not the file). Anything else (a FIFO, a device) is read to its end first,
//! within [`crate::input::MAX_INPUT_BYTES`] (said on stderr for a FIFO; the first signal ends
//! the wait for its writer).

use std::io::IsTerminal;
use std::os::unix::fs::FileTypeExt;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use super::load::LoadError;
use super::run::load_config;
use super::CliError;
use crate::daemon::runner::{self, RunParts};
use crate::daemon::source::{RecordingSource, Source, SourceError};
use crate::daemon::{Publisher, Shutdown};

/// Arguments of `propid replay`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording (raw TSP/1 bytes, as `propid run --record` or `propid sim --record` wrote).
    pub file: PathBuf,
    /// Configuration file (the `[identify]` and `[publish]` tables apply).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Deliver the recording in reads of at most this many bytes (1 = byte at a time).
    #[arg(long, default_value_t = 65_536, value_parser = clap::value_parser!(u64).range(1..=16_777_216))]
    pub chunk: u64,
    /// Serve the live web page on ADDR (a port or `:PORT`: 127.0.0.1 only; another interface
    /// only when its address is given, e.g. `0.0.0.0:8080`; port 0: any free port, printed); the page stays
    /// up after the replay, with its final state, until Ctrl-C.
    #[arg(long, value_name = "ADDR", value_parser = super::http_arg)]
    pub http: Option<std::net::SocketAddr>,
    /// Write the run report (as `propid run --report`) into DIR at the end.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Runs `propid replay`.
pub fn run(args: Args) -> Result<(), CliError> {
    let mut cfg = load_config(args.config.as_ref())?;
    if let Some(a) = args.http {
        cfg.publish.http = Some(a);
    }
    cfg.publish.http_hold = cfg.publish.http.is_some();
    let shutdown = Shutdown::install()?;
    let identifier = crate::daemon::identify::CoreIdentifier::new(&cfg)?;
    let file = args.file.display().to_string();
    let chunk = args.chunk as usize;
    let unreadable = |e| CliError::io(format!("reading {file}"), e);
    let meta = std::fs::metadata(&args.file).map_err(unreadable)?;
    // unreadable: exit 7; empty or (below) nothing decoded: exit 3, as identify
    let (source, size) = if meta.is_file() {
        if meta.len() == 0 {
            return Err(LoadError::Empty { file }.into());
        }
        let source = RecordingSource::open(&args.file, chunk).map_err(|e| match e {
            SourceError::Open { source, .. } => unreadable(source),
            e => CliError::io(file.clone(), std::io::Error::other(e.to_string())),
        })?;
        (source, meta.len())
    } else {
        // a FIFO (or a device) is read to its end before the replay starts: say so, as
        // opening it waits for its writer (the first signal ends the wait: `Shutdown`)
        if meta.file_type().is_fifo() {
            eprintln!(
                "propid replay: {} is a FIFO: reading it until its writer closes it (Ctrl-C to give up)",
                args.file.display()
            );
        }
        let bytes = super::load::read_input(&args.file)?;
        if bytes.is_empty() {
            return Err(LoadError::Empty { file }.into());
        }
        let size = bytes.len() as u64;
        (RecordingSource::from_bytes(&args.file, bytes, chunk), size)
    };
    let source: Box<dyn Source> = if std::io::stderr().is_terminal() {
        Box::new(Progress::new(source))
    } else {
        Box::new(source)
    };
    let publisher = Publisher::open(&cfg.publish)?;
    let parts = RunParts {
        source,
        plan: None,
        identifier,
        publisher,
        record: None,
        shutdown,
    };
    let summary = runner::run(&cfg, parts)?;
    if summary.link.frames_ok == 0 {
        return Err(LoadError::Undecodable { file, bytes: size }.into());
    }
    if let (Some(dir), Some(material)) = (&args.report, &summary.kinds) {
        super::kinds_report::write_for(dir, material)?;
    }
    Ok(())
}

/// A recording that reports how far it got on stderr, at most every 200 ms.
struct Progress {
    inner: RecordingSource,
    last: Instant,
}

impl Progress {
    fn new(inner: RecordingSource) -> Progress {
        Progress {
            inner,
            last: Instant::now(),
        }
    }

    fn show(&self, done: bool) {
        let (pos, total) = self.inner.progress();
        let pct = if total == 0 {
            100.0
        } else {
            100.0 * pos as f64 / total as f64
        };
        let end = if done { "\n" } else { "" };
        eprint!("\rreplay: {pct:5.1} % of {} bytes{end}", total);
    }
}

impl Source for Progress {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, SourceError> {
        let r = self.inner.read(buf);
        if matches!(r, Err(SourceError::Finished { .. })) {
            self.show(true);
        } else if self.last.elapsed() >= Duration::from_millis(200) {
            self.last = Instant::now();
            self.show(false);
        }
        r
    }
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), SourceError> {
        self.inner.write_all(bytes)
    }
    fn reconnect(&mut self) -> Result<(), SourceError> {
        self.inner.reconnect()
    }
    fn is_live(&self) -> bool {
        self.inner.is_live()
    }
    fn describe(&self) -> String {
        self.inner.describe()
    }
}
