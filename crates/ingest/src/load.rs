//! FILE → a [`Record`] holding the channels a subcommand asked for: the one file loader of
//! `propid identify` and `propid diagnose`.
//!
//! The format is detected from the bytes ([`detect`]): a binary TSP/1 recording, or a TSP/1
//! CSV stream, goes through [`read_record_with`] (channels by canonical name, device events
//! kept), everything else through the CSV reader [`read_csv`](propid_ingest::csv_file::read_csv) (exported stand logs: aliases,
//! units, the command's scale decided and stated, empty cells per channel, BOM, files without a
//! time column; a file without a header needs `--columns`; see [`propid_ingest::csv_file`]).
//! The input is the command column (throttle) unless `--input NAME` names another, or
//! `--input none` ([`NO_INPUT`]) asks for none. Errors are the same for both subcommands: an
//! unreadable file is an I/O error (exit 7), an empty or bad file, an absent channel or column,
//! a command whose scale cannot be decided an input error (exit 3), a malformed `--esc-us`,
//! `--input-range` or `--poles` a usage error (exit 2).
//!
//! What a subcommand does with the channels afterwards (identify: the missing mask and the JSON
//! `"source"`; diagnose: gap-filled signals) is its own step after [`load`]; finding the input
//! from the response's steps, with `--input none`, is the shared step [`steps_from_response`].

use std::borrow::Cow;

use crate::csv_file::{parse_csv, CsvFileError, CsvFileOptions, CsvSource, InputChoice};
use crate::steps::{find_steps, StepFinding};
use crate::{read_record_with, IngestError, IngestOptions, IngestStats};
use propid_wire::protocol::csv::encoding::{decode, wide, Encoding};
use propid_wire::protocol::detect::{detect, is_csv_stream, Detection, WireFormat};
use propid_wire::record::{names, Record};

/// The channels of a stand's static map: its key, the record's channel and its unit.
pub const STAND_CHANNELS: [(&str, &str, &str); 4] = [
    ("thrust", names::THRUST, "N"),
    ("torque", names::TORQUE, "N·m"),
    ("rpm", names::RPM, "rev/min"),
    ("current", names::CURRENT, "A"),
];

/// Why a readable file could not be read as asked (exit 3); every message starts with the file.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file has no byte.
    #[error("{file}: the file is empty")]
    Empty {
        /// The file as given.
        file: String,
    },
    /// A spreadsheet workbook or a compressed archive, not a text or a recording.
    #[error("{file}: {kind}, not a CSV text or a TSP/1 recording: {fix}")]
    NotText {
        /// The file as given.
        file: String,
        /// What its first bytes say it is.
        kind: &'static str,
        /// What to do with it.
        fix: &'static str,
    },
    /// The file is larger than what propid reads of one input.
    #[error(
        "{file}: larger than {limit} bytes (1 GiB), the most propid reads of one input (a CSV \
         file takes about 32 bytes of memory a row per column read, and identify its own \
         buffers besides: docs/identify.md, Memory)"
    )]
    TooLarge {
        /// The file as given.
        file: String,
        /// The bound, bytes.
        limit: u64,
    },
    /// A recording in which no frame decoded (`propid replay`).
    #[error("{file}: no TSP/1 frame or CSV row decoded ({bytes} bytes)")]
    Undecodable {
        /// The file as given.
        file: String,
        /// Its size, bytes.
        bytes: u64,
    },
    /// A binary TSP/1 recording that does not decode into a record.
    #[error("{file}: {source}")]
    Recording {
        /// The file as given.
        file: String,
        /// The ingest error.
        source: IngestError,
    },
    /// A channel asked for is not in the recording.
    #[error("{file}: no channel {want}; the recording has {}", .have.join(", "))]
    NoChannel {
        /// The file as given.
        file: String,
        /// The channel asked for.
        want: String,
        /// The channels the recording has.
        have: Vec<String>,
    },
    /// A CSV file that does not read as asked.
    #[error("{file}: {source}")]
    Csv {
        /// The file as given.
        file: String,
        /// The CSV reader's error.
        source: CsvFileError,
    },
    /// A read option that makes no sense (a usage error, exit 2).
    #[error(transparent)]
    Option(#[from] OptionError),
}

