//! FILE → bytes → the one loader ([`propid_ingest::load`], re-exported here): the file read
//! within [`MAX_INPUT_BYTES`] (unreadable: exit 7, too large: exit 3), then its bytes loaded
//! as a [`Request`] asks. [`ReadArgs`] are the flags of every command that reads a file,
//! declared once.

use std::path::{Path, PathBuf};

use super::CliError;
use crate::input::{read_bounded, read_chunks, ReadError, MAX_INPUT_BYTES};
pub use propid_ingest::load::*;
use propid_ingest::window::{Scan, Scanned, WINDOW_SAMPLES};

/// FILE and the flags that say how to read it, shared by every command that reads a file
/// (`identify`, `diagnose`: `#[command(flatten)]` in their `Args`); [`ReadArgs::request`] makes
/// the loader's [`Request`]. The flags that say how any log is read are [`ReadFlags`] (reached
/// through `Deref`), which `sim --replay-command LOG` flattens too.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct ReadArgs {
    /// A TSP/1 recording (raw bytes) or a CSV file.
    pub file: PathBuf,
    /// Output column (default: thrust); repeatable where a command takes several.
    #[arg(long)]
    pub output: Vec<String>,
    /// How the file is read.
    #[command(flatten)]
    pub how: ReadFlags,
}

/// How a log is read: its command column, its rate, its names and its units.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct ReadFlags {
    /// Input column (default: the command column, throttle/ESC signal/pwm; `none`: no input,
    /// steps are found from the response).
    #[arg(long)]
    pub input: Option<String>,
    /// Sample rate, Hz (needed without a time column; resamples onto this rate otherwise).
    #[arg(long)]
    pub fs: Option<f64>,
    /// Column names for a CSV file without a header, comma separated (for a file with one, they
    /// replace its names: to give a column the unit its header does not say).
    #[arg(long, value_delimiter = ',')]
    pub columns: Option<Vec<String>>,
    /// ESC pulse range for throttle columns in µs, `MIN,MAX` (default 1000,2000).
    #[arg(long, value_delimiter = ',')]
    pub esc_us: Option<Vec<f64>>,
    /// Raw command values at throttle 0 and 1, `MIN,MAX` (default: from the header's unit or
    /// the values, e.g. 0..1, 0..100 %, 0..2047 DShot/raw ESC).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub input_range: Option<Vec<f64>>,
    /// Motor magnet poles, for a speed column in eRPM.
    #[arg(long)]
    pub poles: Option<u32>,
}

impl ReadFlags {
    /// The loader's request for `outputs`, with `optional` read too when the file has them.
    pub fn request<'a>(&'a self, outputs: &'a [String], optional: &'a [&'a str]) -> Request<'a> {
        Request {
            input: self.input.as_deref(),
            outputs,
            optional,
            fs_hz: self.fs,
            columns: self.columns.as_deref(),
            esc_us: self.esc_us.as_deref(),
            input_range: self.input_range.as_deref(),
            poles: self.poles,
        }
    }
}

impl std::ops::Deref for ReadArgs {
    type Target = ReadFlags;
    fn deref(&self) -> &ReadFlags {
        &self.how
    }
}

impl ReadArgs {
    /// The loader's request: these flags, with `optional` read too when the file has them.
    pub fn request<'a>(&'a self, optional: &'a [&'a str]) -> Request<'a> {
        self.how.request(&self.output, optional)
    }

    /// Reads FILE as these flags ask, with `optional` read too when the file has them.
    pub fn load(&self, optional: &[&str]) -> Result<LoadedFile, CliError> {
        load(&self.file, &self.request(optional))
    }

    /// [`ReadArgs::load`], but a binary TSP/1 recording longer than the identification window
    /// keeps that window only, in two passes over the file and memory for the window
    /// ([`propid_ingest::window`]; `identify`).
    pub fn load_window(&self, optional: &[&str]) -> Result<LoadedFile, CliError> {
        let req = self.request(optional);
        if let Some(loaded) = load_window(&self.file, &req)? {
            return Ok(loaded);
        }
        let bytes = read_input(&self.file)?;
        Ok(load_owned(self.file.display().to_string(), bytes, &req)?)
    }
}

