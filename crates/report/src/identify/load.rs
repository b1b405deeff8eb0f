//! FILE → input, outputs and a description of where they came from.

use serde::Serialize;

use crate::columns_read::ColumnsRead;
use propid_ingest::csv_file::CsvSource;
use propid_ingest::load::{steps_from_response, LoadedFile, NoSteps, Origin};
use propid_ingest::steps::FoundStep;
use propid_ingest::window::RecordWindow;
use propid_ingest::IngestStats;
use propid_numerics::outliers::{find_outliers, isolated_outliers_of_readings, OutlierScratch};
use propid_numerics::segment::SegmentRules;
use propid_numerics::startup::start_transient;
use propid_wire::protocol::detect::WireFormat;
use propid_wire::record::names;

/// What `identify` works on.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// Sample period, s.
    pub dt_s: f64,
    /// The input (throttle, a chosen column, or the levels of the steps found).
    pub input: Vec<f64>,
    /// The outputs.
    pub outputs: Vec<Vec<f64>>,
    /// Per output, the samples interpolated between its readings (empty: every sample a
    /// reading; [`propid_wire::record::Channel::interpolated`]).
    pub interpolated: Vec<Vec<bool>>,
    /// Missing samples.
    pub missing: Vec<bool>,
    /// Device pulse starts (TSP/1 events), if any.
    pub pulse_starts: Option<Vec<usize>>,
    /// Whether `input` is a command read from the file (not steps found from the response).
    pub commanded: bool,
    /// Whether `input` is a stand's command ([`LoadedFile::input_is_a_command`]).
    pub input_is_a_command: bool,
    /// The static map's channels the file has: key, unit, samples (NaN = not measured).
    pub stand: Vec<(&'static str, &'static str, Vec<f64>)>,
    /// Per channel of `stand`, the samples interpolated between its readings (empty: every
    /// sample a reading; [`propid_wire::record::Channel::interpolated`]).
    pub stand_interpolated: Vec<Vec<bool>>,
    /// The supply voltage when the file has it (the stand model's speed map).
    pub voltage: Option<Vec<f64>>,
    /// Description for the output.
    pub source: Source,
}

impl Loaded {
    /// The segmentation's rules for this record: the one set, at its rate for a stand's
    /// command ([`SegmentRules::at_rate`]: a pulse at most a third of a second long too), by
    /// the sample count alone for a signal in its own units
    /// ([`LoadedFile::input_is_a_command`]).
    pub fn segment_rules(&self) -> SegmentRules {
        SegmentRules::for_record(self.dt_s, self.input_is_a_command)
    }
}

/// `"source"` in the JSON output.
#[derive(Debug, Clone, Serialize)]
pub struct Source {
    /// The file as given.
    pub file: String,
    /// `"csv"` or `"tsp1"`.
    pub format: &'static str,
    /// The input column, or `"steps found from the response"`.
    pub input: String,
    /// The output columns.
    pub outputs: Vec<String>,
    /// CSV files: the columns' units and factors and the command's scale (`units`,
    /// `input_range`, `input_range_from`).
    #[serde(flatten)]
    pub read: ColumnsRead,
    /// Sample rate used, Hz (a recording's: measured from the device clock, clock jumps left
    /// out).
    pub rate_hz: f64,
    /// The rate the recording's HELLO claims, Hz (TSP/1 recordings with a HELLO), printed
    /// beside the measured one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nominal_rate_hz: Option<f64>,
    /// Samples in the record.
    pub samples: usize,
    /// The span of a binary recording longer than the identification window that the record
    /// holds, with the file's length (`propid_ingest::window`); absent when it holds all.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window: Option<RecordWindow>,
    /// Samples marked missing by the file (lost, empty cells).
    pub missing: usize,
    /// Isolated outlier samples of the outputs, left out (marked missing, not counted in
    /// `missing`; [`propid_numerics::outliers`]).
    pub outliers: usize,
    /// Samples at the record's start left out as a start-up transient (the output settling
    /// under the first command level; marked missing, not counted in `missing`;
    /// [`propid_numerics::startup`]); 0 when none.
    pub start_up_transient: usize,
    /// `"pulse"` or `"okid"` (filled in after identification).
    pub path: &'static str,
    /// TSP/1 decoding counters (binary recordings).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tsp1: Option<IngestStats>,
    /// CSV details (columns, time base, jitter, skipped rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub csv: Option<CsvSource>,
    /// Steps found from the response (when the file has no input column).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<Vec<StepOut>>,
    /// The OKID regression (when that path was taken).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub okid: Option<propid_numerics::identify::OkidSummary>,
}

