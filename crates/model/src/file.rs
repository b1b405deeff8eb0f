//! The model file: one JSON object of schema [`SCHEMA`] (docs/model_file.md), written by
//! `identify --save` and `diagnose --save`, read by `compare`, `simulate` and `params`.
//!
//! **Integrity.** `checksum` is `"fnv1a64:"` and 16 hex digits of the 64-bit FNV-1a hash of the
//! file's canonical content: the object without `checksum`, written compactly with every
//! object's keys sorted and numbers as `serde_json` writes them ([`canonical`]). It detects an
//! edit (by hand, by a tool that rewrites numbers), not a forgery: anyone can recompute it.
//!
//! **Versions.** A file of another `schema` (or none) is refused, never guessed at; a file
//! written by this version loads in later versions of the same schema (the stored file of
//! crates/model/tests/data is read by the tests).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::schema::{ModelError, SCHEMA};
use crate::terms::{Extended, TermSpec};

/// An input or output channel of the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Channel {
    /// The channel's key in the record (`throttle`, `thrust`, ...), or the column's name when
    /// it has no key.
    pub name: String,
    /// The column as named in the file.
    pub column: String,
    /// Its unit (the canonical unit the record holds it in: `throttle 0..1`, `N`, ...).
    pub unit: String,
}

/// Where the model came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// `"identify"` or `"diagnose"`.
    pub command: String,
    /// The file as given.
    pub file: String,
    /// Rows (samples) of the record.
    pub rows: usize,
    /// The options that shaped the model, by flag name (`order`, `esc_us`, ...).
    pub options: BTreeMap<String, Value>,
    /// The propid version that wrote the file.
    pub propid_version: String,
}

/// The linear model about its operating point:
/// `x_{k+1} = A x_k + B (u_k − u₀)`, `y_k = y₀ + C x_k + D (u_k − u₀)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Linear {
    /// `A`, one row per state.
    pub a: Vec<Vec<f64>>,
    /// `B`, one row per state (one column per input).
    pub b: Vec<Vec<f64>>,
    /// `C`, one row per output.
    pub c: Vec<Vec<f64>>,
    /// `D`, one row per output.
    pub d: Vec<Vec<f64>>,
    /// The operating point `u₀`, `y₀` the model was identified about.
    pub operating_point: OperatingPoint,
}

/// The operating point of the linear model (its offsets).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OperatingPoint {
    /// `u₀`, input units.
    pub input: f64,
    /// `y₀`, one per output, output units.
    pub outputs: Vec<f64>,
}

/// The supply voltage the record logged, V.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Supply {
    /// Lowest.
    pub min_v: f64,
    /// Highest.
    pub max_v: f64,
    /// Mean.
    pub mean_v: f64,
}

impl Supply {
    /// Of a logged voltage (non-finite samples skipped; `None` without a finite one).
    pub fn of(v: &[f64]) -> Option<Supply> {
        let fin: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        if fin.is_empty() {
            return None;
        }
        Some(Supply {
            min_v: fin.iter().copied().fold(f64::INFINITY, f64::min),
            max_v: fin.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            mean_v: fin.iter().sum::<f64>() / fin.len() as f64,
        })
    }
}

/// The model file (docs/model_file.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// [`SCHEMA`].
    pub schema: String,
    /// The integrity check (module doc); empty until [`ModelFile::to_text`] fills it in.
    #[serde(default)]
    pub checksum: String,
    /// Where it came from.
    pub provenance: Provenance,
    /// Sample period, s.
    pub dt_s: f64,
    /// The input.
    pub input: Channel,
    /// The outputs, in the order of `C`'s rows.
    pub outputs: Vec<Channel>,
    /// The linear model (`identify`'s; `diagnose`'s linear part about its reference throttle).
    pub linear: Option<Linear>,
    /// `diagnose`'s model (null from `identify`).
    pub extended: Option<Extended>,
    /// `identify`'s `"stand"` as it printed it (null when not identified).
    pub stand: Option<Value>,
    /// `identify`'s `"static_map"` as it printed it (`{}` without levels).
    pub static_map: Value,
    /// The supply voltage the record logged (null without one).
    pub supply: Option<Supply>,
}

/// The canonical text of a JSON value: compact, every object's keys sorted.
pub fn canonical(v: &Value) -> String {
    let mut out = String::new();
    write_canonical(v, &mut out);
    out
}

