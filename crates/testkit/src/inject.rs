//! Effects hidden in measured data (issue 11, item 6): a real log's samples with one effect of
//! known parameters added, written back as a CSV file for the app's one loader, and the check
//! that `propid diagnose --json` names it with its parameter.
//!
//! The injector is pure: [`Samples`] come from a record the app's loader read
//! ([`Samples::from_record`]), [`inject`] returns new samples, [`Samples::to_csv`] writes them
//! as `t_s,u,y[,voltage_V]` (missing samples as empty cells). What the detector sees is only
//! that file. The injected effects, with the model term each one should be found as:
//!
//! | [`Injection`] | on the output `y_k` | found as |
//! |---|---|---|
//! | `DeadTime { samples: d }` | `y_k ← y_{k−d}` (first sample held) | `dead_time`, `delay_samples` |
//! | `Periodic { freq_hz, amplitude, phase }` | `+ A sin(2π f t_k + φ)` | `periodic_disturbance` |
//! | `Drift { rate_per_s }` | `+ r t_k` | `baseline_drift`, `rate_per_s` |
//! | `SupplySag { gain_per_volt, .. }` | `· (1 + g (V_k − V̄))` | `supply_sag`, `gain_per_volt` |
//! | `SensorLag { delay_s, tau_s, .. }` | a load cell's lag: `s' = (y − s)/τ`, then delayed by `δ` | `sensor_lag` on that channel, `delay_s`, `tau_s` |
//!
//! The sensor lag acts on one column of a stand's log (the thrust: [`lag_column`]), the
//! others kept: it is found against them ([`STAND_EFFECTS`], the stand baseline of
//! `propid diagnose`).
//!
//! The supply sag uses the log's own voltage when it has one; otherwise a battery discharging
//! linearly from `v_start` to `v_end` is written as the voltage column. Scaling the output is
//! the model's voltage-scaled input only where the output is zero at rest (thrust, a centred
//! signal); a log whose output sits on a large offset would see part of the sag as a drift.

use propid_numerics::EffectName;
use propid_wire::record::Record;
use rand::Rng;
use serde_json::Value;

/// A real log to hide effects in: the file relative to the project root (or to the shared data
/// folder for [`SHARED_LOGS`]), its input and output columns, its sample rate when the file has
/// no time column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Log {
    /// Short name for tables.
    pub name: &'static str,
    /// The file.
    pub path: &'static str,
    /// Input column (`None`: the command column).
    pub input: Option<&'static str>,
    /// Output column (`None`: the thrust).
    pub output: Option<&'static str>,
    /// Sample rate, Hz, for a file without a time column.
    pub fs_hz: Option<f64>,
    /// The output is zero at rest (a thrust, a centred signal), so that scaling it is the
    /// model's voltage-scaled input: the supply sag is injected only then (module doc).
    pub zero_at_rest: bool,
}

impl Log {
    /// Whether `effect` can be injected in this log as the module table says.
    pub fn takes(&self, effect: EffectName) -> bool {
        effect != EffectName::SupplySag || self.zero_at_rest
    }
}

/// Logs copied into the repository (`tests/data`, see its README): the Silverbox slice (an
/// electronic mass-spring-damper at 610.35 Hz), the DaISy flexible robot arm (1024 samples,
/// at the 100 Hz its users assume) and the cascaded tanks (0.25 Hz).
pub const REPO_LOGS: [Log; 3] = [
    Log {
        name: "silverbox",
        path: "tests/data/silverbox/SNLS80mV_slice.csv",
        input: Some("V1"),
        output: Some("V2"),
        fs_hz: Some(610.35),
        zero_at_rest: true,
    },
    Log {
        name: "robot_arm",
        path: "tests/data/daisy-mechanical/robot_arm.csv",
        input: Some("u_torque"),
        output: Some("y_accel"),
        fs_hz: Some(100.0),
        zero_at_rest: true,
    },
    Log {
        name: "cascaded_tanks",
        path: "tests/data/cascaded-tanks/dataBenchmark.csv",
        input: Some("uEst"),
        output: Some("yEst"),
        fs_hz: Some(0.25),
        // A water level: the tank is never empty at rest.
        zero_at_rest: false,
    },
];

