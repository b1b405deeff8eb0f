//! The plant's configuration (the `[plant]` table of `config/sim.toml`): keys with their units,
//! defaults, and the range checks that name the first bad key.

use propid_numerics::stand_model::{
    load, speed_power, CurrentLaw, RotorLaw, SpeedMap, StandParams, Supply,
};
use serde::Deserialize;

use super::sensors::SensorsConfig;
use crate::effects::EffectsConfig;

/// A plant parameter that cannot be simulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlantError {
    /// A configuration value is out of range (the key and the value are named).
    #[error("plant parameter `{key}` = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Configuration key, e.g. `plant.fn_hz` or `plant.effects.dead_time.delay_s`.
        key: &'static str,
        /// The refused value.
        value: f64,
        /// What the valid range is.
        reason: &'static str,
    },
    /// An effect configured for a plant kind that has no place for it (the key is named).
    #[error("`{key}` does not apply to a plant of kind `{kind}`: {reason}")]
    NotForKind {
        /// Configuration key, e.g. `plant.effects.asymmetric_dynamics`.
        key: &'static str,
        /// The plant's `kind`.
        kind: &'static str,
        /// What to use instead.
        reason: &'static str,
    },
}

/// Which plant steps: the `kind` key of `[plant]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlantKind {
    /// The linear 2nd-order thrust response (`fn_hz`, `zeta`, `gain_n_per_throttle`): the same
    /// dynamics at every throttle. The default of the code and of the tests.
    #[default]
    SecondOrder,
    /// The motor ([`super::motor`], `[plant.motor]`): thrust ∝ speed², a first-order speed lag
    /// slower down than up, dead time, supply sag. `config/sim.toml` and `propid demo` use it.
    Motor,
}

/// Configuration of the simulated plant (the `[plant]` table of `config/sim.toml`).
/// Every key has its unit in its name or its doc; unknown keys are refused.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantConfig {
    /// Which plant steps (`"second_order"`, the default, or `"motor"`).
    pub kind: PlantKind,
    /// The motor plant's parameters (`[plant.motor]`; used when `kind = "motor"`).
    pub motor: MotorConfig,
    /// Natural frequency of the thrust response, Hz (> 0, below the Nyquist frequency).
    pub fn_hz: f64,
    /// Damping ratio of the thrust response (> 0; above 1 the poles are real, overdamped).
    pub zeta: f64,
    /// Small-signal (and static) thrust gain, newtons per unit throttle (> 0).
    pub gain_n_per_throttle: f64,
    /// Throttle (0..1, exclusive) at which the derived channels and the static map of the
    /// `static_nonlinearity` effect are referenced.
    pub reference_throttle: f64,
    /// RMS of the white Gaussian noise added to the thrust, newtons (≥ 0).
    pub noise_rms_n: f64,
    /// Load-cell resolution, newtons (≥ 0; 0 = no quantisation).
    pub quantum_n: f64,
    /// The load cell's converter saturates at ± this thrust, newtons (> 0).
    pub adc_full_scale_n: f64,
    /// Torque per thrust, metres (≥ 0): `torque_nm = torque_m · thrust_n`.
    pub torque_m: f64,
    /// Rotor speed at the reference throttle in steady state, rev/min (≥ 0).
    pub rpm_at_reference: f64,
    /// Supply current with the rotor at rest, amperes (≥ 0).
    pub idle_current_a: f64,
    /// Extra current at the reference thrust, amperes (≥ 0); scales with thrust^1.5.
    pub current_at_reference_a: f64,
    /// Open-circuit battery voltage at t = 0, volts (> 0).
    pub battery_v: f64,
    /// Battery internal resistance, ohms (≥ 0).
    pub internal_resistance_ohm: f64,
    /// Fall of the open-circuit voltage with time as the battery discharges, volts per second
    /// (≥ 0).
    pub discharge_v_per_s: f64,
    /// Effects switched on (`[plant.effects.*]`); all off by default.
    pub effects: EffectsConfig,
    /// A sensor per channel (`[plant.sensors.*]`: delay, lag, refresh, offset, creep); none
    /// by default ([`super::sensors`]).
    pub sensors: SensorsConfig,
}

impl Default for PlantConfig {
    fn default() -> Self {
        PlantConfig {
            kind: PlantKind::SecondOrder,
            motor: MotorConfig::default(),
            fn_hz: 12.0,
            zeta: 0.7,
            gain_n_per_throttle: 12.0,
            reference_throttle: 0.5,
            noise_rms_n: 0.01,
            quantum_n: 0.001,
            adc_full_scale_n: 50.0,
            torque_m: 0.012,
            rpm_at_reference: 18000.0,
            idle_current_a: 0.4,
            current_at_reference_a: 8.0,
            battery_v: 16.8,
            internal_resistance_ohm: 0.05,
            discharge_v_per_s: 0.002,
            effects: EffectsConfig::default(),
            sensors: SensorsConfig::default(),
        }
    }
}

