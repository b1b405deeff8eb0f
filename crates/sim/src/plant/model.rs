//! The plant that steps: its core (the exactly discretised 2nd-order response, or the motor of
//! [`super::motor`]), the effects applied around it, the derived channels and the load cell's
//! noise, quantisation and saturation (formulas in the module doc of [`super`]).

use nalgebra::{Matrix2, Vector2};
use propid_numerics::discretise::discretise_second_order;
use propid_numerics::nonlinear_core::NonlinearCore;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use super::motor::Motor;
use super::sensors::{SensorConfig, SensorState, SensorsConfig};
use super::{PlantConfig, PlantError, PlantKind};
use crate::effects::EffectState;

/// One sample of every channel the stand measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Measured thrust (noise, quantisation, effects), newtons.
    pub thrust_n: f64,
    /// Torque, newton metres.
    pub torque_nm: f64,
    /// Rotor speed, rev/min.
    pub rpm: f64,
    /// Supply voltage at the ESC, volts.
    pub voltage_v: f64,
    /// Supply current, amperes.
    pub current_a: f64,
    /// True when the load cell's converter (or a `saturation` effect on the sensor) clipped.
    pub adc_saturated: bool,
}

/// What produces the true thrust from the input the effects hand on.
#[derive(Debug, Clone)]
enum Core {
    /// The 2nd-order response: `x = [T, T']`, `x_{k+1} = A x_k + B u_k`.
    SecondOrder {
        a: Matrix2<f64>,
        b: Vector2<f64>,
        x: Vector2<f64>,
        /// The core with a nonlinear law (`asymmetric_dynamics`, `stiffness_nonlinearity`);
        /// `None`: the exact linear step `a`, `b`.
        nonlinear: Option<NonlinearCore>,
    },
    /// The motor (speed lag, dead time, thrust ∝ speed²).
    Motor(Motor),
}

/// Steps per sample of a nonlinear core in the plant (finer than the models `diagnose` fits).
pub const NONLINEAR_SUBSTEPS: usize = 8;

/// The simulated plant. Create it with [`Plant::new`], drive it with [`Plant::step`].
#[derive(Debug, Clone)]
pub struct Plant {
    cfg: PlantConfig,
    dt_s: f64,
    core: Core,
    k: u64,
    noise: Option<Normal<f64>>,
    rng: StdRng,
    effects: EffectState,
    last_current_a: f64,
    /// The sensors of thrust, torque, rpm and current (`[plant.sensors]`).
    sensors: Sensors,
}

/// The plant's sensors ([`super::sensors`]), `None` where a channel reads its quantity as it is.
#[derive(Debug, Clone)]
struct Sensors {
    thrust: Option<SensorState>,
    torque: Option<SensorState>,
    rpm: Option<SensorState>,
    current: Option<SensorState>,
}

impl Sensors {
    fn new(cfg: &SensorsConfig, dt_s: f64) -> Sensors {
        let make = |c: &Option<SensorConfig>| c.as_ref().map(|c| SensorState::new(c, dt_s));
        Sensors {
            thrust: make(&cfg.thrust),
            torque: make(&cfg.torque),
            rpm: make(&cfg.rpm),
            current: make(&cfg.current),
        }
    }
}

/// `x` through sensor `s` (lag, delay, offset, creep, then held) at sample `k`.
fn read(s: &mut Option<SensorState>, x: f64, k: u64) -> f64 {
    match s {
        Some(s) => {
            let y = s.shape(x, k);
            s.hold(y, k)
        }
        None => x,
    }
}

impl Plant {
    /// A plant at rest (throttle 0, thrust 0) sampled every `dt_s` seconds, with noise drawn from
    /// a generator seeded by `seed` (same seed, same inputs ⇒ same measurements).
    pub fn new(cfg: &PlantConfig, dt_s: f64, seed: u64) -> Result<Plant, PlantError> {
        cfg.validate(dt_s)?;
        let core = match cfg.kind {
            PlantKind::SecondOrder => {
                let (a, b) =
                    discretise_second_order(cfg.fn_hz, cfg.zeta, cfg.gain_n_per_throttle, dt_s);
                let law = cfg.effects.core_law();
                let nonlinear = (!law.is_linear()).then(|| {
                    NonlinearCore::new(
                        cfg.fn_hz,
                        cfg.zeta,
                        cfg.gain_n_per_throttle,
                        dt_s,
                        law,
                        NONLINEAR_SUBSTEPS,
                    )
                });
                Core::SecondOrder {
                    a,
                    b,
                    x: Vector2::zeros(),
                    nonlinear,
                }
            }
            PlantKind::Motor => Core::Motor(Motor::new(cfg, dt_s)?),
        };
        let noise = if cfg.noise_rms_n > 0.0 {
            Some(
                Normal::new(0.0, cfg.noise_rms_n).map_err(|_| PlantError::InvalidParameter {
                    key: "plant.noise_rms_n",
                    value: cfg.noise_rms_n,
                    reason: "must be a finite standard deviation",
                })?,
            )
        } else {
            None
        };
        let effects = EffectState::new(&cfg.effects, cfg, dt_s, seed)?;
        Ok(Plant {
            cfg: cfg.clone(),
            dt_s,
            core,
            k: 0,
            noise,
            rng: StdRng::seed_from_u64(seed),
            effects,
            last_current_a: cfg.idle_current_a,
            sensors: Sensors::new(&cfg.sensors, dt_s),
        })
    }

