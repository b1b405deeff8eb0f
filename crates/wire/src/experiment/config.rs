//! The experiment plan's configuration (`[experiment]` in `config/sim.toml` and the daemon's
//! config): the kind of experiment, operating points, pulse train, holds, ramp rate, chirp,
//! timing. Units are in the names.

use serde::Deserialize;

/// Highest `chirp_f1_hz`: five command points per period at the chirp's 10 ms command step
/// (the program's `CHIRP_STEP_MS`).
pub const CHIRP_MAX_HZ: f64 = 20.0;

/// What the plan does at the stand (`[experiment] kind`); `docs/experiment-kinds.md`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Pulses about each operating point (the default): the ERA models per level.
    #[default]
    Pulses,
    /// Steps through the levels up, then down, each held `hold_ms`: the static map and each
    /// step's figures per direction.
    Staircase,
    /// From the lowest level to the highest and back at `ramp_rate_per_s`: the static map of
    /// each leg and their hysteresis.
    Ramp,
    /// A logarithmic sweep about the one level from `chirp_f0_hz` to `chirp_f1_hz`: the
    /// frequency response.
    Chirp,
}

impl Kind {
    /// The name as configured.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Pulses => "pulses",
            Kind::Staircase => "staircase",
            Kind::Ramp => "ramp",
            Kind::Chirp => "chirp",
        }
    }
}

/// A refused experiment configuration: key (relative to the `[experiment]` table), value, reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("experiment key `{key}` = {value}: {reason}")]
pub struct ExperimentConfigError {
    /// Key inside the experiment table, e.g. `levels[1]`.
    pub key: String,
    /// The refused value.
    pub value: String,
    /// The allowed range.
    pub reason: String,
}

/// One throttle the plan commands ([`ExperimentConfig::commanded`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Commanded {
    /// The keys that make it, e.g. `levels[1]` or `levels[1] - pulse_amplitudes[0]`.
    pub key: String,
    /// How it is made, e.g. `0.3 - 0.05 = 0.25`.
    pub value: String,
    /// The throttle, fraction.
    pub throttle: f64,
}

/// The host-side experiment: arm, visit each operating point, fire pulses, ramp down, disarm.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExperimentConfig {
    /// The kind of experiment (`"pulses"`, `"staircase"`, `"ramp"`, `"chirp"`).
    pub kind: Kind,
    /// Operating points, throttle fraction, each in 0.0..=1.0, 1..=32 of them.
    pub levels: Vec<f64>,
    /// Duration of the ramp from one operating point to the next (and down at the end), ms,
    /// 0..=10000 (0 = step).
    pub ramp_ms: u16,
    /// Wait after the ramp before the first pulse, ms, 0..=60000.
    pub settle_ms: u32,
    /// Pulse amplitudes, throttle fraction, each in 0.001..=0.5, 1..=8 of them; pulse `j` uses
    /// amplitude `pulse_amplitudes[(j / 2) % n]` (or `[j % n]` without alternating sign).
    pub pulse_amplitudes: Vec<f64>,
    /// Alternate the sign of the pulses (+a, −a, +a, …) so that a static nonlinearity shows up
    /// and the mean throttle stays at the operating point.
    pub alternate_sign: bool,
    /// Pulse width, sample periods, 1..=1000 (1 = the Kronecker delta of the ERA derivation).
    pub pulse_width_samples: u32,
    /// Spacing from one pulse to the next, ms, 10..=60000: long enough that the response has
    /// decayed into the noise (several time constants).
    pub pulse_spacing_ms: u32,
    /// Pulses per operating point before the level is reported done (K), 1..=10000.
    pub pulses_per_level: u32,
    /// HEARTBEAT period, ms, 10..=1000 (the protocol asks for 100).
    pub heartbeat_ms: u32,
    /// Device watchdog sent with ARM, ms, 100..=5000; must exceed `heartbeat_ms` twice over.
    pub watchdog_ms: u16,
    /// Re-send a command with the same seq after this long without ACK, ms, 10..=1000.
    /// The device answers a re-send as a repeat only within one second and its last 8
    /// commands (heartbeats included), so a later one is executed again; an IMPULSE the device
    /// reported firing (EVENT IMPULSE_START) is therefore never re-sent.
    pub retry_ms: u32,
    /// Re-sends before the link is declared failed, 0..=10.
    pub max_retries: u32,
    /// After a device reset (a HELLO with a new boot id) or a link stall the host stopped the
    /// motor for: hand-shake, ARM again and resume at the interrupted operating point (`true`),
    /// or end the plan (`false`, the default: a supervisor decides; the daemon exits 8).
    pub rearm_on_reset: bool,
    /// Most re-arms in one run (`rearm_on_reset`), 0..=100: a device that resets or stalls
    /// once more after this many re-arms ends the plan ([`super::Notice::RearmLimit`]; the
    /// daemon exits 8), so a stand that keeps resetting is not re-armed for ever.
    pub max_rearms: u32,
    /// `staircase`: how long each level is held, ms, 100..=600000 (settled and averaged over
    /// its last half); `ramp`: the hold at each end.
    pub hold_ms: u32,
    /// `ramp`: throttle fraction per second of both legs, 0.001..=1.
    pub ramp_rate_per_s: f64,
    /// `chirp`: start frequency, Hz, 0.01..=50.
    pub chirp_f0_hz: f64,
    /// `chirp`: end frequency, Hz, above `chirp_f0_hz`, at most [`CHIRP_MAX_HZ`].
    pub chirp_f1_hz: f64,
    /// `chirp`: amplitude about the level, throttle fraction, 0.001..=0.5.
    pub chirp_amplitude: f64,
    /// `chirp`: sweep duration, s, 1..=600.
    pub chirp_s: f64,
}

