//! serde helpers that write non-finite numbers (NaN, ±inf) as JSON `null` and read `null` back
//! as NaN, so every report is valid JSON (`serde_json` refuses NaN otherwise).
//!
//! Use with `#[serde(with = "crate::nullable::num")]` (and `vec`, `pairs`, `mat`).

fn fin(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

fn unfin(x: Option<f64>) -> f64 {
    x.unwrap_or(f64::NAN)
}

/// One number.
pub mod num {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes `null` for a non-finite value.
    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        match super::fin(*x) {
            Some(v) => s.serialize_f64(v),
            None => s.serialize_none(),
        }
    }

    /// Reads `null` as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(super::unfin(Option::<f64>::deserialize(d)?))
    }
}

/// A list of numbers.
pub mod vec {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes `null` for each non-finite value.
    pub fn serialize<S: Serializer>(x: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(x.iter().map(|v| super::fin(*v)))
    }

    /// Reads `null` entries as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let v = Vec::<Option<f64>>::deserialize(d)?;
        Ok(v.into_iter().map(super::unfin).collect())
    }
}

/// A list of `[re, im]` pairs.
pub mod pairs {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes `null` for each non-finite component.
    pub fn serialize<S: Serializer>(x: &[[f64; 2]], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(x.iter().map(|p| [super::fin(p[0]), super::fin(p[1])]))
    }

    /// Reads `null` components as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
        let v = Vec::<[Option<f64>; 2]>::deserialize(d)?;
        Ok(v.into_iter()
            .map(|p| [super::unfin(p[0]), super::unfin(p[1])])
            .collect())
    }
}

/// A matrix as row-major nested lists.
pub mod mat {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes `null` for each non-finite entry.
    pub fn serialize<S: Serializer>(x: &[Vec<f64>], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(
            x.iter()
                .map(|row| row.iter().map(|v| super::fin(*v)).collect::<Vec<_>>()),
        )
    }

    /// Reads `null` entries as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Vec<f64>>, D::Error> {
        let v = Vec::<Vec<Option<f64>>>::deserialize(d)?;
        Ok(v.into_iter()
            .map(|r| r.into_iter().map(super::unfin).collect())
            .collect())
    }
}
