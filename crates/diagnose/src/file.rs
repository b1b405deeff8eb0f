//! A loaded file into what the engine works on ([`signals`]): the output NaN where missing, the
//! input and the supply voltage held across gaps, the stand's channels; and the file's
//! `source` fields `diagnose --json` adds ([`FileSource`], [`json`]). The CLI reads the file
//! ([`propid_ingest::load`]) and calls these; the engine's tests call them on bytes in memory.

use propid_ingest::columns_read::ColumnsRead;
use propid_ingest::gaps::{fill_gaps, mark_missing};
use propid_ingest::load::{
    steps_from_response, LoadedFile, NoSteps, Origin, NO_INPUT, STAND_CHANNELS,
};
use propid_numerics::stand_model::fit::Channel as StandChannel;
use propid_wire::record::names;

use crate::stand::StandInput;
use crate::{diagnose_with, DiagnoseError, Diagnosis, Options};

/// The output read when none is named.
pub const DEFAULT_OUTPUT: &str = names::THRUST;

/// The channels read when the file has them: the supply voltage and the stand's.
pub const OPTIONAL: [&str; 5] = [
    names::VOLTAGE,
    STAND_CHANNELS[0].1,
    STAND_CHANNELS[1].1,
    STAND_CHANNELS[2].1,
    STAND_CHANNELS[3].1,
];

/// The signals of a file that diagnose works on.
#[derive(Debug, Clone)]
pub struct Signals {
    /// Sample period, s.
    pub dt_s: f64,
    /// Input (throttle, the chosen column, or the levels of the steps found).
    pub u: Vec<f64>,
    /// Output, NaN where missing.
    pub y: Vec<f64>,
    /// The output's samples interpolated between its readings (empty: every sample a reading;
    /// [`propid_wire::record::Channel::interpolated`]).
    pub interpolated: Vec<bool>,
    /// Supply voltage, if the file has it.
    pub voltage: Option<Vec<f64>>,
    /// What the input is.
    pub input_name: String,
    /// What the output is.
    pub output_name: String,
    /// Whether the input is a stand's command ([`LoadedFile::input_is_a_command`]) read from
    /// the file (not steps found from the response).
    pub input_is_a_command: bool,
    /// The stand's channels the file has (`rpm`, `thrust`, `torque`, `current`: key, samples
    /// with NaN where missing, the samples interpolated between readings), for the stand
    /// baseline; empty without a command.
    pub stand: Vec<(&'static str, Vec<f64>, Vec<bool>)>,
    /// The key of the output among `stand` (`None`: the output is none of them).
    pub stand_output: Option<&'static str>,
    /// What the file's columns were read as ([`FileSource`]).
    pub file: FileSource,
}

/// What `diagnose --json` adds to its `source` about the file, with the names `identify`
/// publishes: the findings' parameters are in the canonical units these say (a thrust column in
/// gram-force gives a sinusoid's amplitude and a drift's rate in newtons).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct FileSource {
    /// `"csv"` or `"tsp1"`.
    pub format: &'static str,
    /// The input column as named in the file, or `"steps found from the response"`.
    pub input: String,
    /// The output column as named in the file.
    pub output: String,
    /// CSV files: the columns' units and factors and the command's scale.
    #[serde(flatten)]
    pub read: ColumnsRead,
    /// Sample rate used, Hz.
    pub rate_hz: f64,
}

impl FileSource {
    /// Of a loaded file.
    fn of(file: &LoadedFile, input: &str, output: &str) -> FileSource {
        let rate_hz = 1.0 / file.record.dt_s;
        match &file.origin {
            Origin::Tsp1(_) => FileSource {
                format: "tsp1",
                input: input.to_string(),
                output: output.to_string(),
                rate_hz,
                ..FileSource::default()
            },
            Origin::Csv(src) => FileSource {
                format: "csv",
                input: src.input.clone().unwrap_or_else(|| input.to_string()),
                output: src
                    .outputs
                    .first()
                    .cloned()
                    .unwrap_or_else(|| output.into()),
                read: ColumnsRead::of(Some(src)),
                rate_hz: src.rate_hz,
            },
        }
    }
}

/// The diagnosis as `--json` prints it: [`Diagnosis`] with the file's [`FileSource`] fields
/// added to its `source`.
pub fn json(d: &Diagnosis, file: &FileSource) -> Result<serde_json::Value, serde_json::Error> {
    let mut v = serde_json::to_value(d)?;
    if let (Some(source), serde_json::Value::Object(extra)) = (
        v.get_mut("source").and_then(|s| s.as_object_mut()),
        serde_json::to_value(file)?,
    ) {
        source.extend(extra);
    }
    Ok(v)
}