impl Default for ExperimentConfig {
    fn default() -> Self {
        ExperimentConfig {
            kind: Kind::Pulses,
            levels: vec![0.3, 0.45, 0.6],
            ramp_ms: 500,
            settle_ms: 500,
            pulse_amplitudes: vec![0.05, 0.1],
            alternate_sign: true,
            pulse_width_samples: 1,
            pulse_spacing_ms: 250,
            pulses_per_level: 8,
            heartbeat_ms: 100,
            watchdog_ms: 500,
            retry_ms: 50,
            max_retries: 3,
            rearm_on_reset: false,
            max_rearms: 3,
            hold_ms: 2000,
            ramp_rate_per_s: 0.05,
            chirp_f0_hz: 0.5,
            chirp_f1_hz: 20.0,
            chirp_amplitude: 0.05,
            chirp_s: 30.0,
        }
    }
}

fn refuse(key: impl Into<String>, value: impl ToString, reason: &str) -> ExperimentConfigError {
    ExperimentConfigError {
        key: key.into(),
        value: value.to_string(),
        reason: reason.to_string(),
    }
}

fn check_f(key: String, v: f64, lo: f64, hi: f64) -> Result<(), ExperimentConfigError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(refuse(key, v, &format!("a finite number in {lo}..={hi}")))
    }
}

fn check_i(key: &str, v: u64, lo: u64, hi: u64) -> Result<(), ExperimentConfigError> {
    if v >= lo && v <= hi {
        Ok(())
    } else {
        Err(refuse(key, v, &format!("an integer in {lo}..={hi}")))
    }
}

impl ExperimentConfig {
    /// Refuses NaN, out-of-range values and empty lists, naming the key and the value.
    pub fn validate(&self) -> Result<(), ExperimentConfigError> {
        check_i("levels.len()", self.levels.len() as u64, 1, 32)?;
        for (i, &l) in self.levels.iter().enumerate() {
            check_f(format!("levels[{i}]"), l, 0.0, 1.0)?;
        }
        check_i(
            "pulse_amplitudes.len()",
            self.pulse_amplitudes.len() as u64,
            1,
            8,
        )?;
        for (i, &a) in self.pulse_amplitudes.iter().enumerate() {
            check_f(format!("pulse_amplitudes[{i}]"), a, 0.001, 0.5)?;
        }
        check_i("ramp_ms", self.ramp_ms as u64, 0, 10_000)?;
        check_i("settle_ms", self.settle_ms as u64, 0, 60_000)?;
        check_i(
            "pulse_width_samples",
            self.pulse_width_samples as u64,
            1,
            1000,
        )?;
        check_i("pulse_spacing_ms", self.pulse_spacing_ms as u64, 10, 60_000)?;
        check_i("pulses_per_level", self.pulses_per_level as u64, 1, 10_000)?;
        check_i("heartbeat_ms", self.heartbeat_ms as u64, 10, 1000)?;
        check_i("watchdog_ms", self.watchdog_ms as u64, 100, 5000)?;
        if (self.watchdog_ms as u32) < 2 * self.heartbeat_ms {
            return Err(refuse(
                "watchdog_ms",
                self.watchdog_ms,
                "at least twice heartbeat_ms",
            ));
        }
        check_i("retry_ms", self.retry_ms as u64, 10, 1000)?;
        check_i("max_retries", self.max_retries as u64, 0, 10)?;
        check_i("max_rearms", self.max_rearms as u64, 0, 100)?;
        check_i("hold_ms", self.hold_ms as u64, 100, 600_000)?;
        check_f("ramp_rate_per_s".into(), self.ramp_rate_per_s, 0.001, 1.0)?;
        check_f("chirp_f0_hz".into(), self.chirp_f0_hz, 0.01, 50.0)?;
        check_f("chirp_f1_hz".into(), self.chirp_f1_hz, 0.01, CHIRP_MAX_HZ)?;
        if self.chirp_f1_hz <= self.chirp_f0_hz {
            return Err(refuse("chirp_f1_hz", self.chirp_f1_hz, "above chirp_f0_hz"));
        }
        check_f("chirp_amplitude".into(), self.chirp_amplitude, 0.001, 0.5)?;
        check_f("chirp_s".into(), self.chirp_s, 1.0, 600.0)?;
        match self.kind {
            Kind::Pulses => self.check_pulse_levels(),
            Kind::Staircase => Ok(()),
            Kind::Ramp => {
                let (lo, hi) = self.envelope();
                if hi - lo < 0.01 {
                    return Err(refuse(
                        "levels",
                        format!("{:?}", self.levels),
                        "a ramp runs from the lowest level to the highest: at least 0.01 apart",
                    ));
                }
                Ok(())
            }
            Kind::Chirp => self.check_chirp(),
        }
    }

