//! A file's bytes in memory read as `propid diagnose` reads a file (the loader asked for
//! [`OPTIONAL`], then [`signals`]), diagnosed as the command does (the data choose the baseline),
//! and the object its `--json` prints.

use propid_diagnose::file::{json, signals, DEFAULT_OUTPUT, OPTIONAL};
use propid_diagnose::Options;
use propid_ingest::load::{load_bytes, Request};
use serde_json::Value;

/// How the file is read: `--input`, `--output`, `--fs`.
#[derive(Debug, Default, Clone, Copy)]
pub struct How<'a> {
    pub input: Option<&'a str>,
    pub output: Option<&'a str>,
    pub fs_hz: Option<f64>,
}

/// `propid diagnose --json` of a file named `name` holding `bytes`, read as `how` says.
pub fn diagnose_json(name: &str, bytes: &[u8], how: How) -> Value {
    let outputs = [how.output.unwrap_or(DEFAULT_OUTPUT).to_string()];
    let req = Request {
        input: how.input,
        outputs: &outputs,
        optional: &OPTIONAL,
        fs_hz: how.fs_hz,
        ..Request::default()
    };
    let file = load_bytes(name.into(), bytes, &req).unwrap_or_else(|e| panic!("{e}"));
    let s = signals(&file, how.input).unwrap_or_else(|e| panic!("{e}"));
    let d = s
        .diagnose(&Options::default())
        .unwrap_or_else(|e| panic!("{e}"));
    json(&d, &s.file).expect("a JSON object")
}
