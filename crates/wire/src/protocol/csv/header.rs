//! A header line mapped onto canonical quantities ([`HeaderMap`]), and data rows read through
//! it into canonical units ([`CsvRow`]).
//!
//! The header's names are looked up in the one alias table ([`columns`](super::columns));
//! unknown columns are ignored, a known one that needs an option (ESC range, motor poles) is
//! reported as unresolved. Without a header, §6's default order applies
//! ([`HeaderMap::default_order`]), named by the one name table ([`Quantity::name`]).

use serde::Serialize;

use super::columns::{self, ColumnSpec, ConvError, ConvOptions, Quantity, DEFAULT_ORDER};

/// One mapped column of a header.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MappedColumn {
    /// Field position in the line.
    pub index: usize,
    /// The name as written in the source.
    pub source_name: String,
    /// Quantity and unit.
    pub spec: ColumnSpec,
    /// Conversion to canonical units.
    #[serde(skip)]
    pub conv: columns::Affine,
}

/// A known column that cannot be used for lack of an option.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnresolvedColumn {
    /// Field position.
    pub index: usize,
    /// The name as written.
    pub source_name: String,
    /// Why.
    #[serde(serialize_with = "ser_display")]
    pub reason: ConvError,
}

fn ser_display<S: serde::Serializer>(e: &ConvError, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(e)
}

/// Header → canonical channel mapping. At most one column per quantity: the first one that
/// maps (for instance RCbenchmark's electrical speed before its optical speed).
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct HeaderMap {
    /// Mapped columns, in field order.
    pub columns: Vec<MappedColumn>,
    /// Known columns that need an option to be used.
    pub unresolved: Vec<UnresolvedColumn>,
    /// Number of fields in the header line.
    pub field_count: usize,
}

impl HeaderMap {
    /// Map the fields of a header line.
    pub fn from_fields<S: AsRef<str>>(
        fields: impl IntoIterator<Item = S>,
        o: &ConvOptions,
    ) -> Self {
        let mut map = HeaderMap::default();
        for (index, name) in fields.into_iter().enumerate() {
            map.field_count = index + 1;
            let name = name.as_ref();
            if let Some(spec) = columns::lookup(name) {
                map.add(index, name.trim().trim_start_matches('\u{feff}'), spec, o);
            }
        }
        map
    }

    /// The header-less default order for lines of `field_count` fields.
    pub fn default_order(field_count: usize, o: &ConvOptions) -> Self {
        let mut map = HeaderMap {
            field_count,
            ..Default::default()
        };
        for (index, spec) in DEFAULT_ORDER.iter().enumerate().take(field_count) {
            map.add(index, spec.quantity.name(), *spec, o);
        }
        map
    }

    fn add(&mut self, index: usize, name: &str, spec: ColumnSpec, o: &ConvOptions) {
        if self.column(spec.quantity).is_some() {
            return;
        }
        match spec.conversion(o) {
            Ok(conv) => self.columns.push(MappedColumn {
                index,
                source_name: name.to_string(),
                spec,
                conv,
            }),
            Err(reason) => self.unresolved.push(UnresolvedColumn {
                index,
                source_name: name.to_string(),
                reason,
            }),
        }
    }

    /// The column of a quantity, if mapped.
    pub fn column(&self, q: Quantity) -> Option<&MappedColumn> {
        self.columns.iter().find(|c| c.spec.quantity == q)
    }

    /// Parse a data line's fields into a row. Text in a mapped field is an error.
    pub fn row<S: AsRef<str>>(
        &self,
        fields: impl IntoIterator<Item = S>,
    ) -> Result<CsvRow, RowError> {
        let mut row = CsvRow::default();
        // `columns` is in field order, so one pass pairs fields and columns.
        let mut cols = self.columns.iter().peekable();
        for (i, f) in fields.into_iter().enumerate() {
            let Some(col) = cols.next_if(|c| c.index == i) else {
                continue;
            };
            let f = f.as_ref().trim();
            if f.is_empty() {
                continue;
            }
            let raw: f64 = f.parse().map_err(|_| RowError::NotANumber(i))?;
            row.set(col.spec.quantity, col.conv.apply(raw));
        }
        Ok(row)
    }
}

/// Why a data line is not a row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RowError {
    /// The mapped field at this position is not a number.
    #[error("field {0} is not a number")]
    NotANumber(usize),
}

/// One data row in canonical units; `None` = column absent or field empty.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CsvRow {
    /// Time, s.
    pub t_s: Option<f64>,
    /// Sample index.
    pub index: Option<f64>,
    /// Throttle fraction 0..1.
    pub throttle: Option<f64>,
    /// Thrust, N.
    pub thrust_n: Option<f64>,
    /// Torque, N·m.
    pub torque_nm: Option<f64>,
    /// Rotor speed, rev/min.
    pub rpm: Option<f64>,
    /// Voltage, V.
    pub voltage_v: Option<f64>,
    /// Current, A.
    pub current_a: Option<f64>,
}

impl CsvRow {
    /// The value of a quantity.
    pub fn get(&self, q: Quantity) -> Option<f64> {
        match q {
            Quantity::Time => self.t_s,
            Quantity::Index => self.index,
            Quantity::Throttle => self.throttle,
            Quantity::Thrust => self.thrust_n,
            Quantity::Torque => self.torque_nm,
            Quantity::Rpm => self.rpm,
            Quantity::Voltage => self.voltage_v,
            Quantity::Current => self.current_a,
        }
    }

    fn set(&mut self, q: Quantity, v: f64) {
        let slot = match q {
            Quantity::Time => &mut self.t_s,
            Quantity::Index => &mut self.index,
            Quantity::Throttle => &mut self.throttle,
            Quantity::Thrust => &mut self.thrust_n,
            Quantity::Torque => &mut self.torque_nm,
            Quantity::Rpm => &mut self.rpm,
            Quantity::Voltage => &mut self.voltage_v,
            Quantity::Current => &mut self.current_a,
        };
        *slot = Some(v);
    }
}