/// Checks `ok` (written as a positive check so that NaN fails) or names the key and the value.
pub(crate) fn check(
    ok: bool,
    key: &'static str,
    value: f64,
    reason: &'static str,
) -> Result<(), PlantError> {
    if ok {
        Ok(())
    } else {
        Err(PlantError::InvalidParameter { key, value, reason })
    }
}

impl PlantConfig {
    /// Checks every value for a sample period `dt_s`; the error names the first bad key.
    pub fn validate(&self, dt_s: f64) -> Result<(), PlantError> {
        check(dt_s.is_finite() && dt_s > 0.0, "dt_s", dt_s, "must be > 0")?;
        let nyquist = 0.5 / dt_s;
        check(
            self.fn_hz.is_finite() && self.fn_hz > 0.0 && self.fn_hz < nyquist,
            "plant.fn_hz",
            self.fn_hz,
            "must be > 0 and below the Nyquist frequency",
        )?;
        check(
            self.zeta.is_finite() && self.zeta > 0.0 && self.zeta <= 20.0,
            "plant.zeta",
            self.zeta,
            "must be in (0, 20]",
        )?;
        let positive = [
            (self.gain_n_per_throttle, "plant.gain_n_per_throttle"),
            (self.adc_full_scale_n, "plant.adc_full_scale_n"),
            (self.battery_v, "plant.battery_v"),
        ];
        for (v, key) in positive {
            check(v.is_finite() && v > 0.0, key, v, "must be > 0")?;
        }
        check(
            self.reference_throttle.is_finite()
                && self.reference_throttle > 0.0
                && self.reference_throttle < 1.0,
            "plant.reference_throttle",
            self.reference_throttle,
            "must be in (0, 1)",
        )?;
        let non_negative = [
            (self.noise_rms_n, "plant.noise_rms_n"),
            (self.quantum_n, "plant.quantum_n"),
            (self.torque_m, "plant.torque_m"),
            (self.rpm_at_reference, "plant.rpm_at_reference"),
            (self.idle_current_a, "plant.idle_current_a"),
            (self.current_at_reference_a, "plant.current_at_reference_a"),
            (
                self.internal_resistance_ohm,
                "plant.internal_resistance_ohm",
            ),
            (self.discharge_v_per_s, "plant.discharge_v_per_s"),
        ];
        for (v, key) in non_negative {
            check(v.is_finite() && v >= 0.0, key, v, "must be >= 0")?;
        }
        self.motor.validate()?;
        if self.kind == PlantKind::Motor {
            let z = self.motor.command_zero;
            check(
                z < self.reference_throttle,
                "plant.motor.command_zero",
                z,
                "must be below plant.reference_throttle",
            )?;
        }
        self.sensors.validate()?;
        self.effects.validate(dt_s)?;
        self.effects_fit_the_kind()
    }

    /// The core effects act on the 2nd-order core; the motor has its own lag per direction and
    /// no spring, so they are refused there rather than silently ignored.
    fn effects_fit_the_kind(&self) -> Result<(), PlantError> {
        if self.kind != PlantKind::Motor {
            return Ok(());
        }
        let misplaced = [
            (
                self.effects.asymmetric_dynamics.is_some(),
                "plant.effects.asymmetric_dynamics",
                "the motor's spin-up and spin-down lags are plant.motor.tau_up_s and tau_down_s",
            ),
            (
                self.effects.stiffness_nonlinearity.is_some(),
                "plant.effects.stiffness_nonlinearity",
                "the cubic spring acts on the 2nd-order core (kind = \"second_order\")",
            ),
        ];
        match misplaced.into_iter().find(|(set, _, _)| *set) {
            Some((_, key, reason)) => Err(PlantError::NotForKind {
                key,
                kind: "motor",
                reason,
            }),
            None => Ok(()),
        }
    }

    /// Thrust at the reference throttle in steady state, newtons (the clean static map; for the
    /// motor, with the battery unloaded).
    pub fn reference_thrust_n(&self) -> f64 {
        match self.kind {
            PlantKind::SecondOrder => self.gain_n_per_throttle * self.reference_throttle,
            PlantKind::Motor => self.motor.thrust_at_reference_n,
        }
    }