/// Reads all of `file` within [`MAX_INPUT_BYTES`]: unreadable is an I/O error (exit 7), too
/// large is bad input (exit 3).
pub fn read_input(file: &Path) -> Result<Vec<u8>, CliError> {
    let name = file.display().to_string();
    read_bounded(file, MAX_INPUT_BYTES).map_err(|e| match e {
        ReadError::Io(e) => CliError::io(format!("reading {name}"), e),
        ReadError::TooLarge { limit } => LoadError::TooLarge { file: name, limit }.into(),
    })
}

/// Reads `file` as `req` asks: TSP/1 binary recordings by channel name, everything else as CSV.
pub fn load(file: &Path, req: &Request) -> Result<LoadedFile, CliError> {
    if let Some(loaded) = load_streamed(file, req)? {
        return Ok(loaded);
    }
    let bytes = read_input(file)?;
    Ok(load_owned(file.display().to_string(), bytes, req)?)
}

/// A regular file whose first bytes are a binary TSP/1 recording, decoded as it is read:
/// memory for the record, not for the file's bytes. `None` for anything else.
fn load_streamed(file: &Path, req: &Request) -> Result<Option<LoadedFile>, CliError> {
    let name = file.display().to_string();
    let mut reader = propid_ingest::BinaryReader::new(&ingest_options(req));
    match read_chunks(file, MAX_INPUT_BYTES, is_binary_recording, |c| {
        reader.push(c)
    }) {
        Ok(true) => match reader.finish() {
            Ok((record, stats)) => Ok(Some(from_record(req, name, record, stats)?)),
            Err(source) => Err(LoadError::Recording { file: name, source }.into()),
        },
        Ok(false) => Ok(None),
        Err(ReadError::Io(e)) => Err(CliError::io(format!("reading {name}"), e)),
        Err(ReadError::TooLarge { limit }) => Err(LoadError::TooLarge { file: name, limit }.into()),
    }
}