/// The column names of the noahcurtiss BL-Ctrl logs (`robbe12.0.txt`, `tiger12.0.txt`: no
/// header, `--columns`; PROVENANCE.md): the current in 0.1 A and the rpm as a raw byte are
/// named so that they are not read as amperes and rev/min; the force is in ADC counts.
pub const BLCTRL_COLUMNS: &[&str] = &[
    "cmd",
    "current_raw",
    "maxpwm",
    "temp",
    "rpm_raw",
    "res",
    "volt",
    "force",
];

/// Motor-stand logs that may only be read from `../shared/data` (no licence to copy them).
pub const SHARED_LOGS: [Log; 3] = [
    Log {
        name: "vanderploeg 90PERCENT",
        path: "vanderploeg-rcbenchmark-steps/90PERCENT_2024-08-13_185523.csv",
        input: None,
        output: None,
        fs_hz: None,
        zero_at_rest: true,
    },
    Log {
        name: "dantonio ramp",
        path: "dantonio-rcbenchmark-ramp/StepsTest20230615_2023-06-15_174003.csv",
        input: None,
        output: None,
        fs_hz: None,
        zero_at_rest: true,
    },
    Log {
        name: "bitcraze cf21",
        path: "bitcraze-cf21-pwm-steps/cf21_stock2.csv",
        input: Some("pwm"),
        output: Some("weight[g]"),
        fs_hz: Some(100.0),
        zero_at_rest: true,
    },
];

/// One uniformly sampled input/output log (missing samples are NaN).
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    /// Sample period, s.
    pub dt_s: f64,
    /// Time of sample 0, s.
    pub t0_s: f64,
    /// Input.
    pub u: Vec<f64>,
    /// Output.
    pub y: Vec<f64>,
    /// Supply voltage, V, when the log has it.
    pub voltage: Option<Vec<f64>>,
}

/// An effect with its parameters (the module table says what each does).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Injection {
    /// The output delayed by whole samples.
    DeadTime {
        /// Delay, samples.
        samples: usize,
    },
    /// A sinusoid added to the output.
    Periodic {
        /// Frequency, Hz.
        freq_hz: f64,
        /// Amplitude, output units.
        amplitude: f64,
        /// Phase, rad.
        phase: f64,
    },
    /// A linear drift added to the output.
    Drift {
        /// Rate, output units per second.
        rate_per_s: f64,
    },
    /// One channel read through a load cell's filter: a first-order lag `tau_s`, then a delay
    /// `delay_s` ([`lag_column`]).
    SensorLag {
        /// Delay, s.
        delay_s: f64,
        /// First-order lag, s.
        tau_s: f64,
        /// The log's row period, s (the delay's tolerance is one row).
        dt_s: f64,
    },
    /// The output scaled by the supply voltage.
    SupplySag {
        /// Relative gain change per volt, 1/V.
        gain_per_volt: f64,
        /// Synthesised battery voltage at the start, V (unused when the log has a voltage).
        v_start: f64,
        /// Synthesised battery voltage at the end, V.
        v_end: f64,
    },
}

/// The effects injected.
pub const EFFECTS: [EffectName; 4] = [
    EffectName::DeadTime,
    EffectName::PeriodicDisturbance,
    EffectName::BaselineDrift,
    EffectName::SupplySag,
];

/// The effects injected into one channel of a stand's log, found against its other channels.
pub const STAND_EFFECTS: [EffectName; 1] = [EffectName::SensorLag];