/// A malformed read option (`--esc-us`, `--input-range`, `--poles`), found when a CSV file
/// needs it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptionError {
    /// `--esc-us` without exactly two finite values, `MIN < MAX`.
    #[error("--esc-us takes MIN,MAX")]
    EscUs,
    /// `--input-range` without exactly two finite values, `MIN < MAX`.
    #[error("--input-range takes MIN,MAX (the raw command values at throttle 0 and 1)")]
    InputRange,
    /// `--poles` zero or odd.
    #[error("--poles {0}: a motor has an even number of magnet poles > 0")]
    Poles(u32),
}

/// What to read from a file (the options `identify` and `diagnose` share).
#[derive(Debug, Clone, Default)]
pub struct Request<'a> {
    /// Input column or channel; `None` = the command (throttle) column, which a CSV file must
    /// then have; [`NO_INPUT`] (`--input none`) = no input, steps are found in the response.
    pub input: Option<&'a str>,
    /// Output columns or channels; empty = the thrust (by quantity in a CSV file).
    pub outputs: &'a [String],
    /// Channels read too when the file has them (diagnose: the supply voltage; identify: the
    /// static map's thrust, torque, rpm and current); in a CSV file each is asked for after the
    /// outputs (after `thrust` when `outputs` is empty) and left out when the file lacks it.
    pub optional: &'a [&'a str],
    /// Sample rate, Hz (`--fs`).
    pub fs_hz: Option<f64>,
    /// Column names for a CSV file without a header, or replacing a header's names (`--columns`).
    pub columns: Option<&'a [String]>,
    /// ESC pulse range for throttle columns, µs (`--esc-us MIN,MAX`, CSV files only).
    pub esc_us: Option<&'a [f64]>,
    /// Raw command values at throttle 0 and 1 (`--input-range MIN,MAX`, CSV files only).
    pub input_range: Option<&'a [f64]>,
    /// Motor pole count, for a speed in eRPM (`--poles N`, CSV files only).
    pub poles: Option<u32>,
}

/// The `--input` value that asks for no input column: the steps are found in the response.
pub const NO_INPUT: &str = "none";

/// The format a file was read as, with what its reader reports.
#[derive(Debug, Clone)]
pub enum Origin {
    /// A binary TSP/1 recording and its decoding counters.
    Tsp1(Box<IngestStats>),
    /// A CSV file: columns as named in the file, time base, skipped rows.
    Csv(Box<CsvSource>),
}

/// A file read as a [`Request`] asked.
#[derive(Debug, Clone)]
pub struct LoadedFile {
    /// The file as given (the prefix of every message about it).
    pub name: String,
    /// The channels read; missing samples are NaN and marked in `record.missing`.
    pub record: Record,
    /// How it was read.
    pub origin: Origin,
    /// The input channel in `record`; `None` for a CSV file without an input column.
    pub input: Option<String>,
    /// The output channels in `record`, in the order asked for.
    pub outputs: Vec<String>,
    /// The optional channels in `record` that the file has, in the order asked for.
    pub optional: Vec<String>,
}

impl LoadedFile {
    /// Whether the input is a stand's command (a throttle, an ESC signal; the levels of steps
    /// found from the response): every input but a CSV column read as a signal in its own
    /// units ([`CsvSource::input_is_a_command`]).
    pub fn input_is_a_command(&self) -> bool {
        match &self.origin {
            Origin::Csv(src) => src.input_is_a_command(),
            Origin::Tsp1(_) => true,
        }
    }

    /// A copy of the samples of channel `name` (empty when the record has no such channel).
    pub fn data(&self, name: &str) -> Vec<f64> {
        self.record
            .channel(name)
            .map(|c| c.data.clone())
            .unwrap_or_default()
    }
}

/// Reads the bytes of a file named `name` as `req` asks (the fuzz harness calls it in memory).
pub fn load_bytes(name: String, bytes: &[u8], req: &Request) -> Result<LoadedFile, LoadError> {
    load_from(name, Cow::Borrowed(bytes), req)
}