/// A regular file whose first bytes are a binary TSP/1 recording, of any size, read as
/// [`Scan`] says: whole within the window, else its window in a second pass. `None` for
/// anything else.
fn load_window(file: &Path, req: &Request) -> Result<Option<LoadedFile>, CliError> {
    let name = file.display().to_string();
    let io = |e| match e {
        ReadError::Io(e) => CliError::io(format!("reading {name}"), e),
        ReadError::TooLarge { limit } => LoadError::TooLarge {
            file: name.clone(),
            limit,
        }
        .into(),
    };
    let bad = |source| -> CliError {
        LoadError::Recording {
            file: name.clone(),
            source,
        }
        .into()
    };
    let command = match req.input {
        Some(NO_INPUT) => None,
        other => Some(other.unwrap_or(propid_wire::record::names::THROTTLE)),
    };
    let mut scan = Scan::new(&ingest_options(req), command, WINDOW_SAMPLES);
    if !read_chunks(file, u64::MAX, is_binary_recording, |c| scan.push(c)).map_err(io)? {
        return Ok(None);
    }
    let (record, stats) = loop {
        match scan.finish().map_err(bad)? {
            Scanned::Whole(record, stats) => break (record, stats),
            Scanned::Rescan(again) => {
                scan = again;
                read_chunks(file, u64::MAX, |_, _| true, |c| scan.push(c)).map_err(io)?;
            }
            Scanned::Window(mut reader) => {
                read_chunks(file, u64::MAX, |_, _| true, |c| reader.push(c)).map_err(io)?;
                break reader.finish().map_err(bad)?;
            }
        }
    };
    Ok(Some(from_record(req, name, record, stats)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn errors_keep_their_class() {
        let dir = tempfile::tempdir().unwrap();
        let e = load(&write(dir.path(), "e.csv", ""), &Request::default()).unwrap_err();
        assert!(matches!(&e, CliError::Load(LoadError::Empty { .. })), "{e}");
        assert_eq!(e.exit_code(), 3);
        let good = write(
            dir.path(),
            "g.csv",
            "t_s,throttle,thrust_N\n0,0.2,1\n0.01,0.2,1\n",
        );
        let bad_esc = [1000.0];
        let req = Request {
            esc_us: Some(&bad_esc),
            ..Request::default()
        };
        let e = load(&good, &req).unwrap_err();
        assert_eq!(e.to_string(), "--esc-us takes MIN,MAX");
        assert_eq!(e.exit_code(), 2);
        let e = load(&dir.path().join("absent.csv"), &Request::default()).unwrap_err();
        assert_eq!(e.exit_code(), 7, "{e}");
    }

    /// A binary recording of `n` samples at 1 kHz whose throttle steps on every 50th row over
    /// rows `burst` only.
    fn recording(n: u32, burst: std::ops::Range<u32>) -> Vec<u8> {
        use propid_wire::protocol::message::{Sample, SampleFlags};
        use propid_wire::protocol::{encode_frame, Message, MAX_FRAME_LEN};
        let mut out = Vec::new();
        let mut buf = [0u8; MAX_FRAME_LEN];
        for i in 0..n {
            let up = burst.contains(&i) && (i / 50) % 2 == 1;
            let s = Sample {
                sample_index: i,
                t_us: 1000 * i,
                throttle: if up { 3000 } else { 2000 },
                flags: SampleFlags::THRUST_VALID | SampleFlags::THRUST_FRESH,
                thrust_n: if up { 2.0 } else { 1.0 } + 0.001 * (i % 5) as f32,
                ..Sample::default()
            };
            let len = encode_frame(i as u16, &Message::Sample(s), &mut buf);
            out.extend_from_slice(&buf[..len]);
        }
        out
    }

    #[test]
    fn a_long_recording_is_read_in_two_passes_keeping_its_window() {
        let dir = tempfile::tempdir().unwrap();
        let n = WINDOW_SAMPLES as u32 + 9000;
        let f = dir.path().join("long.tsp");
        std::fs::write(&f, recording(n, n - 1000..n - 500)).unwrap();
        let args = ReadArgs {
            file: f,
            ..ReadArgs::default()
        };
        let whole = args.load(&[]).unwrap();
        let part = args.load_window(&[]).unwrap();
        let Origin::Tsp1(stats) = &part.origin else {
            panic!("not read as a recording");
        };
        let w = stats.window.unwrap();
        // the burst's block (a sixteenth of the window) is the window's last
        let start = WINDOW_SAMPLES / 16;
        assert_eq!(
            (w.start, w.samples, w.file_samples),
            (start, WINDOW_SAMPLES, n as usize)
        );
        assert!(w.moves > 0 && w.moves <= w.file_moves, "{w:?}");
        let span = start..start + WINDOW_SAMPLES;
        for name in ["throttle", "thrust_N"] {
            assert_eq!(part.data(name), whole.data(name)[span.clone()], "{name}");
        }
        // the file's counters
        let Origin::Tsp1(all) = &whole.origin else {
            panic!("not read as a recording");
        };
        assert_eq!(stats.assemble, all.assemble);
        assert_eq!(stats.frames, all.frames);
        // a short one is read as before
        let short = dir.path().join("short.tsp");
        std::fs::write(&short, recording(5000, 1000..2000)).unwrap();
        let args = ReadArgs {
            file: short,
            ..ReadArgs::default()
        };
        let (a, b) = (args.load(&[]).unwrap(), args.load_window(&[]).unwrap());
        assert_eq!(format!("{:?}", a.record), format!("{:?}", b.record));
        let (Origin::Tsp1(a), Origin::Tsp1(b)) = (a.origin, b.origin) else {
            panic!("not read as a recording");
        };
        assert_eq!(a, b);
        assert_eq!(b.window, None);
    }
}