impl Injection {
    /// The published name of the effect it should be found as.
    pub fn effect(&self) -> EffectName {
        match self {
            Injection::SensorLag { .. } => STAND_EFFECTS[0],
            Injection::DeadTime { .. } => EFFECTS[0],
            Injection::Periodic { .. } => EFFECTS[1],
            Injection::Drift { .. } => EFFECTS[2],
            Injection::SupplySag { .. } => EFFECTS[3],
        }
    }

    /// A random draw of effect `effect` (one of [`EFFECTS`]) sized to log `s`, so that it is
    /// comparable to what the log itself holds (`σ` = the output's standard deviation, `T` =
    /// the record's duration): a delay of 2–6 samples; a sinusoid of 0.1–0.3 σ between 20
    /// periods per record and a quarter of the sample rate (log-uniform: unrelated to any
    /// staircase or sweep of the log); a drift of 0.3–1 σ over the record, either sign; a sag
    /// with thrust ∝ V^n, `n` 1–2 (a propeller's speed ∝ the voltage gives `n` = 2), i.e.
    /// `g = n / V̄` per volt at the mean voltage `V̄`: of the log's own voltage when it has one
    /// (0.27–0.54 per volt on a 1-cell log at 3.7 V), else of a battery falling 2–3.5 V from
    /// 16.8 V (0.066–0.13 per volt).
    pub fn draw(effect: EffectName, s: &Samples, rng: &mut impl Rng) -> Option<Injection> {
        let sigma = std_dev(&s.y);
        let span = s.u.len() as f64 * s.dt_s;
        Some(match effect {
            EffectName::DeadTime => Injection::DeadTime {
                samples: rng.gen_range(2..=6),
            },
            EffectName::PeriodicDisturbance => {
                let (lo, hi) = ((20.0 / span).ln(), (0.25 / s.dt_s).ln());
                Injection::Periodic {
                    freq_hz: rng.gen_range(lo..hi).exp(),
                    amplitude: rng.gen_range(0.1..0.3) * sigma,
                    phase: rng.gen_range(0.0..std::f64::consts::TAU),
                }
            }
            EffectName::BaselineDrift => {
                let sign = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
                Injection::Drift {
                    rate_per_s: sign * rng.gen_range(0.3..1.0) * sigma / span,
                }
            }
            // A load cell's lag against the rotor: a delay of 1–4 rows and a lag of 2–8 rows
            // (log-uniform), neither a whole number of rows.
            EffectName::SensorLag => Injection::SensorLag {
                delay_s: rng.gen_range(1.0..4.0) * s.dt_s,
                tau_s: rng.gen_range(2f64.ln()..8f64.ln()).exp() * s.dt_s,
                dt_s: s.dt_s,
            },
            EffectName::SupplySag => {
                let v_start = 16.8;
                let v_end = v_start - rng.gen_range(2.0..3.5);
                let v_mean = s
                    .voltage
                    .as_deref()
                    .map_or(0.5 * (v_start + v_end), mean)
                    .abs()
                    .max(1e-6);
                Injection::SupplySag {
                    gain_per_volt: rng.gen_range(1.0..2.0) / v_mean,
                    v_start,
                    v_end,
                }
            }
            _ => return None,
        })
    }
}

impl Samples {
    /// Channels `input`, `output` and (when given and present) `voltage` of `rec`; `None` when
    /// `input` or `output` is absent.
    pub fn from_record(
        rec: &Record,
        input: &str,
        output: &str,
        voltage: Option<&str>,
    ) -> Option<Samples> {
        let data = |n: &str| rec.channel(n).map(|c| c.data.clone());
        Some(Samples {
            dt_s: rec.dt_s,
            t0_s: rec.t0_s,
            u: data(input)?,
            y: data(output)?,
            voltage: voltage.and_then(data),
        })
    }