fn write_canonical(v: &Value, out: &mut String) {
    match v {
        Value::Object(m) => {
            let mut keys: Vec<&String> = m.keys().collect();
            keys.sort();
            out.push('{');
            for (i, k) in keys.into_iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                out.push_str(&Value::String(k.clone()).to_string());
                out.push(':');
                write_canonical(&m[k], out);
            }
            out.push('}');
        }
        Value::Array(a) => {
            out.push('[');
            for (i, x) in a.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                write_canonical(x, out);
            }
            out.push(']');
        }
        other => out.push_str(&other.to_string()),
    }
}

/// 64-bit FNV-1a of `bytes` (Fowler, Noll, Vo: offset basis 0xcbf29ce484222325, prime
/// 0x100000001b3).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The checksum of a file's object `v` (its `checksum` key left out).
pub fn checksum_of(v: &Value) -> String {
    let mut v = v.clone();
    if let Value::Object(m) = &mut v {
        m.remove("checksum");
    }
    format!("fnv1a64:{:016x}", fnv1a64(canonical(&v).as_bytes()))
}

impl ModelFile {
    /// The file's text: pretty JSON with the checksum filled in. The checksum is taken over the
    /// text's own numbers read back, so a reader computes it from the same values.
    pub fn to_text(&self) -> Result<String, ModelError> {
        self.check()?;
        let mut me = self.clone();
        me.checksum = String::new();
        let first = serde_json::to_string(&me).map_err(|e| ModelError::Invalid(e.to_string()))?;
        let mut v: Value =
            serde_json::from_str(&first).map_err(|e| ModelError::Invalid(e.to_string()))?;
        let sum = checksum_of(&v);
        if let Value::Object(m) = &mut v {
            m.insert("checksum".into(), Value::String(sum));
        }
        serde_json::to_string_pretty(&v).map_err(|e| ModelError::Invalid(e.to_string()))
    }

    /// Reads a file's text: its schema first (another is refused whatever else it holds), then
    /// the checksum, then the content and its consistency ([`ModelFile::check`]).
    pub fn from_text(text: &str) -> Result<ModelFile, ModelError> {
        let v: Value =
            serde_json::from_str(text).map_err(|e| ModelError::NotJson(e.to_string()))?;
        let Value::Object(obj) = &v else {
            return Err(ModelError::NotJson("not a JSON object".into()));
        };
        let schema = obj.get("schema").and_then(Value::as_str).unwrap_or("none");
        if schema != SCHEMA {
            return Err(ModelError::Schema {
                found: schema.to_string(),
            });
        }
        let stored = obj
            .get("checksum")
            .and_then(Value::as_str)
            .unwrap_or("none")
            .to_string();
        let computed = checksum_of(&v);
        if stored != computed {
            return Err(ModelError::Tampered { stored, computed });
        }
        let m: ModelFile =
            serde_json::from_value(v).map_err(|e| ModelError::Invalid(e.to_string()))?;
        m.check()?;
        Ok(m)
    }

    /// The content holds together: a positive sample period, at least one output, a linear or
    /// an extended model, the linear model's matrices of consistent sizes and finite, the
    /// extended model with one output.
    pub fn check(&self) -> Result<(), ModelError> {
        let bad = |s: String| Err(ModelError::Invalid(s));
        if !(self.dt_s.is_finite() && self.dt_s > 0.0) {
            return bad(format!(
                "dt_s {} is not a positive sample period",
                self.dt_s
            ));
        }
        if self.outputs.is_empty() {
            return bad("no output".into());
        }
        if self.linear.is_none() && self.extended.is_none() {
            return bad("neither a linear nor an extended model".into());
        }
        if let Some(l) = &self.linear {
            let (n, q) = (l.a.len(), self.outputs.len());
            let rows_ok = |m: &[Vec<f64>], rows: usize, cols: usize| {
                m.len() == rows && m.iter().all(|r| r.len() == cols)
            };
            if !(rows_ok(&l.a, n, n)
                && rows_ok(&l.b, n, 1)
                && rows_ok(&l.c, q, n)
                && rows_ok(&l.d, q, 1)
                && l.operating_point.outputs.len() == q)
            {
                return bad(format!(
                    "linear model: A must be {n}x{n}, B {n}x1, C {q}x{n}, D {q}x1 and one \
                     operating point per output"
                ));
            }
            let all = l.a.iter().chain(&l.b).chain(&l.c).chain(&l.d).flatten();
            let ops = l.operating_point.outputs.iter();
            if !all
                .chain(ops)
                .chain([&l.operating_point.input])
                .all(|x| x.is_finite())
            {
                return bad("linear model: a non-finite entry".into());
            }
        }
        if let Some(e) = &self.extended {
            if self.outputs.len() != 1 {
                return bad("the extended model has one output".into());
            }
            let c = &e.core;
            if ![c.fn_hz, c.zeta, c.gain, c.offset, c.lead, e.u_ref, e.v_ref]
                .iter()
                .all(|x| x.is_finite())
                || c.fn_hz <= 0.0
                || c.zeta <= 0.0
            {
                return bad("extended model: its core is not a finite, positive mode".into());
            }
        }
        Ok(())
    }