    /// The configuration the plant was built from.
    pub fn config(&self) -> &PlantConfig {
        &self.cfg
    }

    /// Sample period, seconds.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// Time of the next sample, seconds since the plant was created.
    pub fn time_s(&self) -> f64 {
        self.k as f64 * self.dt_s
    }

    /// The discrete linear core `(A, B, C)` with state `[T, T']`, `C = [1, 0]`, `D = 0`, of the
    /// 2nd-order plant; `None` for the motor (see [`PlantConfig::linearise`]).
    pub fn linear_core(&self) -> Option<(Matrix2<f64>, Vector2<f64>)> {
        match &self.core {
            Core::SecondOrder { a, b, .. } => Some((*a, *b)),
            Core::Motor(_) => None,
        }
    }

    /// True thrust of the core's state, newtons.
    fn thrust_true(&self) -> f64 {
        match &self.core {
            Core::SecondOrder { x, .. } => x[0],
            Core::Motor(m) => m.thrust_n(&self.cfg),
        }
    }

    /// Puts the plant in steady state at `throttle` (as if it had been held there for ever),
    /// without advancing time. Effects with memory (delay lines, extra mode) settle too.
    pub fn settle(&mut self, throttle: f64) {
        self.settle_at_supply(throttle, None);
    }

    /// [`Plant::settle`] with the supply at `supply_v` (a measured voltage, [`Plant::step_at_supply`])
    /// when given.
    pub fn settle_at_supply(&mut self, throttle: f64, supply_v: Option<f64>) {
        let throttle = throttle.clamp(0.0, 1.0);
        let v = supply_v.unwrap_or(self.cfg.battery_v);
        let u = self.effects.input_map(throttle, v, &self.cfg);
        let t_s = self.time_s();
        match &mut self.core {
            Core::SecondOrder { x, nonlinear, .. } => {
                *x = match nonlinear {
                    Some(core) => core.settle(u),
                    None => Vector2::new(self.cfg.gain_n_per_throttle * u, 0.0),
                }
            }
            Core::Motor(m) => match supply_v {
                Some(v) => m.settle_at(&self.cfg, throttle, u, v),
                None => m.settle(&self.cfg, throttle, u, t_s),
            },
        }
        let thrust = self.thrust_true();
        // The load-cell path settles at what the thrust sensor reads (its offset with it).
        let read = thrust + self.cfg.sensors.thrust.map_or(0.0, |s| s.offset);
        self.effects.settle(throttle, read);
        let (rpm, current) = match &self.core {
            Core::Motor(m) => {
                let n = m.speed_rpm();
                (n, self.cfg.motor.current_a(&self.cfg, n, 0.0))
            }
            Core::SecondOrder { .. } => (
                self.cfg.rpm_at_reference
                    * (thrust.max(0.0) / self.cfg.reference_thrust_n()).sqrt(),
                self.cfg.current_a(thrust),
            ),
        };
        self.last_current_a = current;
        let s = &mut self.sensors;
        let torque = self.cfg.torque_m * thrust.max(0.0);
        for (sensor, x) in [
            (&mut s.thrust, thrust),
            (&mut s.torque, torque),
            (&mut s.rpm, rpm),
            (&mut s.current, current),
        ] {
            if let Some(sensor) = sensor {
                sensor.settle(x);
            }
        }
    }

    /// Advances one sample with `throttle` (0..1; NaN counts as 0, out-of-range values are
    /// clamped as an ESC would) held during this sample; returns what the stand measures at the
    /// start of the sample (`y_k = C x_k`, see the module doc).
    pub fn step(&mut self, throttle: f64) -> Measurement {
        self.step_at_supply(throttle, None)
    }