impl Signals {
    /// These signals with the stand channel `key` replaced by `f` of it (and the output with
    /// it when the output is that channel): one sensor changed, every other channel kept (an
    /// effect hidden in one channel of a log, `crates/diagnose/examples/stand_lag_table.rs`).
    pub fn map_channel(&self, key: &str, f: impl Fn(&[f64]) -> Vec<f64>) -> Signals {
        let mut out = self.clone();
        if self.stand_output == Some(key) {
            out.y = f(&self.y);
        }
        for (k, y, _) in out.stand.iter_mut() {
            if *k == key {
                *y = f(y);
            }
        }
        out
    }

    /// [`crate::diagnose`] of these signals (with what the input is:
    /// [`Options::input_is_a_command`]).
    pub fn diagnose(&self, opts: &Options) -> Result<Diagnosis, DiagnoseError> {
        let opts = Options {
            input_is_a_command: self.input_is_a_command,
            ..*opts
        };
        let stand = StandInput {
            channels: self
                .stand
                .iter()
                .filter_map(|(key, y, flags)| {
                    Some(StandChannel {
                        key,
                        quantity: crate::stand::quantity(key)?,
                        y,
                        interpolated: flags,
                    })
                })
                .collect(),
            output: self.stand_output,
        };
        diagnose_with(
            self.dt_s,
            &self.u,
            &self.y,
            &self.interpolated,
            self.voltage.as_deref(),
            (!stand.channels.is_empty()).then_some(&stand),
            &opts,
        )
    }
}

/// Diagnose's step after the shared load ([`propid_ingest::load`], asked for [`OPTIONAL`]):
/// the output NaN at every sample marked missing; the input (without an input column: the
/// level sequence of the steps found in the response) and the voltage held across gaps
/// ([`fill_gaps`]); the voltage dropped when it has no finite sample. An input named
/// (`named_input`, as `--input NAME`) that is not a command keeps that name (a shaker's
/// `force_N` is read as the record's force channel, `thrust_N`, but is no thrust). Without an
/// input column and no step in the response: [`NoSteps`].
pub fn signals(file: &LoadedFile, named_input: Option<&str>) -> Result<Signals, NoSteps> {
    let rec = &file.record;
    let output_name = file.outputs.first().cloned().unwrap_or_default();
    let mut y = file.data(&output_name);
    mark_missing(&mut y, &rec.missing);
    let interpolated = rec
        .channel(&output_name)
        .map(|c| c.interpolated.clone())
        .unwrap_or_default();
    let voltage = file
        .optional
        .iter()
        .find(|n| n.as_str() == names::VOLTAGE)
        .map(|n| fill_gaps(file.data(n)))
        .filter(|v| v.iter().all(|x| x.is_finite()));
    // The stand's channels, when the input is a command read from the file.
    let commanded = file.input.is_some() && file.input_is_a_command();
    let stand: Vec<(&'static str, Vec<f64>, Vec<bool>)> = STAND_CHANNELS
        .iter()
        .filter(|_| commanded)
        .filter_map(|&(key, channel, _)| {
            let c = rec.channel(channel)?;
            let mut y = c.data.clone();
            mark_missing(&mut y, &rec.missing);
            Some((key, y, c.interpolated.clone()))
        })
        .collect();
    let stand_output = STAND_CHANNELS
        .iter()
        .find(|c| c.1 == output_name && stand.iter().any(|s| s.0 == c.0))
        .map(|c| c.0);
    let (u, input_name) = match &file.input {
        Some(n) => (file.data(n), n.clone()),
        None => {
            let f = steps_from_response(&y)?;
            (f.input, "steps found from the response".to_string())
        }
    };
    let source = FileSource::of(file, &input_name, &output_name);
    let input_name = match named_input.filter(|n| *n != NO_INPUT) {
        Some(name) if input_name != names::THROTTLE => name.to_string(),
        _ => input_name,
    };
    Ok(Signals {
        dt_s: rec.dt_s,
        u: fill_gaps(u),
        y,
        interpolated,
        voltage,
        file: source,
        input_name,
        output_name,
        input_is_a_command: file.input_is_a_command(),
        stand,
        stand_output,
    })
}