/// [`load_bytes`] of bytes it owns, dropped as soon as they are read (a CSV file's once its
/// columns are parsed, before they are carried onto the time base).
pub fn load_owned(name: String, bytes: Vec<u8>, req: &Request) -> Result<LoadedFile, LoadError> {
    load_from(name, Cow::Owned(bytes), req)
}

fn load_from(name: String, bytes: Cow<'_, [u8]>, req: &Request) -> Result<LoadedFile, LoadError> {
    if bytes.is_empty() {
        return Err(LoadError::Empty { file: name });
    }
    if let Some((kind, fix)) = container(&bytes) {
        return Err(LoadError::NotText {
            file: name,
            kind,
            fix,
        });
    }
    // A UTF-16 or UTF-32 text (its NUL bytes would look binary) is read as the UTF-8 it
    // decodes to; anything else is decoded once, by the reader that takes it as text.
    let utf8 = wide(&bytes)
        .map(|_| decode(&bytes))
        .filter(|(text, _)| is_text(text))
        .map(|(text, e)| (text.into_owned().into_bytes(), e));
    let (bytes, wide_from) = match utf8 {
        Some((utf8, e)) => {
            drop(bytes);
            (Cow::Owned(utf8), Some(e))
        }
        None => (bytes, None),
    };
    match detect(&bytes, true) {
        Detection::Format(WireFormat::Binary) => load_tsp(req, name, &bytes),
        // A CSV stream is placed by the stream placer, as `replay` places it; any other CSV
        // file is an exported log, read by its own time column.
        _ if req.columns.is_none() && is_csv_stream(&bytes) => load_tsp(req, name, &bytes),
        _ => load_csv(req, name, bytes, wide_from),
    }
}

/// What a file's first bytes say it is when it is a container a stand's software writes
/// beside its CSV (an Excel or LibreOffice workbook, a compressed log), with what to do: its
/// bytes would otherwise read as a stream with no frame.
fn container(bytes: &[u8]) -> Option<(&'static str, &'static str)> {
    const XLS: &[u8] = &[0xD0, 0xCF, 0x11, 0xE0, 0xA1, 0xB1, 0x1A, 0xE1];
    if bytes.starts_with(b"PK\x03\x04") {
        Some((
            "a zip archive (an .xlsx or .ods workbook?)",
            "export the sheet as CSV, or unpack the archive",
        ))
    } else if bytes.starts_with(XLS) {
        Some((
            "an Excel 97–2003 workbook (.xls)",
            "export the sheet as CSV",
        ))
    } else if bytes.starts_with(&[0x1F, 0x8B, 0x08]) && bytes.get(3).is_some_and(|f| f & 0xE0 == 0)
    {
        // Deflate and no reserved flag (RFC 1952): a recording's stray bytes are not taken
        // for one.
        Some(("a gzip-compressed file", "decompress it first (gunzip)"))
    } else {
        None
    }
}

/// A binary TSP/1 recording: every channel the device sent; the input (default throttle) and
/// the outputs (default thrust) must be among them.
fn load_tsp(req: &Request, name: String, bytes: &[u8]) -> Result<LoadedFile, LoadError> {
    let (record, stats) = match read_record_with(bytes, &ingest_options(req)) {
        Ok(r) => r,
        Err(source) => return Err(LoadError::Recording { file: name, source }),
    };
    from_record(req, name, record, stats)
}

/// Whether a file's first bytes (`whole`: they are the whole file) are a binary TSP/1
/// recording, as [`load_bytes`] would take them: the test a caller streaming a file from disk
/// makes before decoding it in chunks ([`crate::BinaryReader`], then [`from_record`]).
pub fn is_binary_recording(first: &[u8], whole: bool) -> bool {
    container(first).is_none()
        && wide(first).is_none()
        && detect(first, whole) == Detection::Format(WireFormat::Binary)
}

/// The decoder's options a request asks for.
pub fn ingest_options(req: &Request) -> IngestOptions {
    IngestOptions {
        fs_hz: req.fs_hz,
        ..IngestOptions::default()
    }
}