    /// Supply current at true thrust `t_n` (momentum theory, see the module doc of
    /// [`super`]): `idle_current_a + current_at_reference_a · (T / T_ref)^{3/2}`.
    pub fn current_a(&self, t_n: f64) -> f64 {
        let r = t_n.max(0.0) / self.reference_thrust_n();
        self.idle_current_a + self.current_at_reference_a * r.powf(1.5)
    }
}

/// The `[plant.motor]` table: the motor plant's own parameters (the battery, the current model,
/// `reference_throttle` and `rpm_at_reference` are the `[plant]` keys).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MotorConfig {
    /// Thrust at `reference_throttle` in steady state with the battery unloaded, newtons (> 0).
    pub thrust_at_reference_n: f64,
    /// Spin-up time constant at `rpm_at_reference`, seconds (> 0).
    pub tau_up_s: f64,
    /// Spin-down time constant at `rpm_at_reference`, seconds (> 0).
    pub tau_down_s: f64,
    /// Exponent `γ` of the time constant's fall with speed, `τ ∝ (n_ref / n)^γ` (0..=2).
    pub tau_speed_exponent: f64,
    /// ESC dead time, seconds (0..=1; rounded to whole samples).
    pub dead_time_s: f64,
    /// The ESC's dead band `u₀`: no speed at or below this throttle (-1 ..< reference_throttle).
    pub command_zero: f64,
    /// Exponent `a` of the speed map `((u − u₀)/(u_ref − u₀))^a` (0.3..=3).
    pub speed_map_exponent: f64,
    /// Exponent `e` of thrust and torque in the speed, `T ∝ nᵉ` (0.5..=4.5; the current's
    /// mechanical power `∝ n^{e+1}`).
    pub thrust_exponent: f64,
    /// `k_J` of the current's acceleration term `k_J n n'`, A per (rev/min · rev/min per s)
    /// (finite, either sign).
    pub current_per_acceleration: f64,
    /// Exponent `b` of the speed's dependence on the supply, `n ∝ (V / V₀)^b` (0..=2; 1: a
    /// duty-cycle ESC on an unloaded motor; a loaded motor's winding takes part of a sag,
    /// `b < 1`: `diagnose`'s `supply_sag`).
    pub speed_voltage_exponent: f64,
}

impl Default for MotorConfig {
    fn default() -> Self {
        MotorConfig {
            thrust_at_reference_n: 6.0,
            tau_up_s: 0.030,
            tau_down_s: 0.040,
            tau_speed_exponent: 0.0,
            dead_time_s: 0.008,
            command_zero: 0.0,
            speed_map_exponent: 1.0,
            thrust_exponent: 2.0,
            current_per_acceleration: 0.0,
            speed_voltage_exponent: 1.0,
        }
    }
}

impl MotorConfig {
    /// Checks every value; the error names the first bad key.
    pub fn validate(&self) -> Result<(), PlantError> {
        let positive = [
            (
                self.thrust_at_reference_n,
                "plant.motor.thrust_at_reference_n",
            ),
            (self.tau_up_s, "plant.motor.tau_up_s"),
            (self.tau_down_s, "plant.motor.tau_down_s"),
        ];
        for (v, key) in positive {
            check(v.is_finite() && v > 0.0, key, v, "must be > 0")?;
        }
        let g = self.tau_speed_exponent;
        let key = "plant.motor.tau_speed_exponent";
        check(
            g.is_finite() && (-1.0..=3.0).contains(&g),
            key,
            g,
            "must be in [-1, 3]",
        )?;
        let d = self.dead_time_s;
        let ok = d.is_finite() && (0.0..=1.0).contains(&d);
        check(ok, "plant.motor.dead_time_s", d, "must be in [0, 1] s")?;
        let z = self.command_zero;
        let ok = z.is_finite() && (-1.0..1.0).contains(&z);
        check(ok, "plant.motor.command_zero", z, "must be in [-1, 1)")?;
        let a = self.speed_map_exponent;
        let ok = a.is_finite() && (0.3..=3.0).contains(&a);
        check(
            ok,
            "plant.motor.speed_map_exponent",
            a,
            "must be in [0.3, 3]",
        )?;
        let b = self.speed_voltage_exponent;
        let ok = b.is_finite() && (0.0..=2.0).contains(&b);
        check(
            ok,
            "plant.motor.speed_voltage_exponent",
            b,
            "must be in [0, 2]",
        )?;
        let e = self.thrust_exponent;
        let ok = e.is_finite() && (0.5..=4.5).contains(&e);
        check(
            ok,
            "plant.motor.thrust_exponent",
            e,
            "must be in [0.5, 4.5]",
        )?;
        let j = self.current_per_acceleration;
        check(
            j.is_finite(),
            "plant.motor.current_per_acceleration",
            j,
            "must be finite",
        )
    }

