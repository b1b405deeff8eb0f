//! The stand's sensors, one per measured channel (`[plant.sensors.<channel>]`): what the plant
//! logs of a quantity, as the stand model's sensor ([`propid_numerics::stand_model::Sensor`],
//! `sense`) — a first-order lag, a delay, an offset and a creep, and a refresh interval over
//! which the reading is held — stepped one sample at a time:
//!
//! ```text
//!   s_k = a s_{k−1} + (1 − a) x_{k−1} + (1 − τ(1 − a)/dt)(x_k − x_{k−1}),   a = e^{−dt/τ}
//!   y_k = s(t_k − δ) + offset + creep · t_k        (s linear between samples)
//! ```
//!
//! (the lag's exact first-order-hold step, as `stand_model::lag`), `y` read once per
//! `refresh_s` from the plant's start and held in between. A channel without a table reads its
//! quantity as it is.

use serde::Deserialize;

use super::{check, PlantError};

/// One `[plant.sensors.<channel>]` table. Units are the channel's: N (thrust), N·m (torque),
/// rev/min (rpm), A (current).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// Delay of the reading, s (0..=1).
    pub delay_s: f64,
    /// First-order lag, s (0 = none ..= 5).
    pub tau_s: f64,
    /// Refresh interval, s (0 or at most a sample: every sample; ..= 10).
    pub refresh_s: f64,
    /// Offset added to the reading, the channel's unit.
    pub offset: f64,
    /// Creep of the reading, the channel's unit per second.
    pub creep_per_s: f64,
}

/// `[plant.sensors]`: a sensor per channel (absent: the quantity as it is).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorsConfig {
    /// The load cell's thrust reading.
    pub thrust: Option<SensorConfig>,
    /// The torque reading.
    pub torque: Option<SensorConfig>,
    /// The speed reading.
    pub rpm: Option<SensorConfig>,
    /// The current reading.
    pub current: Option<SensorConfig>,
}

impl SensorsConfig {
    /// Range checks; the error names the first bad key.
    pub fn validate(&self) -> Result<(), PlantError> {
        let all = [
            (&self.thrust, "thrust"),
            (&self.torque, "torque"),
            (&self.rpm, "rpm"),
            (&self.current, "current"),
        ];
        for (s, name) in all {
            if let Some(s) = s {
                s.validate(name)?;
            }
        }
        Ok(())
    }
}

impl SensorConfig {
    fn validate(&self, channel: &'static str) -> Result<(), PlantError> {
        let key = |k: &str| -> &'static str {
            match (channel, k) {
                ("thrust", "delay") => "plant.sensors.thrust.delay_s",
                ("thrust", "tau") => "plant.sensors.thrust.tau_s",
                ("thrust", "refresh") => "plant.sensors.thrust.refresh_s",
                ("thrust", _) => "plant.sensors.thrust",
                ("torque", "delay") => "plant.sensors.torque.delay_s",
                ("torque", "tau") => "plant.sensors.torque.tau_s",
                ("torque", "refresh") => "plant.sensors.torque.refresh_s",
                ("torque", _) => "plant.sensors.torque",
                ("rpm", "delay") => "plant.sensors.rpm.delay_s",
                ("rpm", "tau") => "plant.sensors.rpm.tau_s",
                ("rpm", "refresh") => "plant.sensors.rpm.refresh_s",
                ("rpm", _) => "plant.sensors.rpm",
                (_, "delay") => "plant.sensors.current.delay_s",
                (_, "tau") => "plant.sensors.current.tau_s",
                (_, "refresh") => "plant.sensors.current.refresh_s",
                _ => "plant.sensors.current",
            }
        };
        let within = |v: f64, hi: f64| v.is_finite() && (0.0..=hi).contains(&v);
        check(
            within(self.delay_s, 1.0),
            key("delay"),
            self.delay_s,
            "must be in [0, 1] s",
        )?;
        check(
            within(self.tau_s, 5.0),
            key("tau"),
            self.tau_s,
            "must be in [0, 5] s",
        )?;
        check(
            within(self.refresh_s, 10.0),
            key("refresh"),
            self.refresh_s,
            "must be in [0, 10] s",
        )?;
        let finite = self.offset.is_finite() && self.creep_per_s.is_finite();
        check(
            finite,
            key("offset"),
            if self.offset.is_finite() {
                self.creep_per_s
            } else {
                self.offset
            },
            "offset and creep_per_s must be finite",
        )
    }
}