/// A step found from the response, with its time.
#[derive(Debug, Clone, Serialize)]
pub struct StepOut {
    /// Sample index of the command change.
    pub sample: usize,
    /// Its time, s.
    pub t_s: f64,
    /// Level before, output units.
    pub from: f64,
    /// Level after, output units.
    pub to: f64,
}

/// The static map's key of an identified output that is none of [`STAND_CHANNELS`] (its unit
/// the column's own, `?`).
pub const OUTPUT_KEY: &str = "output";

pub use propid_ingest::load::STAND_CHANNELS;

/// The channels read when the file has them: the static map's, and the supply voltage.
pub const OPTIONAL: [&str; 5] = [
    STAND_CHANNELS[0].1,
    STAND_CHANNELS[1].1,
    STAND_CHANNELS[2].1,
    STAND_CHANNELS[3].1,
    names::VOLTAGE,
];

/// Why identify has no input: the file has no input column and no step was found in the
/// response.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{file}: {cause}")]
pub struct NoInput {
    /// The file as given.
    pub file: String,
    /// Why no step was found.
    pub cause: NoSteps,
}

/// What identify keeps of a file the shared loader read (with [`OPTIONAL`] asked for): the
/// missing mask, device pulse starts, the JSON `"source"`, with the input found from the
/// response's steps with `--input none`.
pub fn load(file: LoadedFile) -> Result<Loaded, NoInput> {
    let rec = &file.record;
    let outputs: Vec<Vec<f64>> = file.outputs.iter().map(|n| file.data(n)).collect();
    let interpolated: Vec<Vec<bool>> = file
        .outputs
        .iter()
        .map(|n| {
            rec.channel(n)
                .map(|c| c.interpolated.clone())
                .unwrap_or_default()
        })
        .collect();
    let (input, input_name, steps) = match &file.input {
        Some(n) => {
            let label = match &file.origin {
                Origin::Csv(src) => src.input.clone().unwrap_or_else(|| n.clone()),
                Origin::Tsp1(_) => n.clone(),
            };
            (file.data(n), label, None)
        }
        None => {
            let y = outputs.first().map_or(&[][..], Vec::as_slice);
            let f = steps_from_response(y).map_err(|cause| NoInput {
                file: file.name.clone(),
                cause,
            })?;
            let steps = f.steps.iter().map(|s| step_out(s, rec.t0_s, rec.dt_s));
            let label = "steps found from the response".to_string();
            (f.input, label, Some(steps.collect()))
        }
    };
    // A CSV stream's pulses come from its throttle column, as on the live CSV link (its
    // IMPULSE_START lines carry a time, not the sample the excursion shows in).
    let csv_stream = matches!(&file.origin, Origin::Tsp1(s) if s.format == WireFormat::Csv);
    let starts: Vec<usize> = if csv_stream {
        Vec::new()
    } else {
        rec.impulse_starts().collect()
    };
    let commanded = file.input.is_some();
    let input_is_a_command = file.input_is_a_command();
    let mut stand: Vec<(&'static str, &'static str, Vec<f64>)> = STAND_CHANNELS
        .iter()
        .filter(|c| rec.channel(c.1).is_some())
        .map(|&(key, channel, unit)| (key, unit, file.data(channel)))
        .collect();
    let mut stand_interpolated: Vec<Vec<bool>> = STAND_CHANNELS
        .iter()
        .filter_map(|c| rec.channel(c.1))
        .map(|c| c.interpolated.clone())
        .collect();
    // An identified output that is none of them (a force in ADC counts, a benchmark's level)
    // has its map too, under `output`, in the column's own unit.
    if let Some(first) = file.outputs.first() {
        if !STAND_CHANNELS.iter().any(|c| c.1 == first) {
            stand.push((OUTPUT_KEY, "?", file.data(first)));
            stand_interpolated.push(Vec::new());
        }
    }
    let (format, output_names, rate_hz, mut tsp1, csv) = match file.origin {
        Origin::Tsp1(stats) => (
            "tsp1",
            file.outputs.clone(),
            1.0 / rec.dt_s,
            Some(*stats),
            None,
        ),
        Origin::Csv(src) => ("csv", src.outputs.clone(), src.rate_hz, None, Some(*src)),
    };
    let read = ColumnsRead::of(csv.as_ref());
    let window = tsp1.as_mut().and_then(|s| s.window.take());
    let voltage = rec.channel(names::VOLTAGE).map(|c| c.data.clone());
    Ok(Loaded {
        dt_s: rec.dt_s,
        input,
        outputs,
        interpolated,
        missing: rec.missing.clone(),
        pulse_starts: (!starts.is_empty()).then_some(starts),
        commanded,
        input_is_a_command,
        stand,
        stand_interpolated,
        voltage,
        source: Source {
            file: file.name,
            format,
            input: input_name,
            outputs: output_names,
            read,
            rate_hz,
            nominal_rate_hz: tsp1
                .as_ref()
                .and_then(|s| s.dt_nominal_s)
                .map(|dt| 1.0 / dt),
            samples: rec.len(),
            window,
            missing: rec.missing_count(),
            outliers: 0,
            start_up_transient: 0,
            path: "",
            tsp1,
            csv,
            steps,
            okid: None,
        },
    })
}