    /// Whether simulating the model reads the supply voltage (an extended model's supply term).
    pub fn needs_voltage(&self) -> bool {
        self.extended
            .as_ref()
            .is_some_and(|e| e.terms.iter().any(TermSpec::reads_voltage))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn sample() -> ModelFile {
        ModelFile {
            schema: SCHEMA.into(),
            checksum: String::new(),
            provenance: Provenance {
                command: "identify".into(),
                file: "run.csv".into(),
                rows: 1000,
                options: BTreeMap::from([("order".into(), Value::from(2))]),
                propid_version: "0.1.0".into(),
            },
            dt_s: 0.01,
            input: Channel {
                name: "throttle".into(),
                column: "ESC signal (µs)".into(),
                unit: "throttle 0..1".into(),
            },
            outputs: vec![Channel {
                name: "thrust".into(),
                column: "Thrust (N)".into(),
                unit: "N".into(),
            }],
            linear: Some(Linear {
                a: vec![vec![0.9, 0.1], vec![-0.1, 0.8]],
                b: vec![vec![0.1], vec![0.2]],
                c: vec![vec![1.0, 0.0]],
                d: vec![vec![0.0]],
                operating_point: OperatingPoint {
                    input: 0.5,
                    outputs: vec![3.0],
                },
            }),
            extended: None,
            stand: None,
            static_map: Value::Object(Default::default()),
            supply: None,
        }
    }

    #[test]
    fn a_written_file_reads_back_equal() {
        let m = sample();
        let text = m.to_text().unwrap();
        let back = ModelFile::from_text(&text).unwrap();
        assert_eq!(back.linear, m.linear);
        assert!(back.checksum.starts_with("fnv1a64:"), "{}", back.checksum);
    }

    #[test]
    fn a_changed_number_is_refused_as_tampered() {
        let text = sample().to_text().unwrap();
        let edited = text.replacen("0.9", "0.91", 1);
        assert_ne!(edited, text);
        assert!(matches!(
            ModelFile::from_text(&edited),
            Err(ModelError::Tampered { .. })
        ));
        // Reformatting is no edit: the canonical content is the same.
        let v: Value = serde_json::from_str(&text).unwrap();
        assert!(ModelFile::from_text(&v.to_string()).is_ok());
    }

    #[test]
    fn another_schema_or_none_is_refused_before_anything_else() {
        let text = sample().to_text().unwrap();
        let other = text.replace(SCHEMA, "propid-model/2");
        match ModelFile::from_text(&other) {
            Err(ModelError::Schema { found }) => assert_eq!(found, "propid-model/2"),
            e => panic!("{e:?}"),
        }
        match ModelFile::from_text(r#"{"model": {}}"#) {
            Err(ModelError::Schema { found }) => assert_eq!(found, "none"),
            e => panic!("{e:?}"),
        }
        assert!(matches!(
            ModelFile::from_text("[1, 2]"),
            Err(ModelError::NotJson(_))
        ));
    }

    #[test]
    fn inconsistent_matrices_are_refused() {
        let mut m = sample();
        m.linear.as_mut().unwrap().c = vec![vec![1.0]];
        assert!(matches!(m.to_text(), Err(ModelError::Invalid(_))));
    }

    #[test]
    fn fnv1a_matches_its_published_test_vectors() {
        assert_eq!(fnv1a64(b""), 0xcbf29ce484222325);
        assert_eq!(fnv1a64(b"a"), 0xaf63dc4c8601ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x85944171f73967e8);
    }
}
