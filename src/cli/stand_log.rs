//! A stand's log for the calibrated simulation (`diagnose --sim-config`, `sim
//! --replay-command`): the command and every stand channel, read as `identify` reads them; the
//! stand model fitted on it; the simulated stand's rows written in the log's columns and units,
//! and scored against it as diagnose scores its held-out figure
//! (`propid_diagnose::stand::score_on_folds`). The mapping and the replay are
//! `propid_sim::calibrate`'s.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::load::{self as shared, LoadedFile, Origin, Request};
use super::CliError;
use propid_diagnose::folds::Folds;
use propid_diagnose::stand::{score_on_folds, StandBaseline};
use propid_numerics::segment::SegmentRules;
use propid_numerics::stand_model::fit::{fit, Channel, FitInput, StandFit};
use propid_numerics::stand_model::{simulate, Quantity};
use propid_numerics::EffectName;
use propid_sim::calibrate::{self, Calibrated, Extensions, LogFacts};
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
        let channels: Vec<Channel<'_>> = self.channels.iter().map(as_channel).collect();
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

    /// `fit` with its extensions `ext` as a `propid sim` configuration.
    pub fn calibrate(&self, fit: &StandFit, ext: &Extensions) -> Calibrated {
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
        calibrate::calibrate(fit, ext, &facts)
    }

    /// The plant `cfg` replayed under the log's command (and its measured voltage when the
    /// configuration's supply sags, `calibrate::replays_measured_supply`), each channel the log
    /// has (a held channel held on the log's readings), and the supply voltage.
    pub fn replay(&self, cfg: &PlantConfig) -> Result<(Simulated, Vec<f64>), CliError> {
        let measured = self
            .voltage
            .as_deref()
            .filter(|_| calibrate::replays_measured_supply(cfg));
        let rows = calibrate::replay(cfg, self.dt_s(), &self.command, measured)
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

    /// The folds diagnose scores this log on (its thrust the output, else its first channel;
    /// the default estimation fraction).
    pub fn folds(&self) -> Folds {
        let out = self
            .channel(Quantity::Thrust)
            .or(self.channels.first())
            .map(|c| c.data.as_slice())
            .unwrap_or(&[]);
        let rules = SegmentRules::for_record(self.dt_s(), true);
        Folds::from_input(&self.command, out, 0.7, &rules)
    }

    /// Each simulated channel scored against the log's readings of it on `folds` as diagnose
    /// scores its held-out figure (`score_on_folds`), rounded to 0.01; a channel that never
    /// moves has none.
    pub fn score(&self, sim: &Simulated, folds: &Folds) -> BTreeMap<String, f64> {
        let channels: Vec<Channel<'_>> = self
            .channels
            .iter()
            .filter(|c| {
                let (lo, hi) = readings(c).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), k| {
                    (a.min(c.data[k]), b.max(c.data[k]))
                });
                hi > lo
            })
            .map(as_channel)
            .collect();
        let sim: Vec<(&str, Vec<f64>)> = sim.iter().map(|(k, y)| (*k, y.clone())).collect();
        score_on_folds(&channels, &sim, folds)
            .into_iter()
            .map(|(k, v)| (k.to_string(), (v * 100.0).round() / 100.0))
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

/// A channel of the log as the stand fit and the scoring read it.
fn as_channel(c: &LogChannel) -> Channel<'_> {
    Channel {
        key: c.key,
        quantity: c.quantity,
        y: &c.data,
        interpolated: &c.interpolated,
    }
}

/// The rows of `c` that are readings ([`is_reading`]).
fn readings(c: &LogChannel) -> impl Iterator<Item = usize> + '_ {
    (0..c.data.len()).filter(|&k| is_reading(c, k))
}