/// Leaves out the isolated outlier samples of every output ([`propid_numerics::outliers`],
/// the command's changes guarded when the input is a command): each is marked missing and
/// NaN in the outputs and the stand's channels, never replaced. Returns how many samples.
pub fn leave_out_outliers(loaded: &mut Loaded) -> usize {
    let command: &[f64] = if loaded.commanded { &loaded.input } else { &[] };
    let mut flagged = vec![false; loaded.missing.len().max(loaded.input.len())];
    let mut scratch = OutlierScratch::with_capacity(flagged.len());
    for (i, y) in loaded.outputs.iter().enumerate() {
        let marks = loaded.interpolated.get(i).map_or(&[][..], |m| &m[..]);
        let found: Vec<usize> = if marks.contains(&true) {
            isolated_outliers_of_readings(y, &loaded.missing, command, marks)
        } else {
            find_outliers(y, &loaded.missing, command, &mut scratch).to_vec()
        };
        for k in found {
            if let Some(f) = flagged.get_mut(k) {
                *f = true;
            }
        }
    }
    let count = flagged.iter().filter(|&&f| f).count();
    let ks: Vec<usize> = (0..flagged.len()).filter(|&k| flagged[k]).collect();
    leave_out(loaded, &ks);
    loaded.source.outliers = count;
    count
}

/// Leaves out a start-up transient ([`propid_numerics::startup`], judged on every output under
/// the input's first level; the longest found): its samples are marked missing and NaN in the
/// outputs and the stand's channels, never corrected. Returns how many samples (from the
/// record's start).
pub fn leave_out_start_transient(loaded: &mut Loaded) -> usize {
    let rules = loaded.segment_rules();
    let end = loaded
        .outputs
        .iter()
        .filter_map(|y| start_transient(y, &loaded.missing, &loaded.input, &rules))
        .map(|t| t.end)
        .max()
        .unwrap_or(0);
    let ks: Vec<usize> = (0..end).collect();
    leave_out(loaded, &ks);
    loaded.source.start_up_transient = end;
    end
}

/// Marks samples `ks` missing, NaN in the outputs and the stand's channels.
fn leave_out(loaded: &mut Loaded, ks: &[usize]) {
    let Some(&last) = ks.iter().max() else {
        return;
    };
    if loaded.missing.len() <= last {
        loaded.missing.resize(last + 1, false);
    }
    for &k in ks {
        loaded.missing[k] = true;
        let channels = loaded.outputs.iter_mut().map(Vec::as_mut_slice);
        let stand = loaded.stand.iter_mut().map(|(_, _, y)| y.as_mut_slice());
        for y in channels.chain(stand) {
            if let Some(v) = y.get_mut(k) {
                *v = f64::NAN;
            }
        }
    }
}

fn step_out(s: &FoundStep, t0: f64, dt: f64) -> StepOut {
    StepOut {
        sample: s.sample,
        t_s: t0 + s.sample as f64 * dt,
        from: s.from,
        to: s.to,
    }
}
