//! A TSP/1 recording — the raw bytes a stand sent, as `cat /dev/ttyACM0 > run.tsp` gives —
//! into a uniform [`Record`]. Binary or CSV is detected ([`detect`]); both go through the same
//! sans-IO decoders as the live link, then through the [`RecordBuilder`].
//!
//! CSV time base: with an `idx` column, the device index places rows exactly as in binary
//! (gaps become missing samples). Otherwise rows are placed on the grid
//! `k = round((t − t₀) / dt_med)`, `dt_med` the median of the positive time steps: a row
//! landing on an occupied position is a duplicate (dropped, counted), a skipped position is a
//! missing sample. This suits streams with a steady clock; for logs with irregular timestamps
//! (exported files) resample first (the CSV file reader does). Without a time column,
//! [`IngestOptions::fs_hz`] gives the rate and rows are consecutive.

use serde::Serialize;

use super::assemble::{AssembleOptions, AssembleStats, BuildStats, RecordBuilder, Values};
use super::IngestError;
use propid_wire::protocol::csv::{CsvDecoder, CsvItem, CsvOptions, CsvRow, CsvStats};
use propid_wire::protocol::detect::{detect, Detection, WireFormat};
use propid_wire::protocol::{DecodeStats, Decoder};
use propid_wire::record::Record;

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
    let mut dec = Decoder::new();
    let mut b = RecordBuilder::new(o.assemble);
    dec.push(bytes, |f| b.push_frame(&f));
    let dt_nominal_s = b.assembler().nominal_dt_s();
    let (record, assemble, build) = b.finish()?;
    let stats = IngestStats {
        format: WireFormat::Binary,
        frames: Some(*dec.stats()),
        csv: None,
        assemble,
        build,
        dt_s: record.dt_s,
        dt_nominal_s,
    };
    Ok((record, stats))
}

fn read_csv(bytes: &[u8], o: &IngestOptions) -> Result<(Record, IngestStats), IngestError> {
    let mut dec = CsvDecoder::new(o.csv);
    let mut rows = Vec::new();
    let mut unresolved = None;
    let mut on = |it: CsvItem<'_>| match it {
        CsvItem::Row(r) => rows.push(r),
        CsvItem::Header(h) => {
            unresolved = h.unresolved.first().cloned();
        }
        _ => {}
    };
    dec.push(bytes, &mut on);
    dec.finish(&mut on);
    if let Some(u) = unresolved {
        return Err(IngestError::NeedsOption {
            column: u.source_name,
            reason: u.reason,
        });
    }
    let mut b = RecordBuilder::new(o.assemble);
    let (t0, dt) = place_rows(&rows, o, &mut b)?;
    let (mut record, assemble, build) = b.finish()?;
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
        dt_nominal_s: None,
    };
    Ok((record, stats))
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

/// Feed the rows to the builder with device-like indices and clocks (see the module
/// documentation); returns t₀ in seconds and, for a given rate, the exact sample period.
fn place_rows(
    rows: &[CsvRow],
    o: &IngestOptions,
    b: &mut RecordBuilder,
) -> Result<(f64, Option<f64>), IngestError> {
    if rows.is_empty() {
        return Err(IngestError::NoSamples);
    }
    let timed: Vec<(f64, &CsvRow)> = rows
        .iter()
        .filter_map(|r| r.t_s.filter(|t| t.is_finite()).map(|t| (t, r)))
        .collect();
    let us = |dt_s: f64| (dt_s * 1e6).round() as i64 as u32;
    if timed.len() >= 2 {
        let t0 = timed[0].0;
        let has_idx = timed.iter().all(|(_, r)| r.index.is_some_and(|i| i >= 0.0));
        if has_idx {
            for (t, r) in &timed {
                let idx = r.index.unwrap_or(0.0) as u64 as u32;
                b.push_point(idx, us(t - t0), row_values(r));
            }
        } else {
            let dt = median_step(&timed).ok_or(IngestError::NoTimebase)?;
            for (t, r) in &timed {
                let k = ((t - t0) / dt).round();
                if k < 0.0 {
                    continue; // before the first row: out of order, cannot be placed
                }
                b.push_point(k as u64 as u32, us(t - t0), row_values(r));
            }
        }
        return Ok((t0, None));
    }
    let fs = o.fs_hz.ok_or(IngestError::NoTimebase)?;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(IngestError::BadOption {
            name: "fs_hz",
            value: fs,
        });
    }
    for (k, r) in rows.iter().enumerate() {
        b.push_point(k as u32, us(k as f64 / fs), row_values(r));
    }
    Ok((0.0, Some(1.0 / fs)))
}

/// Median of the positive steps between successive times.
fn median_step(timed: &[(f64, &CsvRow)]) -> Option<f64> {
    let mut steps: Vec<f64> = timed
        .windows(2)
        .map(|w| w[1].0 - w[0].0)
        .filter(|d| *d > 0.0)
        .collect();
    if steps.is_empty() {
        return None;
    }
    steps.sort_by(f64::total_cmp);
    Some(steps[steps.len() / 2])
}

#[cfg(test)]
mod tests;
