//! A TSP/1 recording — the raw bytes a stand sent, as `cat /dev/ttyACM0 > run.tsp` gives —
//! into a uniform [`Record`]. Binary or CSV is detected ([`detect`]); both go through the same
//! sans-IO decoders as the live link, then through the [`RecordBuilder`].
//!
//! CSV time base: rows, `# HELLO` and `#EVENT` lines go through `propid_wire`'s [`CsvStream`]
//! — the adapter the daemon's CSV link (`replay`) reads the same bytes with — so every row gets
//! the index the daemon gives it: its `idx` column when it has one, otherwise the index rebuilt
//! from its time by the one placer ([`RowPlacer`](propid_wire::stream::RowPlacer): period from
//! the HELLO rate or measured on the first rows, a phase tracker that absorbs jitter, lost rows
//! left as gaps, a repeated time a duplicate, the 32-bit clock unwrapped, a big step back a new
//! segment). Gaps become missing samples. This suits streams with a steady clock; for logs with
//! irregular timestamps (exported files) resample instead (the CSV file reader does). Rows
//! without a time (or a negative one) are dropped, as on the live link; when fewer than two rows
//! have a time, [`IngestOptions::fs_hz`] gives the rate and all rows are consecutive.

use serde::Serialize;

use super::assemble::{AssembleOptions, AssembleStats, BuildStats, RecordBuilder, Values};
use super::IngestError;
use propid_wire::protocol::csv::{
    CsvDecoder, CsvItem, CsvOptions, CsvRow, CsvStats, UnresolvedColumn,
};
use propid_wire::protocol::detect::{detect, Detection, WireFormat};
use propid_wire::protocol::{DecodeStats, Decoder};
use propid_wire::record::Record;
use propid_wire::stream::{CsvFact, CsvStream};

/// Options of [`read_record_with`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IngestOptions {
    /// Gap handling.
    pub assemble: AssembleOptions,
    /// CSV decoding (unit options, line limit: 255 as on the wire by default).
    pub csv: CsvOptions,
    /// Sample rate for CSV data without a time column, Hz.
    pub fs_hz: Option<f64>,
}

impl IngestOptions {
    /// Options for exported CSV files: lines up to 4096 characters (their headers are long).
    pub fn exported_file() -> Self {
        let mut o = Self::default();
        o.csv.max_line = 4096;
        o
    }
}

/// What reading a recording found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IngestStats {
    /// Binary or CSV.
    pub format: WireFormat,
    /// Binary decoder counters (binary input).
    pub frames: Option<DecodeStats>,
    /// CSV decoder counters (CSV input).
    pub csv: Option<CsvStats>,
    /// Sample placement counters.
    pub assemble: AssembleStats,
    /// Record building counters.
    pub build: BuildStats,
    /// Sample period used, s.
    pub dt_s: f64,
    /// Nominal sample period from HELLO, s (binary input with a HELLO).
    pub dt_nominal_s: Option<f64>,
    /// The span of the file the record holds, when not all of it ([`crate::window`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window: Option<RecordWindow>,
}

/// Read a recording with default options.
pub fn read_record(bytes: &[u8]) -> Result<(Record, IngestStats), IngestError> {
    read_record_with(bytes, &IngestOptions::default())
}

/// Read a recording (binary or CSV, detected).
pub fn read_record_with(
    bytes: &[u8],
    o: &IngestOptions,
) -> Result<(Record, IngestStats), IngestError> {
    if bytes.is_empty() {
        return Err(IngestError::Empty);
    }
    match detect(bytes, true) {
        Detection::Format(WireFormat::Csv) => read_csv(bytes, o),
        _ => read_binary(bytes, o),
    }
}

fn read_binary(bytes: &[u8], o: &IngestOptions) -> Result<(Record, IngestStats), IngestError> {
    let mut r = BinaryReader::new(o);
    r.push(bytes);
    r.finish()
}

/// Which span of a recording the record holds (`"source"."window"` of `identify`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RecordWindow {
    /// Position of the record's first row in the file's rows.
    pub start: usize,
    /// Rows in the record.
    pub samples: usize,
    /// Rows of the whole file (missing ones included).
    pub file_samples: usize,
    /// The record's start, s after the file's first row (`start` sample periods).
    pub start_s: f64,
    /// The command's moves in the window (changes of more than 2 % of its range).
    pub moves: usize,
    /// The command's moves in the whole file.
    pub file_moves: usize,
}

impl RecordWindow {
    /// The window a windowed reader's record holds: `kept` its first row and end in the
    /// file's rows, `moves` the command's moves in the window and in the file.
    pub(crate) fn new(
        kept: (usize, usize),
        file_samples: usize,
        samples: usize,
        dt_s: f64,
        moves: (usize, usize),
    ) -> Self {
        RecordWindow {
            start: kept.0,
            samples,
            file_samples,
            start_s: kept.0 as f64 * dt_s,
            moves: moves.0,
            file_moves: moves.1,
        }
    }
}

/// A binary TSP/1 recording read piece by piece (a file read in chunks: memory for the record,
/// not for the file's bytes): the same decoder and builder as [`read_record_with`], so any
/// split of the bytes gives the same record and counters.
pub struct BinaryReader {
    dec: Decoder,
    builder: RecordBuilder,
    /// The command's moves in the kept span and in the file (a windowed reader).
    pub(crate) moves: Option<(usize, usize)>,
}

impl BinaryReader {
    /// A reader with `o`'s gap handling.
    pub fn new(o: &IngestOptions) -> Self {
        BinaryReader {
            dec: Decoder::new(),
            builder: RecordBuilder::new(o.assemble),
            moves: None,
        }
    }