    /// The samples as a CSV file: `t_s,u,y` and `voltage_V` when present; a missing (NaN)
    /// sample is an empty cell.
    pub fn to_csv(&self) -> String {
        let cell = |x: f64| {
            if x.is_finite() {
                format!("{x}")
            } else {
                String::new()
            }
        };
        let mut s = String::from(if self.voltage.is_some() {
            "t_s,u,y,voltage_V\n"
        } else {
            "t_s,u,y\n"
        });
        for k in 0..self.u.len() {
            let t = self.t0_s + k as f64 * self.dt_s;
            s += &format!("{t},{},{}", cell(self.u[k]), cell(self.y[k]));
            if let Some(v) = &self.voltage {
                s += &format!(",{}", cell(v[k]));
            }
            s.push('\n');
        }
        s
    }
}

/// `s` with `inj` added (module table).
pub fn inject(s: &Samples, inj: &Injection) -> Samples {
    let mut out = s.clone();
    let t = |k: usize| k as f64 * s.dt_s;
    match *inj {
        Injection::DeadTime { samples } => {
            for k in 0..s.y.len() {
                out.y[k] = s.y[k.saturating_sub(samples)];
            }
        }
        Injection::SensorLag { delay_s, tau_s, .. } => {
            out.y = lag_column(&s.y, s.dt_s, delay_s, tau_s);
        }
        Injection::Periodic {
            freq_hz,
            amplitude,
            phase,
        } => {
            let w = std::f64::consts::TAU * freq_hz;
            for (k, y) in out.y.iter_mut().enumerate() {
                *y += amplitude * (w * t(k) + phase).sin();
            }
        }
        Injection::Drift { rate_per_s } => {
            for (k, y) in out.y.iter_mut().enumerate() {
                *y += rate_per_s * t(k);
            }
        }
        Injection::SupplySag {
            gain_per_volt,
            v_start,
            v_end,
        } => {
            let n = s.y.len();
            let volt = s.voltage.clone().unwrap_or_else(|| {
                let last = n.saturating_sub(1).max(1) as f64;
                (0..n)
                    .map(|k| v_start + (v_end - v_start) * k as f64 / last)
                    .collect()
            });
            let v_mean = mean(&volt);
            for (y, v) in out.y.iter_mut().zip(&volt) {
                *y *= 1.0 + gain_per_volt * (v - v_mean);
            }
            out.voltage = Some(volt);
        }
    }
    out
}

/// Column `y` (every `dt_s`; NaN: missing, kept missing) read through a load cell's filter:
/// a first-order lag `s' = (y − s)/τ` with `y` linear between samples (exact:
/// `s⁺ = a s + (1 − a) y_k + (1 − τ(1 − a)/dt)(y_{k+1} − y_k)`, `a = e^{−dt/τ}`, from the
/// steady state of the first sample), then delayed by `delay_s` (linear interpolation between
/// samples, the first sample held before the start). Gaps are bridged by the last value
/// while filtering.
pub fn lag_column(y: &[f64], dt_s: f64, delay_s: f64, tau_s: f64) -> Vec<f64> {
    let Some(first) = y.iter().copied().find(|v| v.is_finite()) else {
        return y.to_vec();
    };
    let mut last = first;
    let x: Vec<f64> = y
        .iter()
        .map(|&v| {
            if v.is_finite() {
                last = v;
            }
            last
        })
        .collect();
    let a = (-dt_s / tau_s).exp();
    let ramp = 1.0 - tau_s * (1.0 - a) / dt_s;
    let mut lagged = Vec::with_capacity(x.len());
    let mut s = x[0];
    lagged.push(s);
    for w in x.windows(2) {
        s = a * s + (1.0 - a) * w[0] + ramp * (w[1] - w[0]);
        lagged.push(s);
    }
    let d = delay_s / dt_s;
    (0..x.len())
        .map(|k| {
            if !y[k].is_finite() {
                return f64::NAN;
            }
            let t = (k as f64 - d).max(0.0);
            let i = t.floor() as usize;
            let f = t - i as f64;
            match lagged.get(i + 1) {
                Some(next) => lagged[i] + f * (next - lagged[i]),
                None => lagged[i.min(lagged.len() - 1)],
            }
        })
        .collect()
}

