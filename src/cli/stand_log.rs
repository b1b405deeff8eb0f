//! A stand's log for the calibrated simulation (`diagnose --sim-config`, `sim
//! --replay-command`): the command and every stand channel, read as `identify` reads them; the
//! stand model fitted on it; the simulated stand's rows written in the log's columns and units,
//! and scored against it. The mapping and the replay are `propid_sim::calibrate`'s.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::load::{self as shared, LoadedFile, Origin, Request};
use super::CliError;
use propid_diagnose::folds::fit_percent;
use propid_numerics::segment::SegmentRules;
use propid_numerics::stand_model::fit::{fit, Channel, FitInput, StandFit};
use propid_numerics::stand_model::{simulate, Quantity};
use propid_sim::calibrate::{self, Calibrated, LogFacts};
use propid_sim::plant::{Measurement, PlantConfig};
use propid_wire::record::names;

/// The stand's channels: key, the record's channel, what it measures.
const CHANNELS: [(&str, &str, Quantity); 4] = [
    ("thrust", names::THRUST, Quantity::Thrust),
    ("torque", names::TORQUE, Quantity::Torque),
    ("rpm", names::RPM, Quantity::Speed),
    ("current", names::CURRENT, Quantity::Current),
];

const OPTIONAL: [&str; 5] = [
    names::THRUST,
    names::TORQUE,
    names::RPM,
    names::CURRENT,
    names::VOLTAGE,
];

/// One stand channel of the log.
pub struct LogChannel {
    /// `thrust`, `torque`, `rpm`, `current`.
    pub key: &'static str,
    /// What it measures.
    pub quantity: Quantity,
    /// Samples, canonical units (NaN: missing).
    pub data: Vec<f64>,
    /// Rows a reader interpolated between readings (empty: every row a reading).
    pub interpolated: Vec<bool>,
}

/// A stand's log, read.
pub struct StandLog {
    /// The file as read.
    pub file: LoadedFile,
    /// The command, throttle 0..1.
    pub command: Vec<f64>,
    /// The supply voltage, V.
    pub voltage: Option<Vec<f64>>,
    /// The stand channels it has.
    pub channels: Vec<LogChannel>,
}