/// The channels `req` asks for in a decoded recording.
pub fn from_record(
    req: &Request,
    name: String,
    record: Record,
    stats: IngestStats,
) -> Result<LoadedFile, LoadError> {
    let present = |want: &str| -> Result<String, LoadError> {
        match record.channel(want) {
            Some(_) => Ok(want.to_string()),
            None => Err(LoadError::NoChannel {
                file: name.clone(),
                want: want.to_string(),
                have: record.channels.iter().map(|c| c.name.clone()).collect(),
            }),
        }
    };
    let input = match req.input {
        Some(NO_INPUT) => None,
        other => Some(present(other.unwrap_or(names::THROTTLE))?),
    };
    let outputs = if req.outputs.is_empty() {
        vec![present(names::THRUST)?]
    } else {
        req.outputs
            .iter()
            .map(|n| present(n))
            .collect::<Result<_, _>>()?
    };
    let optional = req
        .optional
        .iter()
        .filter_map(|n| present(n).ok())
        .collect();
    Ok(LoadedFile {
        name,
        record,
        origin: Origin::Tsp1(Box::new(stats)),
        input,
        outputs,
        optional,
    })
}

/// A CSV file: the columns asked for, with the optional ones the file has.
/// `was` is the encoding the bytes were decoded from already (UTF-16, UTF-32), if any. The
/// bytes (and their text) are dropped once the columns are parsed.
fn load_csv(
    req: &Request,
    name: String,
    bytes: Cow<'_, [u8]>,
    was: Option<Encoding>,
) -> Result<LoadedFile, LoadError> {
    let pair = |v: Option<&[f64]>, bad: OptionError| match v {
        Some(&[lo, hi]) if lo.is_finite() && hi.is_finite() && lo < hi => Ok(Some((lo, hi))),
        Some(_) => Err(bad),
        None => Ok(None),
    };
    let opts = CsvFileOptions {
        input: match req.input {
            None => InputChoice::Command,
            Some(NO_INPUT) => InputChoice::None,
            Some(column) => InputChoice::Column(column.to_string()),
        },
        outputs: req.outputs.to_vec(),
        optional: req.optional.iter().map(|s| s.to_string()).collect(),
        fs_hz: req.fs_hz,
        columns: req.columns.map(<[String]>::to_vec),
        esc_us: pair(req.esc_us, OptionError::EscUs)?,
        input_range: pair(req.input_range, OptionError::InputRange)?,
        motor_poles: match req.poles {
            Some(p) if p == 0 || p % 2 == 1 => return Err(OptionError::Poles(p).into()),
            p => p,
        },
    };
    let (parsed, encoding) = {
        let (text, encoding) = decode(&bytes);
        (parse_csv(&text, &opts), was.unwrap_or(encoding))
    };
    drop(bytes);
    let mut file = parsed
        .and_then(|p| p.build(&opts))
        .map_err(|source| LoadError::Csv {
            file: name.clone(),
            source,
        })?;
    file.source.encoding = (encoding != Encoding::Utf8).then_some(encoding);
    Ok(LoadedFile {
        name,
        record: file.record,
        origin: Origin::Csv(Box::new(file.source)),
        input: file.input,
        outputs: file.outputs,
        optional: file.optional,
    })
}

/// True when decoded text is text: no replacement character and no control character but a
/// tab or a line end (a binary recording that happens to start like a UTF-16 mark is not).
fn is_text(text: &str) -> bool {
    !text
        .chars()
        .any(|c| c == '\u{fffd}' || (c.is_control() && !matches!(c, '\t' | '\r' | '\n')))
}

/// Why no input could be found from the response.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum NoSteps {
    /// Fewer finite samples than [`find_steps`] needs.
    #[error("too short to find steps in")]
    TooShort,
    /// The response has no step.
    #[error("no step found in the response")]
    NoneFound,
}