/// What `diagnose` made of one injection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// The effect was named.
    pub found: bool,
    /// Its parameter's error: samples for a dead time, relative (found/expected − 1)
    /// otherwise; `None` when not found.
    pub error: Option<f64>,
}

impl Outcome {
    /// Found, with the parameter within [`tolerance`].
    pub fn within(&self, inj: &Injection) -> bool {
        self.found && self.error.is_some_and(|e| e.abs() <= tolerance(inj))
    }
}

/// The parameter tolerance per effect, and why:
/// - dead time ±1 sample: the delay is fitted on the whole-sample grid, and a log's own
///   dynamics trade a sample of delay against phase in `fn` and `ζ`;
/// - sinusoid: 1 % on the frequency (the fitted line of a record of ≥ 20 periods is far
///   sharper) and 25 % on the amplitude (checked as the error, the frequency must also hold):
///   the log's own coloured residual near `f` adds to the fitted amplitude;
/// - drift 25 %: the log's own slow dynamics and offset trade against a line over a finite
///   record;
/// - sensor lag 25 % on `τ`, its delay within one row (issue 29, item 6);
/// - supply sag 30 %: the log's own supply dependence adds to the injected one where the clean
///   log does not name it (dantonio's ramp: median 26 %, at most 41 % high), and a log's own
///   dependence on the drive beside an injected one on the output is no single term
///   (vanderploeg: 23 % low; docs/injection.md, "Which side the supply scales").
pub fn tolerance(inj: &Injection) -> f64 {
    match inj {
        Injection::DeadTime { .. } => 1.0,
        Injection::Periodic { .. } => 0.25,
        Injection::Drift { .. } => 0.25,
        Injection::SupplySag { .. } => 0.30,
        Injection::SensorLag { .. } => 0.25,
    }
}

/// Judges the findings (`diagnose --json`'s `findings` array) of the injected log against
/// those of the clean log: the effect must be named; its parameter is compared with the
/// injected one plus what the clean log already had for an additive parameter (a delay, a
/// drift rate, a supply sag's gain per volt: the relative slopes of two gains that multiply
/// add).
pub fn judge(inj: &Injection, clean: &[Value], injected: &[Value]) -> Outcome {
    let name = inj.effect();
    let param = |fs: &[Value], key: &str| {
        fs.iter()
            .find(|f| f["effect"] == name.as_str())
            .and_then(|f| f[key].as_f64())
    };
    let rel = |got: f64, want: f64| got / want - 1.0;
    let error = match *inj {
        Injection::DeadTime { samples } => {
            let before = param(clean, "delay_samples").unwrap_or(0.0);
            param(injected, "delay_samples").map(|d| d - before - samples as f64)
        }
        Injection::Periodic {
            freq_hz, amplitude, ..
        } => param(injected, "freq_hz").and_then(|f| {
            let a = param(injected, "amplitude")?;
            // The frequency must hold (1 %); then the amplitude's error is the figure.
            Some(if rel(f, freq_hz).abs() <= 0.01 {
                rel(a, amplitude)
            } else {
                f64::INFINITY
            })
        }),
        Injection::Drift { rate_per_s } => {
            let before = param(clean, "rate_per_s").unwrap_or(0.0);
            param(injected, "rate_per_s").map(|r| rel(r - before, rate_per_s))
        }
        Injection::SensorLag {
            delay_s,
            tau_s,
            dt_s,
        } => {
            // Delays and lags in series add (the lags to first order): the injected ones on
            // top of what the clean log's thrust already had.
            let lag = |fs: &[Value], key: &str| {
                fs.iter()
                    .find(|f| f["effect"] == name.as_str() && f["channel"] == "thrust")
                    .and_then(|f| f[key].as_f64())
            };
            let (d0, t0) = (
                lag(clean, "delay_s").unwrap_or(0.0),
                lag(clean, "tau_s").unwrap_or(0.0),
            );
            lag(injected, "delay_s")
                .zip(lag(injected, "tau_s"))
                .map(|(d, t)| {
                    if (d - d0 - delay_s).abs() <= dt_s {
                        rel(t - t0, tau_s)
                    } else {
                        f64::INFINITY
                    }
                })
        }
        Injection::SupplySag { gain_per_volt, .. } => {
            // Gains multiply: (1 + g₀ ΔV)(1 + g ΔV) has the relative slope g₀ + g at the mean.
            let before = param(clean, "gain_per_volt").unwrap_or(0.0);
            param(injected, "gain_per_volt").map(|g| rel(g - before, gain_per_volt))
        }
    };
    Outcome {
        found: error.is_some(),
        error,
    }
}