    /// A chirp sweeps about one level, and `level ± chirp_amplitude` must lie in 0..=1.
    fn check_chirp(&self) -> Result<(), ExperimentConfigError> {
        if self.levels.len() != 1 {
            return Err(refuse(
                "levels",
                format!("{:?}", self.levels),
                "kind = \"chirp\" sweeps about one level: levels = [one level]",
            ));
        }
        let (l, a) = (self.levels[0], self.chirp_amplitude);
        if l - a < -1e-9 || l + a > 1.0 + 1e-9 {
            return Err(refuse(
                "levels[0] ± chirp_amplitude",
                format!("{l} ± {a}"),
                "the sweep (level ± amplitude) in 0..=1: a device would clamp it",
            ));
        }
        Ok(())
    }

    /// The lowest and highest throttle the plan commands: the bounds of [`Self::commanded`].
    pub fn envelope(&self) -> (f64, f64) {
        self.commanded()
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                (lo.min(c.throttle), hi.max(c.throttle))
            })
    }

    /// Every pulse level `level + delta` (each level with each signed amplitude the train
    /// uses: `+a`, and `−a` with `alternate_sign`) must lie in 0..=1: a device clamps what lies
    /// outside (`levels = [0.95]` with `pulse_amplitudes = [0.1]` pulses to 100 %, `levels =
    /// [0.02]` with `−0.05` cuts the motor to 0 %), a pulse the plan never meant. The pair is
    /// refused, named (`levels[i] ± pulse_amplitudes[j]`), before anything is sent.
    fn check_pulse_levels(&self) -> Result<(), ExperimentConfigError> {
        match self
            .commanded()
            .into_iter()
            .find(|c| c.throttle > 1.0 + 1e-9 || c.throttle < -1e-9)
        {
            Some(c) => Err(refuse(
                c.key,
                c.value,
                "every pulse level (level ± amplitude) in 0..=1: a device would clamp it",
            )),
            None => Ok(()),
        }
    }

    /// The commanded envelope: every throttle the plan commands besides the ramp down to 0,
    /// named by the keys that make it — each level (`levels[i]`), and each pulse level about it
    /// (`levels[i] + pulse_amplitudes[j]`, and `levels[i] - pulse_amplitudes[j]` with
    /// `alternate_sign`), in that order; a `staircase` or `ramp` commands its levels (a ramp's
    /// ends), a `chirp` each level and `levels[i] ± chirp_amplitude`. The one list the plan's
    /// checks read: 0..=1 here,
    /// `[limits] max_throttle` ([`super::Limits::refuse_plan`]).
    pub fn commanded(&self) -> Vec<Commanded> {
        let mut out = Vec::new();
        for (i, &l) in self.levels.iter().enumerate() {
            out.push(Commanded {
                key: format!("levels[{i}]"),
                value: l.to_string(),
                throttle: l,
            });
            if self.kind == Kind::Chirp {
                for (sign, v) in [
                    ('+', l + self.chirp_amplitude),
                    ('-', l - self.chirp_amplitude),
                ] {
                    out.push(Commanded {
                        key: format!("levels[{i}] {sign} chirp_amplitude"),
                        value: format!("{l} {sign} {} = {v}", self.chirp_amplitude),
                        throttle: v,
                    });
                }
            }
            if self.kind != Kind::Pulses {
                continue;
            }
            for (j, &a) in self.pulse_amplitudes.iter().enumerate() {
                let signs: &[char] = if self.alternate_sign {
                    &['+', '-']
                } else {
                    &['+']
                };
                for &sign in signs {
                    let v = if sign == '+' { l + a } else { l - a };
                    out.push(Commanded {
                        key: format!("levels[{i}] {sign} pulse_amplitudes[{j}]"),
                        value: format!("{l} {sign} {a} = {v}"),
                        throttle: v,
                    });
                }
            }
        }
        out
    }

    /// Signed amplitude (throttle fraction) of pulse `j` at an operating point.
    pub fn pulse_delta(&self, j: u32) -> f64 {
        let n = self.pulse_amplitudes.len().max(1);
        if self.alternate_sign {
            let a = self.pulse_amplitudes[(j as usize / 2) % n];
            if j % 2 == 0 {
                a
            } else {
                -a
            }
        } else {
            self.pulse_amplitudes[j as usize % n]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid() {
        ExperimentConfig::default().validate().unwrap();
    }

    #[test]
    fn pulse_train_alternates_sign_and_cycles_amplitudes() {
        let c = ExperimentConfig::default();
        let d: Vec<f64> = (0..5).map(|j| c.pulse_delta(j)).collect();
        assert_eq!(d, vec![0.05, -0.05, 0.1, -0.1, 0.05]);
    }

    #[test]
    fn bad_level_is_named() {
        let c = ExperimentConfig {
            levels: vec![0.3, f64::NAN],
            ..ExperimentConfig::default()
        };
        let e = c.validate().unwrap_err();
        assert_eq!(e.key, "levels[1]");
        assert_eq!(e.value, "NaN");
    }

    #[test]
    fn a_pulse_level_outside_0_to_1_is_refused_by_its_pair() {
        let c = ExperimentConfig {
            levels: vec![0.95],
            pulse_amplitudes: vec![0.1, 0.5],
            ..ExperimentConfig::default()
        };
        let e = c.validate().unwrap_err();
        assert_eq!(e.key, "levels[0] + pulse_amplitudes[0]", "{e}");
        assert!(e.value.contains("1.05"), "{e}");
        let c = ExperimentConfig {
            levels: vec![0.3, 0.02],
            ..ExperimentConfig::default()
        };
        let e = c.validate().unwrap_err();
        assert_eq!(e.key, "levels[1] - pulse_amplitudes[0]", "{e}");
        // without alternating signs only +a is fired
        let c = ExperimentConfig {
            levels: vec![0.02],
            alternate_sign: false,
            ..ExperimentConfig::default()
        };
        c.validate().unwrap();
        // the edges themselves are pulse levels
        let c = ExperimentConfig {
            levels: vec![0.1, 0.9],
            ..ExperimentConfig::default()
        };
        c.validate().unwrap();
    }

    #[test]
    fn envelope_of_each_kind() {
        let c = ExperimentConfig::default();
        let (lo, hi) = c.envelope();
        assert!(
            (lo - 0.2).abs() < 1e-12 && (hi - 0.7).abs() < 1e-12,
            "{lo} {hi}"
        );
        for kind in [Kind::Staircase, Kind::Ramp] {
            let c = ExperimentConfig {
                kind,
                ..ExperimentConfig::default()
            };
            assert_eq!(c.envelope(), (0.3, 0.6));
        }
        let c = ExperimentConfig {
            kind: Kind::Chirp,
            levels: vec![0.5],
            chirp_amplitude: 0.1,
            ..ExperimentConfig::default()
        };
        c.validate().unwrap();
        assert_eq!(c.envelope(), (0.4, 0.6));
    }

    #[test]
    fn a_chirp_needs_one_level_and_room_for_its_amplitude() {
        let c = ExperimentConfig {
            kind: Kind::Chirp,
            ..ExperimentConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().key, "levels");
        let c = ExperimentConfig {
            kind: Kind::Chirp,
            levels: vec![0.05],
            chirp_amplitude: 0.1,
            ..ExperimentConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().key, "levels[0] ± chirp_amplitude");
        let c = ExperimentConfig {
            kind: Kind::Chirp,
            levels: vec![0.5],
            chirp_f0_hz: 5.0,
            chirp_f1_hz: 2.0,
            ..ExperimentConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().key, "chirp_f1_hz");
    }

    #[test]
    fn kinds_parse_by_name() {
        for k in [Kind::Pulses, Kind::Staircase, Kind::Ramp, Kind::Chirp] {
            let parsed: Kind = serde_json::from_str(&format!("\"{}\"", k.name())).unwrap();
            assert_eq!(parsed, k);
        }
        assert!(serde_json::from_str::<Kind>("\"sweep\"").is_err());
    }

    #[test]
    fn watchdog_must_outlast_heartbeats() {
        let c = ExperimentConfig {
            watchdog_ms: 150,
            ..ExperimentConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().key, "watchdog_ms");
    }
}