/// What `diagnose --sim-config` wrote (`"sim_config"` in its JSON).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Written {
    /// The configuration file.
    pub file: String,
    /// The written stand's fit of the log per channel, %: diagnose's final stand model (fitted
    /// on the estimation part) over the whole log, scored as diagnose scores its held-out
    /// figure (the same folds and channels, `score_on_folds`). The replay gives it within a
    /// point.
    pub fit_percent: BTreeMap<String, f64>,
    /// Diagnose's held-out figure per channel, % (`stand.channels.<key>.fit_percent`: each
    /// fold predicted by the model refitted without it; below `fit_percent` by the model's
    /// optimism). Empty on diagnose's generic baseline.
    pub held_out_fit_percent: BTreeMap<String, f64>,
    /// The configuration replayed under the log's command, scored the same way, % (what
    /// `propid sim --replay-command` reports).
    pub replay_fit_percent: BTreeMap<String, f64>,
    /// The effects the configuration carries beyond the stand baseline (diagnose's findings).
    pub effects: Vec<EffectName>,
    /// What the configuration could not carry exactly.
    pub notes: Vec<String>,
}

impl Written {
    /// The summary's line.
    pub fn line(&self) -> String {
        let fits: Vec<String> = self
            .fit_percent
            .iter()
            .map(|(k, v)| {
                let r = self.replay_fit_percent.get(k).copied().unwrap_or(f64::NAN);
                format!("{k} {v:.2} % (replayed {r:.2} %)")
            })
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

/// Writes diagnose's calibrated stand `stand` of the log `path` (read as `req` asks) to `out`
/// as a `propid sim` configuration, with diagnose's held-out figures `reported` per channel
/// (`stand.channels.<key>.fit_percent`);
/// without a stand (diagnose's generic baseline) the stand model fitted on the whole log.
pub fn write_config(
    path: &Path,
    req: &Request,
    out: &Path,
    stand: Option<&StandBaseline>,
    reported: BTreeMap<String, f64>,
) -> Result<Written, CliError> {
    let log = read(path, req)?;
    let whole;
    let (fit, ext, folds, mut notes) = match stand {
        Some(sb) => (
            &sb.extended.fit,
            Extensions::of(&sb.extended, &sb.structure),
            sb.folds.clone(),
            Vec::new(),
        ),
        None => {
            whole = log.fit()?;
            (
                &whole,
                Extensions::whole(&whole),
                log.folds(),
                vec![
                    "diagnose's baseline is the generic model: the stand model fitted on the \
                      whole log is written"
                        .to_string(),
                ],
            )
        }
    };
    let cal = log.calibrate(fit, &ext);
    let (sim, _) = log.replay(&cal.config.plant)?;
    let replay_fit_percent = log.score(&sim, &folds);
    // The written stand's own fit of the log, scored as the replay is (module doc).
    let own: Simulated = match stand {
        Some(sb) => sb
            .extended
            .prediction
            .iter()
            .map(|(k, p)| (*k, p.clone()))
            .collect(),
        None => {
            let sensors = calibrate::fitted_sensors(fit, &ext);
            let pairs: Vec<_> = sensors.iter().map(|(_, q, s)| (*q, *s)).collect();
            let v = log.voltage.as_deref().filter(|_| ext.supply_measured);
            let model = simulate(&fit.params, log.dt_s(), &log.command, v, &pairs);
            sensors
                .iter()
                .zip(model)
                .map(|((k, ..), y)| (*k, y))
                .collect()
        }
    };
    let fit_percent = log.score(&own, &folds);
    notes.extend(cal.notes.iter().cloned());
    let mut effects = stand.map_or_else(Vec::new, |sb| sb.effects.clone());
    effects.retain(|e| *e != EffectName::StiffnessNonlinearity);
    let header = [
        format!(
            "propid sim configuration: the stand of {} as propid diagnose fitted it",
            path.display()
        ),
        format!(
            "(effects: {}; docs/stand-model.md). Replay it under the log's command:",
            if effects.is_empty() {
                "none".to_string()
            } else {
                effects
                    .iter()
                    .map(|e| e.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        ),
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
        held_out_fit_percent: reported
            .into_iter()
            .map(|(k, v)| (k, (v * 100.0).round() / 100.0))
            .collect(),
        replay_fit_percent,
        effects,
        notes,
    })
}