/// One channel of a simulation: key and rows.
pub type Simulated = Vec<(&'static str, Vec<f64>)>;

/// Reads `path` as `req` asks (its optional channels: the stand's and the voltage).
pub fn read(path: &Path, req: &Request) -> Result<StandLog, CliError> {
    let req = Request {
        optional: &OPTIONAL,
        ..req.clone()
    };
    let file = shared::load(path, &req)?;
    let command = file
        .input
        .as_deref()
        .map(|n| file.data(n))
        .unwrap_or_default();
    let channels = CHANNELS
        .iter()
        .filter_map(|&(key, name, quantity)| {
            let c = file.record.channel(name)?;
            Some(LogChannel {
                key,
                quantity,
                data: c.data.clone(),
                interpolated: c.interpolated.clone(),
            })
        })
        .collect();
    let voltage = file.record.channel(names::VOLTAGE).map(|c| c.data.clone());
    Ok(StandLog {
        file,
        command,
        voltage,
        channels,
    })
}

impl StandLog {
    /// Row period, s.
    pub fn dt_s(&self) -> f64 {
        self.file.record.dt_s
    }

    /// The stand model fitted on every channel (as `identify`'s `stand`).
    pub fn fit(&self) -> Result<StandFit, CliError> {
        let channels: Vec<Channel<'_>> = self
            .channels
            .iter()
            .map(|c| Channel {
                key: c.key,
                quantity: c.quantity,
                y: &c.data,
                interpolated: &c.interpolated,
            })
            .collect();
        Ok(fit(&FitInput {
            dt_s: self.dt_s(),
            command: &self.command,
            voltage: self.voltage.as_deref(),
            channels: &channels,
            rules: SegmentRules::for_record(self.dt_s(), true),
        })?)
    }

    fn channel(&self, q: Quantity) -> Option<&LogChannel> {
        self.channels.iter().find(|c| c.quantity == q)
    }

    /// `fit` as a `propid sim` configuration, and the fit's own score on each channel.
    pub fn calibrate(&self, fit: &StandFit) -> (Calibrated, BTreeMap<String, f64>) {
        let dt = self.dt_s();
        let current = self.channel(Quantity::Current).map(|c| c.data.as_slice());
        let thrust_noise_n = self.channel(Quantity::Thrust).map_or(0.0, |c| {
            let rows: Vec<usize> = readings(c).collect();
            propid_numerics::stand_model::fit::reading_noise(&c.data, &rows)
        });
        let facts = LogFacts {
            dt_s: dt,
            supply: self
                .voltage
                .as_deref()
                .and_then(|v| calibrate::fit_supply(dt, v, current)),
            thrust_noise_n,
            command_low: self
                .command
                .iter()
                .copied()
                .filter(|u| u.is_finite())
                .fold(f64::INFINITY, f64::min),
        };
        let sensors = calibrate::fitted_sensors(fit);
        let pairs: Vec<_> = sensors.iter().map(|(_, q, s)| (*q, *s)).collect();
        let model = simulate(
            &fit.params,
            dt,
            &self.command,
            self.voltage.as_deref(),
            &pairs,
        );
        let own: Simulated = sensors
            .iter()
            .zip(model)
            .map(|((key, ..), y)| (*key, y))
            .collect();
        (calibrate::calibrate(fit, &facts), self.score(&own))
    }

    /// The plant `cfg` replayed under the log's command, each channel the log has (a held
    /// channel held on the log's readings), and the supply voltage.
    pub fn replay(&self, cfg: &PlantConfig) -> Result<(Simulated, Vec<f64>), CliError> {
        let rows = calibrate::replay(cfg, self.dt_s(), &self.command)
            .map_err(propid_sim::SimError::from)?;
        let col = |f: fn(&Measurement) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
        let sim = self
            .channels
            .iter()
            .map(|c| {
                let y = match c.quantity {
                    Quantity::Thrust => col(|m| m.thrust_n),
                    Quantity::Torque => col(|m| m.torque_nm),
                    Quantity::Speed => col(|m| m.rpm),
                    Quantity::Current => col(|m| m.current_a),
                };
                let reading: Vec<bool> = if c.interpolated.is_empty() {
                    Vec::new()
                } else {
                    (0..y.len()).map(|k| is_reading(c, k)).collect()
                };
                (c.key, calibrate::hold_on(&y, &reading))
            })
            .collect();
        Ok((sim, col(|m| m.voltage_v)))
    }

    /// Fit percent of each simulated channel against the log's readings of it.
    pub fn score(&self, sim: &Simulated) -> BTreeMap<String, f64> {
        sim.iter()
            .filter_map(|(key, yhat)| {
                let c = self.channels.iter().find(|c| c.key == *key)?;
                let y: Vec<f64> = (0..c.data.len())
                    .map(|k| {
                        if is_reading(c, k) {
                            c.data[k]
                        } else {
                            f64::NAN
                        }
                    })
                    .collect();
                let (lo, hi) = y
                    .iter()
                    .filter(|v| v.is_finite())
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                        (a.min(v), b.max(v))
                    });
                let (pct, _, n) = fit_percent(&y, yhat, 0..y.len().min(yhat.len()));
                // A channel that never moves has no fit percent.
                (n > 0 && hi > lo).then(|| (key.to_string(), (pct * 100.0).round() / 100.0))
            })
            .collect()
    }

    /// The simulation as CSV text in the log's columns and units: time, command, each
    /// simulated channel, the voltage when the log has one.
    pub fn csv(&self, sim: &Simulated, voltage: &[f64]) -> String {
        let units = match &self.file.origin {
            Origin::Csv(src) => Some((src.units.clone(), src.units_row)),
            Origin::Tsp1(_) => None,
        };
        // (name, unit, raw = canonical / factor + zero) of a key, else the canonical name.
        let column = |key: &str, canonical: &str| -> Column {
            match units.as_ref().and_then(|(u, _)| u.get(key)) {
                Some(u) => (u.column.clone(), u.unit.clone(), u.factor, u.zero),
                None => (canonical.to_string(), String::new(), 1.0, 0.0),
            }
        };
        let rec = &self.file.record;
        let mut cols: Vec<(Column, Vec<f64>)> = Vec::new();
        let time: Vec<f64> = (0..self.command.len())
            .map(|k| rec.t0_s + k as f64 * rec.dt_s)
            .collect();
        cols.push((column("time", "t_s"), time));
        cols.push((column("throttle", names::THROTTLE), self.command.clone()));
        for (key, y) in sim {
            let canonical = CHANNELS.iter().find(|c| c.0 == *key).map_or(*key, |c| c.1);
            cols.push((column(key, canonical), y.clone()));
        }
        if self.voltage.is_some() {
            cols.push((column("voltage", names::VOLTAGE), voltage.to_vec()));
        }
        let mut t = String::new();
        let head: Vec<&str> = cols.iter().map(|((n, ..), _)| n.as_str()).collect();
        let _ = writeln!(t, "{}", head.join(","));
        if units.as_ref().is_some_and(|(_, row)| *row) {
            let row: Vec<&str> = cols.iter().map(|((_, u, ..), _)| u.as_str()).collect();
            let _ = writeln!(t, "{}", row.join(","));
        }
        for k in 0..self.command.len() {
            let row: Vec<String> = cols
                .iter()
                .map(|((_, _, factor, zero), y)| match y.get(k) {
                    Some(v) if v.is_finite() => format!("{}", v / factor + zero),
                    _ => String::new(),
                })
                .collect();
            let _ = writeln!(t, "{}", row.join(","));
        }
        t
    }
}