/// The input of a record without an input column: the steps of response `y` and the level
/// sequence built from them ([`find_steps`], whose module documents the method).
pub fn steps_from_response(y: &[f64]) -> Result<StepFinding, NoSteps> {
    let found = find_steps(y).ok_or(NoSteps::TooShort)?;
    if found.steps.is_empty() {
        return Err(NoSteps::NoneFound);
    }
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `t_s,throttle,thrust_N,voltage_V` (with the voltage when `volt`), a step at sample 50.
    fn csv(volt: bool) -> String {
        let mut s = String::from(if volt {
            "t_s,throttle,thrust_N,voltage_V\n"
        } else {
            "t_s,throttle,thrust_N\n"
        });
        for k in 0..100 {
            let u = if k < 50 { 0.2 } else { 0.4 };
            let y = if k < 51 { 1.0 } else { 3.0 };
            s += &format!("{},{u},{y}", k as f64 * 0.01);
            if volt {
                s += ",12.0";
            }
            s += "\n";
        }
        s
    }

    #[test]
    fn csv_reads_the_optional_channel_when_present_and_not_otherwise() {
        let req = Request {
            optional: &[names::VOLTAGE],
            ..Request::default()
        };
        let with = load_bytes("v.csv".into(), csv(true).as_bytes(), &req).unwrap();
        assert_eq!(with.input.as_deref(), Some(names::THROTTLE));
        assert_eq!(with.outputs, [names::THRUST]);
        assert_eq!(with.optional, vec![names::VOLTAGE.to_string()]);
        assert_eq!(with.data(names::VOLTAGE).len(), 100);
        let without = load_bytes("n.csv".into(), csv(false).as_bytes(), &req).unwrap();
        assert_eq!(without.outputs, [names::THRUST]);
        assert!(without.optional.is_empty());
        assert!(matches!(without.origin, Origin::Csv(_)));
    }

    #[test]
    fn errors_keep_their_kind_and_name_the_file() {
        let e = load_bytes("e.csv".into(), b"", &Request::default()).unwrap_err();
        assert!(
            matches!(&e, LoadError::Empty { file } if file.ends_with("e.csv")),
            "{e}"
        );
        assert!(e.to_string().ends_with("e.csv: the file is empty"), "{e}");
        // A workbook saved where its CSV export was expected, a compressed log.
        for (bytes, says) in [
            (&b"PK\x03\x04\x14\x00rest"[..], "export the sheet as CSV"),
            (
                &[0xD0, 0xCF, 0x11, 0xE0, 0xA1, 0xB1, 0x1A, 0xE1, 0][..],
                ".xls",
            ),
            (&[0x1F, 0x8B, 8, 0][..], "gunzip"),
        ] {
            let e = load_bytes("log".into(), bytes, &Request::default()).unwrap_err();
            assert!(e.to_string().contains(says), "{e}");
            assert!(matches!(e, LoadError::NotText { .. }), "{e}");
        }
        let good = csv(false);
        let good = good.as_bytes();
        let bad_esc = [1000.0];
        let req = Request {
            esc_us: Some(&bad_esc),
            ..Request::default()
        };
        let e = load_bytes("g.csv".into(), good, &req).unwrap_err();
        assert!(matches!(e, LoadError::Option(OptionError::EscUs)), "{e}");
        let outputs = ["rpm".to_string()];
        let req = Request {
            outputs: &outputs,
            ..Request::default()
        };
        let e = load_bytes("g.csv".into(), good, &req).unwrap_err();
        assert!(matches!(&e, LoadError::Csv { .. }), "{e}");
        let m = e.to_string();
        assert!(m.contains("g.csv") && m.contains("rpm"), "{m}");
    }

    #[test]
    fn steps_from_response_tells_too_short_from_no_step() {
        assert_eq!(
            steps_from_response(&[1.0; 5]).unwrap_err(),
            NoSteps::TooShort
        );
        assert_eq!(
            steps_from_response(&[1.0; 200]).unwrap_err(),
            NoSteps::NoneFound
        );
        let y: Vec<f64> = (0..200).map(|k| if k < 100 { 1.0 } else { 3.0 }).collect();
        let found = steps_from_response(&y).unwrap();
        assert_eq!(found.steps.len(), 1);
        assert_eq!(found.input.len(), 200);
    }
}