    /// The record builder.
    pub fn builder(&self) -> &RecordBuilder {
        &self.builder
    }

    /// The record builder, to keep a span of it or take its rows.
    pub fn builder_mut(&mut self) -> &mut RecordBuilder {
        &mut self.builder
    }

    /// The next bytes of the recording.
    pub fn push(&mut self, bytes: &[u8]) {
        let b = &mut self.builder;
        self.dec.push(bytes, |f| b.push_frame(&f));
    }

    /// The record and what reading it found.
    pub fn finish(self) -> Result<(Record, IngestStats), IngestError> {
        let dt_nominal_s = self.builder.assembler().nominal_dt_s();
        let (kept, file_samples) = (self.builder.kept(), self.builder.len());
        let (record, assemble, build) = self.builder.finish()?;
        let window = kept.map(|k| {
            let moves = self.moves.unwrap_or_default();
            RecordWindow::new(k, file_samples, record.len(), record.dt_s, moves)
        });
        let stats = IngestStats {
            format: WireFormat::Binary,
            frames: Some(*self.dec.stats()),
            csv: None,
            assemble,
            build,
            dt_s: record.dt_s,
            dt_nominal_s,
            window,
        };
        Ok((record, stats))
    }
}

fn read_csv(bytes: &[u8], o: &IngestOptions) -> Result<(Record, IngestStats), IngestError> {
    let mut dec = CsvDecoder::new(o.csv);
    let mut ingest = CsvIngest {
        stream: CsvStream::new(),
        builder: RecordBuilder::new(o.assemble),
        rows: Vec::new(),
        unresolved: None,
        t0_s: None,
    };
    dec.push(bytes, |it| ingest.item(it));
    dec.finish(|it| ingest.item(it));
    let CsvIngest {
        mut stream,
        mut builder,
        rows,
        unresolved,
        t0_s,
    } = ingest;
    stream.finish(&mut |f| put(&mut builder, f));
    if let Some(u) = unresolved {
        return Err(IngestError::NeedsOption {
            column: u.source_name,
            reason: u.reason,
        });
    }
    if rows.is_empty() {
        return Err(IngestError::NoSamples);
    }
    let timed = stream.stats().rows + stream.stats().out_of_order;
    let (t0, dt) = if timed >= 2 {
        (t0_s.unwrap_or(0.0), None)
    } else {
        builder = RecordBuilder::new(o.assemble);
        let dt = consecutive(&rows, o, &mut builder)?;
        (0.0, Some(dt))
    };
    let dt_nominal_s = builder.assembler().nominal_dt_s();
    let (mut record, assemble, build) = builder.finish()?;
    record.t0_s = t0;
    if let Some(dt) = dt {
        record.dt_s = dt;
    }
    let stats = IngestStats {
        format: WireFormat::Csv,
        frames: None,
        csv: Some(*dec.stats()),
        assemble,
        build,
        dt_s: record.dt_s,
        dt_nominal_s,
        window: None,
    };
    Ok((record, stats))
}

/// Decoded CSV lines into the record builder, through the daemon's [`CsvStream`].
struct CsvIngest {
    stream: CsvStream,
    builder: RecordBuilder,
    /// Every data row, for input without a time column.
    rows: Vec<CsvRow>,
    /// The first column of the header that needs an option.
    unresolved: Option<UnresolvedColumn>,
    /// Time of the first placed row, s.
    t0_s: Option<f64>,
}

impl CsvIngest {
    fn item(&mut self, it: CsvItem<'_>) {
        match &it {
            CsvItem::Row(r) => self.rows.push(*r),
            CsvItem::Header(h) => self.unresolved = h.unresolved.first().cloned(),
            _ => {}
        }
        let (b, t0) = (&mut self.builder, &mut self.t0_s);
        self.stream.item(it, &mut |f| {
            if let CsvFact::Row(p) = &f {
                t0.get_or_insert(p.value.t_s.unwrap_or(0.0));
            }
            put(b, f)
        });
    }
}

/// One device fact into the builder: rows at the index the placer gave them (the wire's
/// 32-bit counters, as the daemon's SAMPLE frames carry them).
fn put(b: &mut RecordBuilder, f: CsvFact) {
    match f {
        CsvFact::Row(p) => b.push_point(p.index as u32, p.t_us as u32, row_values(&p.value)),
        CsvFact::Hello(h) => b.push_hello(&h),
        CsvFact::Event(e) => b.push_event(&e),
        CsvFact::NewBoot | CsvFact::Ack(_) => {}
    }
}

fn row_values(r: &CsvRow) -> Values {
    [
        r.throttle,
        r.thrust_n,
        r.torque_nm,
        r.rpm,
        r.voltage_v,
        r.current_a,
    ]
}

/// Rows without times, consecutive at the given rate; returns the exact sample period.
fn consecutive(
    rows: &[CsvRow],
    o: &IngestOptions,
    b: &mut RecordBuilder,
) -> Result<f64, IngestError> {
    let fs = o.fs_hz.ok_or(IngestError::NoTimebase)?;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(IngestError::BadOption {
            name: "fs_hz",
            value: fs,
        });
    }
    let us = |t_s: f64| (t_s * 1e6).round() as i64 as u32;
    for (k, r) in rows.iter().enumerate() {
        b.push_point(k as u32, us(k as f64 / fs), row_values(r));
    }
    Ok(1.0 / fs)
}

#[cfg(test)]
mod tests;