fn mean(x: &[f64]) -> f64 {
    let (s, n) = x
        .iter()
        .filter(|v| v.is_finite())
        .fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    s / n.max(1) as f64
}

fn std_dev(x: &[f64]) -> f64 {
    let m = mean(x);
    let (s, n) = x
        .iter()
        .filter(|v| v.is_finite())
        .fold((0.0, 0usize), |(s, n), v| (s + (v - m).powi(2), n + 1));
    (s / n.max(1) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::SeedableRng;
    use serde_json::json;

    fn samples() -> Samples {
        Samples {
            dt_s: 0.5,
            t0_s: 1.0,
            u: vec![0.0, 1.0, 1.0, 0.0],
            y: vec![0.0, 2.0, f64::NAN, 1.0],
            voltage: None,
        }
    }

    #[test]
    fn each_injection_changes_the_output_as_documented() {
        let s = samples();
        let d = inject(&s, &Injection::DeadTime { samples: 1 });
        assert_eq!(d.y[..3], [0.0, 0.0, 2.0]);
        assert!(d.y[3].is_nan());
        let r = inject(&s, &Injection::Drift { rate_per_s: 2.0 });
        assert_eq!((r.y[0], r.y[1], r.y[3]), (0.0, 3.0, 4.0));
        let p = Injection::Periodic {
            freq_hz: 0.5,
            amplitude: 1.0,
            phase: std::f64::consts::FRAC_PI_2,
        };
        let p = inject(&s, &p);
        assert!((p.y[0] - 1.0).abs() < 1e-12 && (p.y[1] - 2.0).abs() < 1e-12);
        let sag = Injection::SupplySag {
            gain_per_volt: 0.1,
            v_start: 16.0,
            v_end: 13.0,
        };
        let g = inject(&s, &sag);
        assert_eq!(g.voltage.as_deref(), Some(&[16.0, 15.0, 14.0, 13.0][..]));
        assert!((g.y[1] - 2.0 * 1.05).abs() < 1e-12 && (g.y[3] - 0.85).abs() < 1e-12);
        // The log's own voltage is used when it has one.
        let own = Samples {
            voltage: Some(vec![12.0, 12.0, 12.0, 10.0]),
            ..s
        };
        assert_eq!(inject(&own, &sag).voltage, own.voltage);
    }

    #[test]
    fn the_csv_keeps_time_missing_cells_and_the_voltage() {
        assert_eq!(
            samples().to_csv(),
            "t_s,u,y\n1,0,0\n1.5,1,2\n2,1,\n2.5,0,1\n"
        );
        let v = Samples {
            voltage: Some(vec![16.0; 4]),
            ..samples()
        };
        assert!(v.to_csv().starts_with("t_s,u,y,voltage_V\n1,0,0,16\n"));
    }

    #[test]
    fn draws_are_sized_to_the_log_and_seeded() {
        let s = Samples {
            dt_s: 0.01,
            t0_s: 0.0,
            u: vec![0.0; 1000],
            y: (0..1000)
                .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
                .collect(),
            voltage: None,
        };
        for e in EFFECTS {
            let a = Injection::draw(e, &s, &mut StdRng::seed_from_u64(3)).unwrap();
            let b = Injection::draw(e, &s, &mut StdRng::seed_from_u64(3)).unwrap();
            assert_eq!((a, a.effect()), (b, e));
            match a {
                Injection::Periodic {
                    freq_hz, amplitude, ..
                } => assert!((2.0..25.0).contains(&freq_hz) && (0.1..0.3).contains(&amplitude)),
                Injection::Drift { rate_per_s } => assert!((0.03..0.1).contains(&rate_per_s.abs())),
                _ => {}
            }
        }
        assert!(
            Injection::draw(EffectName::ExtraMode, &s, &mut StdRng::seed_from_u64(3)).is_none()
        );
    }

    #[test]
    fn a_sag_is_a_power_of_the_logs_own_voltage() {
        let mut s = Samples {
            dt_s: 0.01,
            t0_s: 0.0,
            u: vec![0.0; 100],
            y: vec![0.0; 100],
            voltage: None,
        };
        // thrust ∝ V^n with n in 1..2: g = n / V̄, with V̄ the synthetic battery's mean ...
        for seed in 0..20 {
            let Injection::SupplySag {
                gain_per_volt,
                v_start,
                v_end,
            } = Injection::draw(EffectName::SupplySag, &s, &mut StdRng::seed_from_u64(seed))
                .unwrap()
            else {
                panic!("not a sag");
            };
            let n = gain_per_volt * 0.5 * (v_start + v_end);
            assert!((1.0..2.0).contains(&n), "{n}");
        }
        // ... or the log's own (a 1-cell log at 3.7 V sags 4.5 times as much per volt).
        s.voltage = Some(vec![3.7; 100]);
        for seed in 0..20 {
            let Some(Injection::SupplySag { gain_per_volt, .. }) =
                Injection::draw(EffectName::SupplySag, &s, &mut StdRng::seed_from_u64(seed))
            else {
                panic!("not a sag");
            };
            assert!(
                (1.0..2.0).contains(&(gain_per_volt * 3.7)),
                "{gain_per_volt}"
            );
        }
    }

    #[test]
    fn the_judge_adds_what_the_clean_log_had_and_needs_the_effect_named() {
        let inj = Injection::DeadTime { samples: 3 };
        let clean = [json!({"effect": "dead_time", "delay_samples": 2})];
        let found = [json!({"effect": "dead_time", "delay_samples": 6})];
        let o = judge(&inj, &clean, &found);
        assert_eq!(o.error, Some(1.0));
        assert!(o.within(&inj));
        assert!(!judge(&inj, &[], &found).within(&inj));
        let none = judge(&inj, &clean, &[json!({"effect": "extra_mode"})]);
        assert!(!none.found && !none.within(&inj));
        let p = Injection::Periodic {
            freq_hz: 10.0,
            amplitude: 1.0,
            phase: 0.0,
        };
        let off = [json!({"effect": "periodic_disturbance", "freq_hz": 10.5, "amplitude": 1.0})];
        assert!(judge(&p, &[], &off).found && !judge(&p, &[], &off).within(&p));
        let on = [json!({"effect": "periodic_disturbance", "freq_hz": 10.01, "amplitude": 1.2})];
        assert!(judge(&p, &[], &on).within(&p));
        let sag = Injection::SupplySag {
            gain_per_volt: 0.1,
            v_start: 16.8,
            v_end: 14.0,
        };
        let clean = [json!({"effect": "supply_sag", "gain_per_volt": 0.08})];
        let found = [json!({"effect": "supply_sag", "gain_per_volt": 0.17})];
        let o = judge(&sag, &clean, &found);
        assert!((o.error.unwrap() - -0.1).abs() < 1e-9 && o.within(&sag));
        assert!(!judge(&sag, &[], &found).within(&sag));
    }
}