/// A column of the CSV written: name, unit, factor to canonical units, raw zero.
type Column = (String, String, f64, f64);

/// Whether row `k` of `c` is a reading (finite, not interpolated).
fn is_reading(c: &LogChannel, k: usize) -> bool {
    c.data[k].is_finite() && !c.interpolated.get(k).copied().unwrap_or(false)
}

fn readings(c: &LogChannel) -> impl Iterator<Item = usize> + '_ {
    (0..c.data.len()).filter(|&k| is_reading(c, k))
}

/// What `diagnose --sim-config` wrote (`"sim_config"` in its JSON).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Written {
    /// The configuration file.
    pub file: String,
    /// The fitted stand's own fit per channel, % (what its replay scores, within a point).
    pub fit_percent: BTreeMap<String, f64>,
    /// What the configuration could not carry exactly.
    pub notes: Vec<String>,
}

impl Written {
    /// The summary's line.
    pub fn line(&self) -> String {
        let fits: Vec<String> = self
            .fit_percent
            .iter()
            .map(|(k, v)| format!("{k} {v:.2} %"))
            .collect();
        let mut t = format!(
            "sim config: the fitted stand written to {} (propid sim --config; fit {})",
            self.file,
            fits.join(", ")
        );
        for n in &self.notes {
            let _ = write!(t, "\n  {n}");
        }
        t
    }
}

/// Fits the stand model on the log `path` (read as `req` asks) and writes it to `out` as a
/// `propid sim` configuration.
pub fn write_config(path: &Path, req: &Request, out: &Path) -> Result<Written, CliError> {
    let log = read(path, req)?;
    let fit = log.fit()?;
    let (cal, fit_percent) = log.calibrate(&fit);
    let header = [
        format!(
            "propid sim configuration: the stand of {} as the stand model fitted it",
            path.display()
        ),
        "(propid diagnose --sim-config; docs/stand-model.md). Replay it under the log's command:"
            .to_string(),
        format!(
            "  propid sim --config {} --replay-command {} --out SIM.csv",
            out.display(),
            path.display()
        ),
    ];
    let text = calibrate::to_toml(&cal.config, &header);
    std::fs::write(out, text).map_err(|e| CliError::io(format!("writing {}", out.display()), e))?;
    Ok(Written {
        file: out.display().to_string(),
        fit_percent,
        notes: cal.notes,
    })
}