    /// The thrust coefficient `k_T = T_ref / n_refᵉ`, N per (rev/min)ᵉ.
    pub fn k_t(&self, plant: &PlantConfig) -> f64 {
        self.thrust_at_reference_n / speed_power(plant.rpm_at_reference, self.thrust_exponent)
    }

    /// Thrust `k_T nᵉ` at speed `n` (rev/min), newtons.
    pub fn thrust_n(&self, plant: &PlantConfig, n: f64) -> f64 {
        load(self.k_t(plant), n, self.thrust_exponent)
    }

    /// Supply current at speed `n` (rev/min) and `n'` (rev/min per s), amperes: the stand
    /// model's current law `I₀ + I_ref (n/n_ref)^{e+1} + k_J n n'` (at `e = 2` and `k_J = 0`
    /// the plant's `idle_current_a + current_at_reference_a · (T / T_ref)^{3/2}`).
    pub fn current_a(&self, plant: &PlantConfig, n: f64, n_dot: f64) -> f64 {
        let r = n.max(0.0) / plant.rpm_at_reference;
        plant.idle_current_a
            + plant.current_at_reference_a * speed_power(r, self.thrust_exponent + 1.0)
            + self.current_per_acceleration * n.max(0.0) * n_dot
    }

    /// Dead time in whole samples of `dt_s`.
    pub fn dead_time_samples(&self, dt_s: f64) -> usize {
        (self.dead_time_s / dt_s).round() as usize
    }

    /// The speed map of the stand model: `n_ref · ((u − u₀)/(u_ref − u₀))^a · (V / V₀)`
    /// (`u₀ = 0`, `a = 1` by default).
    pub fn speed_map(&self, plant: &PlantConfig) -> SpeedMap {
        SpeedMap {
            speed_ref: plant.rpm_at_reference,
            command_zero: self.command_zero,
            command_ref: plant.reference_throttle,
            exponent: self.speed_map_exponent,
            voltage_ref: plant.battery_v,
        }
    }

    /// The rotor's lag in the stand model, its time constants given at `rpm_at_reference`.
    pub fn rotor_law(&self, plant: &PlantConfig) -> RotorLaw {
        RotorLaw {
            tau_up_s: self.tau_up_s,
            tau_down_s: self.tau_down_s,
            tau_speed_exponent: self.tau_speed_exponent,
            speed_ref: plant.rpm_at_reference,
        }
    }

    /// The plant as the stand model's parameters (speed in rev/min; the dead time as the
    /// plant steps it, whole samples of `dt_s`; torque `torque_m · T`; the battery unloaded and
    /// not discharging).
    pub fn stand_params(&self, plant: &PlantConfig, dt_s: f64) -> StandParams {
        let n_ref = plant.rpm_at_reference;
        StandParams {
            dead_time_s: self.dead_time_samples(dt_s) as f64 * dt_s,
            map: self.speed_map(plant),
            rotor: self.rotor_law(plant),
            thrust_exponent: self.thrust_exponent,
            k_t: self.k_t(plant),
            k_q: plant.torque_m * self.k_t(plant),
            current: CurrentLaw {
                idle_a: plant.idle_current_a,
                per_power: plant.current_at_reference_a
                    / speed_power(n_ref, self.thrust_exponent + 1.0),
                per_acceleration: self.current_per_acceleration,
            },
            supply: Supply {
                open_circuit_v: plant.battery_v,
                resistance_ohm: plant.internal_resistance_ohm,
            },
        }
    }

    /// Steady-state speed `n_ss(u, V)`, rev/min ([`SpeedMap::speed_ss`] of
    /// `V₀ (V / V₀)^b`, [`MotorConfig::speed_voltage_exponent`]).
    pub fn speed_ss(&self, plant: &PlantConfig, u: f64, voltage_v: f64) -> f64 {
        let b = self.speed_voltage_exponent;
        let v = if b == 1.0 {
            voltage_v
        } else {
            let v0 = plant.battery_v;
            v0 * (voltage_v / v0).max(0.0).powf(b)
        };
        self.speed_map(plant).speed_ss(u, v)
    }

    /// The time constant `τ(n, dir)` at speed `n` (rev/min), seconds ([`RotorLaw::tau_s`]).
    pub fn tau_s(&self, plant: &PlantConfig, n: f64, up: bool) -> f64 {
        self.rotor_law(plant).tau_s(n, up)
    }
}