/// One sensor's state (module doc).
#[derive(Debug, Clone)]
pub(crate) struct SensorState {
    cfg: SensorConfig,
    dt_s: f64,
    /// `e^{−dt/τ}` and the ramp factor `1 − τ(1 − a)/dt` (`None`: no lag).
    lag: Option<(f64, f64)>,
    s: f64,
    last_x: f64,
    /// The lagged values of the last samples, newest last (the delay reads between them).
    past: std::collections::VecDeque<f64>,
    slot: Option<u64>,
    held: f64,
}

impl SensorState {
    pub(crate) fn new(cfg: &SensorConfig, dt_s: f64) -> SensorState {
        let lag = (cfg.tau_s > 0.0).then(|| {
            let a = (-dt_s / cfg.tau_s).exp();
            (a, 1.0 - cfg.tau_s * (1.0 - a) / dt_s)
        });
        let keep = (cfg.delay_s / dt_s).ceil() as usize + 2;
        SensorState {
            cfg: *cfg,
            dt_s,
            lag,
            s: 0.0,
            last_x: 0.0,
            past: std::collections::VecDeque::with_capacity(keep),
            slot: None,
            held: f64::NAN,
        }
    }

    /// Steady state at `x` (as if it had always been `x`).
    pub(crate) fn settle(&mut self, x: f64) {
        self.s = x;
        self.last_x = x;
        self.past.clear();
        self.slot = None;
    }

    /// The reading of `x` at sample `k` (time `k dt`) before it is held: lag, delay, offset and
    /// creep.
    pub(crate) fn shape(&mut self, x: f64, k: u64) -> f64 {
        if self.past.is_empty() {
            self.s = x;
        } else if let Some((a, ramp)) = self.lag {
            self.s = a * self.s + (1.0 - a) * self.last_x + ramp * (x - self.last_x);
        } else {
            self.s = x;
        }
        self.last_x = x;
        let keep = (self.cfg.delay_s / self.dt_s).ceil() as usize + 2;
        if self.past.is_empty() {
            self.past.extend(std::iter::repeat(self.s).take(keep));
        } else {
            self.past.pop_front();
            self.past.push_back(self.s);
        }
        // `past[keep − 1]` is now; read `delay / dt` samples back, linear in between.
        let back = self.cfg.delay_s / self.dt_s;
        let whole = back.floor();
        let f = back - whole;
        let i = keep - 1 - whole as usize;
        let y = if f > 0.0 {
            self.past[i] + f * (self.past[i - 1] - self.past[i])
        } else {
            self.past[i]
        };
        y + self.cfg.offset + self.cfg.creep_per_s * k as f64 * self.dt_s
    }

    /// `y` held over the refresh interval (read at the first sample of each interval).
    pub(crate) fn hold(&mut self, y: f64, k: u64) -> f64 {
        let period = self.cfg.refresh_s / self.dt_s;
        if period.is_nan() || period <= 1.0 + 1e-9 {
            return y;
        }
        let slot = (k as f64 / period + 1e-9).floor() as u64;
        if self.slot != Some(slot) {
            self.slot = Some(slot);
            self.held = y;
        }
        self.held
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_numerics::stand_model::{sense, Sensor};

    #[test]
    fn steps_as_the_stand_models_sensor_logs() {
        let dt = 0.01;
        let x: Vec<f64> = (0..300)
            .map(|k| if (50..180).contains(&k) { 2.0 } else { 0.5 } + 0.001 * k as f64)
            .collect();
        let cfg = SensorConfig {
            delay_s: 0.037,
            tau_s: 0.08,
            refresh_s: 0.07,
            offset: 0.3,
            creep_per_s: -0.02,
        };
        let want = sense(
            &Sensor {
                delay_s: cfg.delay_s,
                tau_s: cfg.tau_s,
                refresh_s: cfg.refresh_s,
                offset: cfg.offset,
                creep_per_s: cfg.creep_per_s,
            },
            dt,
            &x,
        );
        let mut s = SensorState::new(&cfg, dt);
        s.settle(x[0]);
        for (k, (&xk, w)) in x.iter().zip(&want).enumerate() {
            let y = s.shape(xk, k as u64);
            let y = s.hold(y, k as u64);
            assert!((y - w).abs() < 1e-9, "{k}: {y} vs {w}");
        }
    }

    #[test]
    fn out_of_range_values_are_refused_by_key() {
        let bad = SensorsConfig {
            rpm: Some(SensorConfig {
                tau_s: -1.0,
                ..SensorConfig::default()
            }),
            ..SensorsConfig::default()
        };
        match bad.validate() {
            Err(PlantError::InvalidParameter { key, .. }) => {
                assert_eq!(key, "plant.sensors.rpm.tau_s")
            }
            other => panic!("{other:?}"),
        }
    }
}