    /// [`Plant::step`] with the supply at `supply_v` volts when given (a log's measured
    /// voltage, replayed: the battery model is not used, the current is drawn at that voltage).
    pub fn step_at_supply(&mut self, throttle: f64, supply_v: Option<f64>) -> Measurement {
        let throttle = if throttle.is_finite() {
            throttle.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let t_s = self.time_s();
        let k = self.k;
        let thrust_true = self.thrust_true();
        let v_oc = self.cfg.battery_v - self.cfg.discharge_v_per_s * t_s;
        let r_ohm = self.cfg.internal_resistance_ohm;
        // Input path: dead time (the motor's ESC dead time after the effect's), then the
        // current of this sample (the motor's with its acceleration term, `n'` under the
        // supply the current itself sags) and that supply.
        let delayed = self.effects.delay(throttle);
        let (esc, current_a) = match &mut self.core {
            Core::Motor(m) => {
                let esc = m.delay(delayed);
                let m = &*m;
                let n = m.speed_rpm();
                let (cfg, effects) = (&self.cfg, &self.effects);
                let current = |v: f64| {
                    let u = effects.input_map(esc, v, cfg);
                    cfg.motor.current_a(cfg, n, m.rate(cfg, u, v))
                };
                // I(V) is affine in the supply (n' ∝ n_ss ∝ V): the loop V = V_oc − R I(V)
                // solved at once, `I = I_oc − s R I_oc / (1 + R s)` with `s = dI/dV`.
                if let Some(v) = supply_v {
                    (esc, current(v))
                } else {
                    let i_oc = current(v_oc);
                    let slope = i_oc - current(v_oc - 1.0);
                    let loop_gain = (1.0 + r_ohm * slope).max(0.1);
                    (esc, i_oc - slope * r_ohm * i_oc / loop_gain)
                }
            }
            Core::SecondOrder { .. } => (delayed, self.cfg.current_a(thrust_true)),
        };
        let voltage_v = supply_v.unwrap_or(v_oc - r_ohm * current_a);
        // Measured thrust: the sensor, the load-cell path (extra mode), additive terms, noise,
        // clip, quantum, then held over the sensor's refresh interval.
        let (thrust_read, refreshed) = match &mut self.sensors.thrust {
            Some(s) => (s.shape(thrust_true, k), true),
            None => (thrust_true, false),
        };
        let mut thrust = self.effects.sensor_path(thrust_read);
        thrust += self.effects.additive(t_s);
        if let Some(n) = self.noise {
            thrust += n.sample(&mut self.rng);
        }
        let (thrust, mut saturated) = self.effects.sensor_clip(thrust);
        let fs = self.cfg.adc_full_scale_n;
        if thrust.abs() >= fs {
            saturated = true;
        }
        let mut thrust = quantise(thrust.clamp(-fs, fs), self.cfg.quantum_n);
        if let (true, Some(s)) = (refreshed, &mut self.sensors.thrust) {
            thrust = s.hold(thrust, k);
        }
        let rpm = match &mut self.core {
            Core::SecondOrder { a, b, x, nonlinear } => {
                let u = self.effects.input_map(esc, voltage_v, &self.cfg);
                *x = match nonlinear {
                    Some(core) => core.step(*x, u),
                    None => *a * *x + *b * u,
                };
                let t_ref = self.cfg.reference_thrust_n();
                self.cfg.rpm_at_reference * (thrust_true.max(0.0) / t_ref).sqrt()
            }
            Core::Motor(m) => {
                let rpm = m.speed_rpm();
                let u = self.effects.input_map(esc, voltage_v, &self.cfg);
                m.advance(&self.cfg, u, voltage_v);
                rpm
            }
        };
        self.k += 1;
        self.last_current_a = current_a;
        let t_pos = thrust_true.max(0.0);
        let s = &mut self.sensors;
        Measurement {
            thrust_n: thrust,
            torque_nm: read(&mut s.torque, self.cfg.torque_m * t_pos, k),
            rpm: read(&mut s.rpm, rpm, k),
            voltage_v,
            current_a: read(&mut s.current, current_a, k),
            adc_saturated: saturated,
        }
    }

    /// The current drawn at the last step, amperes.
    pub fn last_current_a(&self) -> f64 {
        self.last_current_a
    }
}

/// Rounds `v` to the nearest multiple of `q` (no rounding for `q == 0`).
fn quantise(v: f64, q: f64) -> f64 {
    if q > 0.0 {
        (v / q).round() * q
    } else {
        v
    }
}
