//! `identify --save FILE`: the identified model as a model file (`propid_model`), and
//! `--json`'s `params` from the same content.

use serde_json::{json, Map, Value};

use super::load::Loaded;
use super::summary::Output;
use super::Args;
use crate::cli::model_file::{self as mf, channel, unit_of};
use crate::cli::CliError;
use propid_model::file::{ModelFile, OperatingPoint};
use propid_model::params::{self, Record};
use propid_model::SCHEMA;
use propid_numerics::output_error::OeModel;
use propid_numerics::ModelReport;
use propid_wire::record::names;

/// The model file of an identification.
pub fn model_file(
    args: &Args,
    loaded: &Loaded,
    model: &ModelReport,
    out: &Output,
    refined: Option<&OeModel>,
) -> Result<ModelFile, CliError> {
    let s = &loaded.source;
    let units = s.read.units.as_ref();
    let unit = |key: &str, col: &str| {
        let raw = units
            .and_then(|u| u.values().find(|c| c.column == col))
            .map_or("", |c| c.unit.as_str());
        unit_of(key, raw)
    };
    let input_key = args
        .read
        .input
        .clone()
        .unwrap_or_else(|| names::THROTTLE.to_string());
    let outputs = s
        .outputs
        .iter()
        .enumerate()
        .map(|(i, col)| {
            let key = args
                .read
                .output
                .get(i)
                .cloned()
                .unwrap_or_else(|| names::THRUST.to_string());
            channel(&key, col, &unit(&key, col))
        })
        .collect();
    // A refined model carries its own operating point (fitted offsets, an integrator's input
    // offset); a realisation is about the record's means.
    let op = match refined {
        Some(m) => OperatingPoint {
            input: m.u0,
            outputs: m.y0.clone(),
        },
        None => OperatingPoint {
            input: mf::mean_of(&loaded.input, &loaded.missing),
            outputs: loaded
                .outputs
                .iter()
                .map(|y| mf::mean_of(y, &loaded.missing))
                .collect(),
        },
    };
    let options = json!({
        "order": args.order,
        "svd": format!("{:?}", args.svd).to_lowercase(),
        "hankel": format!("{:?}", args.hankel),
        "fs": args.read.fs,
        "columns": args.read.columns,
        "esc_us": args.read.esc_us,
        "input_range": s.read.input_range,
        "input_range_from": s.read.input_range_from,
        "poles": args.read.poles,
    });
    let to_value = |v: Result<Value, serde_json::Error>| v.map_err(CliError::Json);
    Ok(ModelFile {
        schema: SCHEMA.into(),
        checksum: String::new(),
        provenance: mf::provenance("identify", &args.read.file, s.samples, options),
        dt_s: model.dt_s,
        input: channel(&input_key, &s.input, &unit(&input_key, &s.input)),
        outputs,
        linear: Some(mf::linear(model, op)),
        extended: None,
        stand: out
            .stand
            .map(serde_json::to_value)
            .map(to_value)
            .transpose()?,
        static_map: to_value(serde_json::to_value(out.static_map))?,
        supply: mf::supply(loaded.voltage.as_deref()),
    })
}

/// Every target's parameters from a model file's content (`--json`'s `params`).
pub fn params(m: &ModelFile) -> Map<String, Value> {
    let rec = Record {
        stand: m.stand.as_ref(),
        static_map: &m.static_map,
        supply: m.supply.as_ref(),
    };
    params::all(&rec, &mf::options(Some(m), None))
}
