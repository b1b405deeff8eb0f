//! The simulated stand calibrated from a log: the stand model fitted on it
//! ([`StandFit`], `propid_numerics::stand_model::fit`) as a `propid sim` configuration
//! ([`calibrate`], [`to_toml`]), and the plant replayed under a log's own command at its rows
//! ([`replay`]). Pure: the caller reads the log and writes the files (`diagnose --sim-config`,
//! `sim --replay-command`); `docs/stand-model.md` has the chapter.
//!
//! # From the fit to the plant (`[plant] kind = "motor"`)
//! The fit's speed unit is the log's rev/min, or relative (`n_ref = 1`) without a speed
//! channel: the plant's speed is then `s = NOMINAL_RPM` rev/min per unit. The plant is
//! referenced at `u_r` = the fit's highest command (0.9 when that is full throttle), its
//! battery voltage `V₀` the open-circuit voltage of the log's supply (below), so
//!
//! ```text
//!   rpm_at_reference       = s · n_ss,fit(u_r, V_ref) · V₀ / V_ref
//!   τ_dir (plant)          = τ_dir · (s · n_ref / rpm_at_reference)^γ
//!   thrust_at_reference_n  = k_T · (rpm_at_reference / s)ᵉ,   torque_m = k_Q / k_T
//!   current_at_reference_a = k_I · (rpm_at_reference / s)^{e+1},  k_J (plant) = k_J / s²
//! ```
//!
//! (the same functions of the command, written about another reference). The supply: where
//! the fit took it constant (diagnose's baseline without `supply_sag`, or a log without a
//! voltage channel) the plant's battery is that constant voltage, `V₀ = V_ref`, with no
//! resistance and no discharge; where the measured voltage drove the fit's speed map
//! (`supply_sag`), `V = V₀ − R I − discharge · t` fitted by least squares on the log's voltage
//! against its current and time ([`fit_supply`]; `R` and the discharge held at 0 where they come
//! out negative). [`replay`] drives that plant with the log's own measured voltage (a log is
//! replayed as it was measured: the simulated sag is the configuration's model of the log's
//! voltage, for `propid sim` and `propid demo`, which have no log).
//!
//! # Sensors
//! Each channel's sensor of the fit (delay, lag, refresh, and the offset and creep of its
//! amplitudes) is its `[plant.sensors.<channel>]`; the reference channel has none. A sensor
//! delay cannot be negative in a simulation: a channel ahead of the reference moves the ESC's
//! dead time down by that much and every sensor's delay up (the same timing of every channel),
//! as far as the dead time allows.
//!
//! # Extensions (diagnose's effects)
//! `diagnose --sim-config` writes diagnose's final stand model: the baseline with the effects
//! it took ([`Extensions`] carries what they add beyond [`StandFit`]'s figures). Where each
//! goes in the configuration:
//!
//! | effect | in the configuration |
//! |---|---|
//! | `dead_time` | `[plant.motor] dead_time_s` |
//! | `sensor_lag` | `[plant.sensors.<channel>] delay_s`, `tau_s` |
//! | `asymmetric_dynamics` | `[plant.motor] tau_up_s`, `tau_down_s` |
//! | `speed_dependent_tau` | `[plant.motor] tau_speed_exponent` |
//! | `static_nonlinearity` | `[plant.motor] speed_map_exponent`, `thrust_exponent` |
//! | `supply_sag` | `[plant] battery_v`, `internal_resistance_ohm`, `discharge_v_per_s` (the motor's speed follows its supply) |
//! | `saturation` | `[plant.effects.saturation] level`, `signal = "throttle"` |
//! | `baseline_drift` | `[plant.sensors.<channel>] creep_per_s` (every load and current channel) |
//! | `extra_mode` | `[plant.effects.extra_mode] fn_hz`, `zeta`, `gain = 1`: on the thrust only |
//! | `periodic_disturbance` | `[plant.effects.periodic_disturbance] freq_hz`, `amplitude`, `phase_rad`: on the thrust only |
//!
//! What the simulated stand cannot express: a resonance on the torque channel (the plant's
//! torque is `torque_m` times the true thrust) and a sinusoid on the torque or the current
//! (the plant's disturbance is added to the thrust reading); [`Calibrated::notes`] says so when
//! the fit has them. The fit's current law takes the supply as constant, the plant's current
//! follows the supply it draws from: a few per cent of the sag, not more.

use std::fmt::Write as _;

use nalgebra::{DMatrix, DVector};
use propid_numerics::stand_model::fit::{StandFit, Structure, StructuredFit};
use propid_numerics::stand_model::Quantity;
use propid_numerics::EffectName;

use crate::config::SimConfig;
use crate::effects::{ExtraMode, PeriodicDisturbance, Saturation, SaturationSignal};
use crate::plant::{
    Measurement, Plant, PlantConfig, PlantError, PlantKind, SensorConfig, SensorsConfig,
};

/// The plant's rev/min per unit of a fit's relative speed (a log without a speed channel).
pub const NOMINAL_RPM: f64 = 10_000.0;

/// The longest step the replay takes, s: a log's row is stepped in as many equal parts
/// (the plant's dead time and delays rounded to a part, not a row).
pub const REPLAY_STEP_S: f64 = 1e-3;

/// `V = open_circuit_v − resistance_ohm · I − discharge_v_per_s · t` of a log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupplyFit {
    /// At t = 0 and no current, V.
    pub open_circuit_v: f64,
    /// Ω (≥ 0).
    pub resistance_ohm: f64,
    /// V/s (≥ 0).
    pub discharge_v_per_s: f64,
}

/// What the configuration takes from the log besides the fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogFacts {
    /// The log's row period, s.
    pub dt_s: f64,
    /// The log's supply, when it has a voltage channel ([`fit_supply`]).
    pub supply: Option<SupplyFit>,
    /// The thrust readings' noise, N (0: none).
    pub thrust_noise_n: f64,
    /// The log's lowest command, throttle.
    pub command_low: f64,
}

/// The calibrated configuration and what could not be carried over exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibrated {
    /// The `propid sim` configuration.
    pub config: SimConfig,
    /// One line per approximation (empty: the fit as it is).
    pub notes: Vec<String>,
}

/// What the parts of the stand a fit frees add beyond [`StandFit`]'s figures (module doc,
/// "Extensions").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extensions {
    /// The measured supply voltage drove the fit's speed map (else the supply was constant).
    pub supply_measured: bool,
    /// The speed map's voltage exponent `b` (`n ∝ V^b`; `None`: 1).
    pub voltage_exponent: Option<f64>,
    /// The load and current channels have a creep (their amplitudes: bases, offset, creep).
    pub creep: bool,
    /// The command's clip level (`saturation`).
    pub command_limit: Option<f64>,
    /// A resonance between the rotor and the load cell, (fn Hz, ζ) (`extra_mode`).
    pub mode: Option<(f64, f64)>,
    /// A steady sinusoid on the load and current channels, Hz (`periodic_disturbance`; its
    /// sine and cosine amplitudes are each channel's last two).
    pub sinusoid_hz: Option<f64>,
}

impl Extensions {
    /// Of a fit of the structure `st` (`propid diagnose`'s stand model).
    pub fn of(f: &StructuredFit, st: &Structure) -> Extensions {
        Extensions {
            supply_measured: st.voltage && f.fit.params.map.voltage_ref != 1.0,
            voltage_exponent: f.voltage_exponent,
            creep: st.creep,
            command_limit: f.command_limit,
            mode: f.mode,
            sinusoid_hz: f.sinusoid_hz,
        }
    }

    /// Of the whole stand model ([`propid_numerics::stand_model::fit::fit`],
    /// [`Structure::full`]).
    pub fn whole(fit: &StandFit) -> Extensions {
        Extensions {
            supply_measured: fit.params.map.voltage_ref != 1.0,
            voltage_exponent: None,
            creep: true,
            command_limit: None,
            mode: None,
            sinusoid_hz: None,
        }
    }

    /// The effects of diagnose's catalogue these carry (the rest are figures of [`StandFit`]).
    pub fn effects(&self) -> Vec<EffectName> {
        [
            (self.supply_measured, EffectName::SupplySag),
            (self.command_limit.is_some(), EffectName::Saturation),
            (self.creep, EffectName::BaselineDrift),
            (self.mode.is_some(), EffectName::ExtraMode),
            (self.sinusoid_hz.is_some(), EffectName::PeriodicDisturbance),
        ]
        .into_iter()
        .filter_map(|(on, e)| on.then_some(e))
        .collect()
    }
}

/// A channel's offset and creep per second at `t = 0` of the log, and its sinusoid (sine,
/// cosine amplitudes at `t = 0`), from its amplitudes (the fit's time starts at its window,
/// `t0_s`).
fn offset_creep_sine(
    c: &propid_numerics::stand_model::fit::ChannelFit,
    ext: &Extensions,
    t0_s: f64,
) -> (f64, f64, Option<(f64, f64)>) {
    let amp = &c.amplitudes;
    let at = match c.quantity {
        Quantity::Speed => return (0.0, 0.0, None),
        Quantity::Thrust | Quantity::Torque => 1,
        Quantity::Current => 2,
    };
    let offset = amp.get(at).copied().unwrap_or(0.0);
    let creep = if ext.creep {
        amp.get(at + 1).copied().unwrap_or(0.0)
    } else {
        0.0
    };
    let sine = ext.sinusoid_hz.and_then(|f| {
        let n = amp.len();
        (n >= at + 3).then(|| {
            // a sin(ω(t − t0)) + b cos(ω(t − t0)) written about t = 0.
            let (a, b) = (amp[n - 2], amp[n - 1]);
            let ph = -std::f64::consts::TAU * f * t0_s;
            (a * ph.cos() - b * ph.sin(), a * ph.sin() + b * ph.cos())
        })
    });
    (offset - creep * t0_s, creep, sine)
}

/// Least squares of `voltage` on `[1, current, t]` over the rows where both are read
/// (`current` `None`: on `[1, t]`); a negative resistance or discharge is held at 0 and the
/// rest refitted. `None` with fewer than 3 rows.
pub fn fit_supply(dt_s: f64, voltage: &[f64], current: Option<&[f64]>) -> Option<SupplyFit> {
    let rows: Vec<usize> = (0..voltage.len())
        .filter(|&k| voltage[k].is_finite() && current.map_or(true, |c| c[k].is_finite()))
        .collect();
    if rows.len() < 3 {
        return None;
    }
    let solve = |use_i: bool, use_t: bool| -> Option<(f64, f64, f64)> {
        let cols = 1 + usize::from(use_i) + usize::from(use_t);
        let mut a = DMatrix::<f64>::zeros(rows.len(), cols);
        let mut b = DVector::<f64>::zeros(rows.len());
        for (r, &k) in rows.iter().enumerate() {
            a[(r, 0)] = 1.0;
            let mut c = 1;
            if use_i {
                a[(r, c)] = -current.map_or(0.0, |i| i[k]);
                c += 1;
            }
            if use_t {
                a[(r, c)] = -(k as f64) * dt_s;
            }
            b[r] = voltage[k];
        }
        let x = a.svd(true, true).solve(&b, 1e-12).ok()?;
        let mut c = 1;
        let r_ohm = if use_i {
            c += 1;
            x[1]
        } else {
            0.0
        };
        let d = if use_t { x[c] } else { 0.0 };
        Some((x[0], r_ohm, d))
    };
    let mut use_i = current.is_some();
    let mut use_t = true;
    loop {
        let (v0, r, d) = solve(use_i, use_t)?;
        if use_i && r < 0.0 {
            use_i = false;
            continue;
        }
        if use_t && d < 0.0 {
            use_t = false;
            continue;
        }
        return Some(SupplyFit {
            open_circuit_v: v0,
            resistance_ohm: r,
            discharge_v_per_s: d,
        });
    }
}

/// The sensor key of a quantity (`[plant.sensors.<key>]`).
fn sensor_key(q: Quantity) -> &'static str {
    match q {
        Quantity::Speed => "rpm",
        Quantity::Thrust => "thrust",
        Quantity::Torque => "torque",
        Quantity::Current => "current",
    }
}

/// The fitted stand `fit` with its extensions `ext` of a log described by `log` as a `propid
/// sim` configuration (module doc).
pub fn calibrate(fit: &StandFit, ext: &Extensions, log: &LogFacts) -> Calibrated {
    let p = &fit.params;
    let mut notes = Vec::new();
    let mut cfg = SimConfig::default();
    let plant = &mut cfg.plant;
    plant.kind = PlantKind::Motor;
    let s = if fit.shows.speed { 1.0 } else { NOMINAL_RPM };
    if !fit.shows.speed {
        notes.push(format!(
            "the log has no speed channel: the simulated rotor turns {NOMINAL_RPM} rev/min at \
             the highest command"
        ));
    }
    let e = p.thrust_exponent;
    let u_ref = p.map.command_ref;
    let u_r = if u_ref > 0.0 && u_ref < 0.999 {
        u_ref
    } else {
        0.9
    };
    let u0 = p.map.command_zero.clamp(-1.0, u_r - 1e-3);
    let v_ref = p.map.voltage_ref;
    // The supply (module doc): measured and modelled, or the fit's constant.
    let sagging = match (&log.supply, ext.supply_measured) {
        (Some(sup), true) if sup.open_circuit_v > 0.0 => Some(*sup),
        _ => None,
    };
    let (v0, mut voltage_ratio) = match &sagging {
        Some(sup) => (sup.open_circuit_v, sup.open_circuit_v / v_ref),
        None if v_ref != 1.0 => (v_ref, 1.0),
        None => (plant.battery_v, 1.0),
    };
    let (r_ohm, discharge) = sagging.map_or((0.0, 0.0), |sup| {
        (sup.resistance_ohm, sup.discharge_v_per_s)
    });
    // The speed follows the supply as `(V/V_ref)^b`: at the battery's `V₀`, `(V₀/V_ref)^b`
    // of the fit's reference speed, and `(V/V₀)^b` of it at `V`.
    let b = ext.voltage_exponent.unwrap_or(1.0).clamp(0.0, 2.0);
    voltage_ratio = voltage_ratio.powf(b);
    if sagging.is_some() && r_ohm == 0.0 && discharge == 0.0 {
        notes.push(
            "the log's voltage neither sags with the current nor falls with time: the \
             simulated supply is constant and is replayed at it"
                .into(),
        );
    }
    let rpm_ref = s * p.map.speed_ss(u_r, v_ref) * voltage_ratio;
    let gamma = p.rotor.tau_speed_exponent;
    let tau_scale = (s * p.rotor.speed_ref / rpm_ref).powf(gamma);
    let speed_units = rpm_ref / s;
    plant.reference_throttle = u_r;
    plant.rpm_at_reference = rpm_ref;
    plant.battery_v = v0;
    plant.internal_resistance_ohm = r_ohm;
    plant.discharge_v_per_s = discharge;
    let m = &mut plant.motor;
    m.tau_up_s = p.rotor.tau_up_s * tau_scale;
    m.tau_down_s = p.rotor.tau_down_s * tau_scale;
    m.tau_speed_exponent = gamma.clamp(-1.0, 3.0);
    m.command_zero = u0;
    m.speed_map_exponent = p.map.exponent.clamp(0.3, 3.0);
    m.speed_voltage_exponent = b;
    m.thrust_exponent = e.clamp(0.5, 4.5);
    let t_ref = p.k_t * speed_units.powf(e);
    m.thrust_at_reference_n = if t_ref > 0.0 {
        t_ref
    } else {
        notes.push("no thrust rising with the speed in the log: a nominal 1 N thrust".into());
        1.0
    };
    if p.k_t > 0.0 && p.k_q > 0.0 {
        plant.torque_m = p.k_q / p.k_t;
    }
    let t0 = fit.window_s.0;
    let current = fit
        .channels
        .iter()
        .find(|c| c.quantity == Quantity::Current);
    if let Some(c) = current {
        let (idle, _, _) = offset_creep_sine(c, ext, t0);
        plant.idle_current_a = idle.max(0.0);
        plant.current_at_reference_a = (p.current.per_power * speed_units.powf(e + 1.0)).max(0.0);
        plant.motor.current_per_acceleration = p.current.per_acceleration / (s * s);
    }
    plant.noise_rms_n = log.thrust_noise_n.max(0.0);
    plant.quantum_n = 0.0;
    plant.adc_full_scale_n = (4.0 * plant.motor.thrust_at_reference_n.abs()).max(50.0);

    // The sensors, their delays made non-negative against the dead time (module doc).
    let mut dead = fit.dead_time_s.0.max(0.0);
    let lowest = fit
        .channels
        .iter()
        .filter_map(|c| c.delay_s.map(|d| d.0))
        .fold(0.0, f64::min);
    let shift = (-lowest).min(dead);
    dead -= shift;
    if -lowest > shift + 1e-9 {
        notes.push(format!(
            "a channel leads the rotor by {:.4} s more than the ESC's dead time: its delay is \
             held at 0",
            -lowest - shift
        ));
    }
    plant.motor.dead_time_s = dead.min(1.0);
    let mut sensors = SensorsConfig::default();
    for c in &fit.channels {
        let (offset, creep, sine) = offset_creep_sine(c, ext, t0);
        // The current's offset is its idle current (the part below 0 stays an offset).
        let offset = match c.quantity {
            Quantity::Current => offset.min(0.0),
            _ => offset,
        };
        match (c.quantity, sine, ext.sinusoid_hz) {
            (Quantity::Thrust, Some((a, b)), Some(f)) => {
                plant.effects.periodic_disturbance = Some(PeriodicDisturbance {
                    freq_hz: f,
                    amplitude: a.hypot(b),
                    phase_rad: b.atan2(a),
                })
            }
            (Quantity::Torque | Quantity::Current, Some(_), _) => notes.push(format!(
                "the {} channel's sinusoid is not simulated (the simulated stand adds its \
                 periodic disturbance to the thrust only)",
                c.key
            )),
            _ => {}
        }
        if c.quantity == Quantity::Torque && ext.mode.is_some() {
            notes.push(
                "the torque channel's resonance is not simulated (the simulated stand's \
                 extra mode is in the thrust's load-cell path only)"
                    .into(),
            );
        }
        let sensor = SensorConfig {
            delay_s: (c.delay_s.map_or(0.0, |d| d.0) + shift).clamp(0.0, 1.0),
            tau_s: c.tau_s.map_or(0.0, |t| t.0).clamp(0.0, 5.0),
            refresh_s: c.refresh_s.0.clamp(0.0, 10.0),
            offset,
            creep_per_s: creep,
        };
        let slot = match c.quantity {
            Quantity::Speed => &mut sensors.rpm,
            Quantity::Thrust => &mut sensors.thrust,
            Quantity::Torque => &mut sensors.torque,
            Quantity::Current => &mut sensors.current,
        };
        *slot = Some(sensor);
    }
    cfg.plant.sensors = sensors;
    if let Some(level) = ext.command_limit.filter(|l| *l < 1.0) {
        cfg.plant.effects.saturation = Some(Saturation {
            level: level.clamp(0.0, 1.0),
            signal: SaturationSignal::Throttle,
        });
    }
    if let Some((fn_hz, zeta)) = ext.mode {
        let has_thrust = fit.channels.iter().any(|c| c.quantity == Quantity::Thrust);
        if has_thrust && fn_hz < 0.5 / log.dt_s {
            cfg.plant.effects.extra_mode = Some(ExtraMode {
                fn_hz,
                zeta,
                gain: 1.0,
            });
        }
    }

    cfg.stand.name = "calibrated".into();
    cfg.stand.sample_rate_hz = (1.0 / log.dt_s).round().clamp(10.0, 20_000.0) as u32;
    // The demo's plan (three levels, eight pulses each) inside the log's command range.
    let lo = log.command_low.max(u0).max(0.0);
    let span = (u_r - lo).max(0.05);
    let x = &mut cfg.experiment;
    x.levels = [0.35, 0.55, 0.75]
        .iter()
        .map(|f| round4(lo + f * span))
        .collect();
    x.pulse_amplitudes = vec![round4(0.1 * span), round4(0.15 * span)];
    x.ramp_ms = 300;
    x.settle_ms = 500;
    x.pulse_spacing_ms = 250;
    x.pulses_per_level = 8;
    Calibrated { config: cfg, notes }
}

fn round4(x: f64) -> f64 {
    (x * 1e4).round() / 1e4
}

/// The keys [`calibrate`] sets, as `propid sim` configuration text (every other key at its
/// default); `header` becomes the leading comment lines.
pub fn to_toml(cfg: &SimConfig, header: &[String]) -> String {
    let mut t = String::new();
    for h in header {
        let _ = writeln!(t, "# {h}");
    }
    let s = &cfg.stand;
    let _ = writeln!(
        t,
        "\n[stand]\nname = {:?}\nsample_rate_hz = {}",
        s.name, s.sample_rate_hz
    );
    let p = &cfg.plant;
    let kind = match p.kind {
        PlantKind::Motor => "motor",
        PlantKind::SecondOrder => "second_order",
    };
    let _ = writeln!(t, "\n[plant]\nkind = \"{kind}\"");
    let plant_keys = [
        ("reference_throttle", p.reference_throttle),
        ("rpm_at_reference", p.rpm_at_reference),
        ("battery_v", p.battery_v),
        ("internal_resistance_ohm", p.internal_resistance_ohm),
        ("discharge_v_per_s", p.discharge_v_per_s),
        ("idle_current_a", p.idle_current_a),
        ("current_at_reference_a", p.current_at_reference_a),
        ("torque_m", p.torque_m),
        ("noise_rms_n", p.noise_rms_n),
        ("quantum_n", p.quantum_n),
        ("adc_full_scale_n", p.adc_full_scale_n),
    ];
    for (k, v) in plant_keys {
        let _ = writeln!(t, "{k} = {}", num(v));
    }
    let m = &p.motor;
    let _ = writeln!(t, "\n[plant.motor]");
    let motor_keys = [
        ("thrust_at_reference_n", m.thrust_at_reference_n),
        ("tau_up_s", m.tau_up_s),
        ("tau_down_s", m.tau_down_s),
        ("tau_speed_exponent", m.tau_speed_exponent),
        ("dead_time_s", m.dead_time_s),
        ("command_zero", m.command_zero),
        ("speed_map_exponent", m.speed_map_exponent),
        ("thrust_exponent", m.thrust_exponent),
        ("current_per_acceleration", m.current_per_acceleration),
        ("speed_voltage_exponent", m.speed_voltage_exponent),
    ];
    for (k, v) in motor_keys {
        let _ = writeln!(t, "{k} = {}", num(v));
    }
    let sensors = [
        ("thrust", &p.sensors.thrust),
        ("torque", &p.sensors.torque),
        ("rpm", &p.sensors.rpm),
        ("current", &p.sensors.current),
    ];
    for (name, s) in sensors {
        if let Some(s) = s {
            let _ = writeln!(
                t,
                "\n[plant.sensors.{name}]\ndelay_s = {}\ntau_s = {}\nrefresh_s = {}\noffset = {}\n\
                 creep_per_s = {}",
                num(s.delay_s),
                num(s.tau_s),
                num(s.refresh_s),
                num(s.offset),
                num(s.creep_per_s)
            );
        }
    }
    // The effects `calibrate` sets (module doc, "Extensions"), named by the one catalogue.
    let fx = &p.effects;
    let mut table = |e: EffectName, keys: &[(&str, String)]| {
        let _ = writeln!(t, "\n[plant.effects.{}]", e.as_str());
        for (k, v) in keys {
            let _ = writeln!(t, "{k} = {v}");
        }
    };
    if let Some(s) = &fx.saturation {
        let signal = match s.signal {
            SaturationSignal::Throttle => "\"throttle\"",
            SaturationSignal::Sensor => "\"sensor\"",
        };
        table(
            EffectName::Saturation,
            &[("level", num(s.level)), ("signal", signal.into())],
        );
    }
    if let Some(m) = &fx.extra_mode {
        table(
            EffectName::ExtraMode,
            &[
                ("fn_hz", num(m.fn_hz)),
                ("zeta", num(m.zeta)),
                ("gain", num(m.gain)),
            ],
        );
    }
    if let Some(d) = &fx.periodic_disturbance {
        table(
            EffectName::PeriodicDisturbance,
            &[
                ("freq_hz", num(d.freq_hz)),
                ("amplitude", num(d.amplitude)),
                ("phase_rad", num(d.phase_rad)),
            ],
        );
    }
    let x = &cfg.experiment;
    let list = |v: &[f64]| v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", ");
    let _ = writeln!(
        t,
        "\n[experiment]\nlevels = [{}]\npulse_amplitudes = [{}]\nramp_ms = {}\nsettle_ms = {}\n\
         pulse_spacing_ms = {}\npulses_per_level = {}",
        list(&x.levels),
        list(&x.pulse_amplitudes),
        x.ramp_ms,
        x.settle_ms,
        x.pulse_spacing_ms,
        x.pulses_per_level
    );
    t
}

/// A TOML float that reads back as the same `f64` (`{:?}` keeps a `.0` on whole numbers).
fn num(v: f64) -> String {
    format!("{v:?}")
}

/// What the plant `cfg` measures at the start of each row of a log sampled every `dt_s` under
/// its `command` (throttle per row, NaN: the last one held), from the steady state of its first
/// command, without the thrust's noise. The plant (ESC, rotor, supply, the effects on the
/// command and the load-cell path) is stepped in equal parts of each row of at most
/// [`REPLAY_STEP_S`]; its sensors read what it does at the rows, as the simulated stand at the
/// log's rate reads them ([`propid_numerics::stand_model::sense`], the stand model's own: a
/// delay and a lag between rows see the quantity linear between them), and a periodic
/// disturbance is added to the thrust's reading. A held channel is held by the caller on the
/// log's own readings ([`hold_on`]). With `voltage` (the log's measured supply per row, NaN:
/// the last one held) the plant's supply is that voltage instead of its battery model (module
/// doc).
pub fn replay(
    cfg: &PlantConfig,
    dt_s: f64,
    command: &[f64],
    voltage: Option<&[f64]>,
) -> Result<Vec<Measurement>, PlantError> {
    let parts = (dt_s / REPLAY_STEP_S).ceil().max(1.0) as usize;
    let h = dt_s / parts as f64;
    let mut bare = cfg.clone();
    bare.noise_rms_n = 0.0;
    let sensors = std::mem::take(&mut bare.sensors);
    let disturbance = bare.effects.periodic_disturbance.take();
    let mut plant = Plant::new(&bare, h, 0)?;
    let first = command
        .iter()
        .copied()
        .find(|u| u.is_finite())
        .unwrap_or(0.0);
    let mut v = voltage.and_then(|v| v.iter().copied().find(|x| x.is_finite()));
    plant.settle_at_supply(first, v);
    let mut u = first;
    let mut out = Vec::with_capacity(command.len());
    for (k, &c) in command.iter().enumerate() {
        if c.is_finite() {
            u = c;
        }
        if let Some(x) = voltage.and_then(|m| m.get(k)).filter(|x| x.is_finite()) {
            v = Some(*x);
        }
        out.push(plant.step_at_supply(u, v));
        for _ in 1..parts {
            plant.step_at_supply(u, v);
        }
    }
    type Field = fn(&mut Measurement) -> &mut f64;
    let channels: [(&Option<SensorConfig>, Field); 4] = [
        (&sensors.thrust, |m| &mut m.thrust_n),
        (&sensors.torque, |m| &mut m.torque_nm),
        (&sensors.rpm, |m| &mut m.rpm),
        (&sensors.current, |m| &mut m.current_a),
    ];
    for (sensor, field) in channels {
        let Some(s) = sensor else { continue };
        let x: Vec<f64> = out.iter_mut().map(|m| *field(m)).collect();
        let read = propid_numerics::stand_model::sense(
            &propid_numerics::stand_model::Sensor {
                delay_s: s.delay_s,
                tau_s: s.tau_s,
                refresh_s: 0.0,
                offset: s.offset,
                creep_per_s: s.creep_per_s,
            },
            dt_s,
            &x,
        );
        for (m, y) in out.iter_mut().zip(read) {
            *field(m) = y;
        }
    }
    if let Some(d) = disturbance {
        for (k, m) in out.iter_mut().enumerate() {
            let t = k as f64 * dt_s;
            m.thrust_n += d.amplitude * (std::f64::consts::TAU * d.freq_hz * t + d.phase_rad).sin();
        }
    }
    Ok(out)
}

/// Whether a replay of `cfg` drives it with a log's measured voltage: its supply sags
/// (module doc; a constant supply is the fit's own and is replayed at it).
pub fn replays_measured_supply(cfg: &PlantConfig) -> bool {
    cfg.internal_resistance_ohm > 0.0 || cfg.discharge_v_per_s > 0.0
}

/// `y` read only where `reading` is true and held in between (before the first reading, the
/// first one); as it is when `reading` is empty.
pub fn hold_on(y: &[f64], reading: &[bool]) -> Vec<f64> {
    if reading.is_empty() {
        return y.to_vec();
    }
    let first = (0..y.len())
        .find(|&k| reading.get(k).copied().unwrap_or(false))
        .map_or(f64::NAN, |k| y[k]);
    let mut last = first;
    y.iter()
        .enumerate()
        .map(|(k, &v)| {
            if reading.get(k).copied().unwrap_or(false) {
                last = v;
            }
            last
        })
        .collect()
}

/// The stand model's sensors of `fit`'s channels as it fitted them (key, quantity, sensor):
/// [`propid_numerics::stand_model::simulate`] of `fit.params` with these is the fit's own
/// prediction of each channel (without a resonance or a sinusoid).
pub fn fitted_sensors(
    fit: &StandFit,
    ext: &Extensions,
) -> Vec<(&'static str, Quantity, propid_numerics::stand_model::Sensor)> {
    fit.channels
        .iter()
        .map(|c| {
            let (offset, creep, _) = offset_creep_sine(c, ext, fit.window_s.0);
            let offset = match c.quantity {
                Quantity::Current => offset - fit.params.current.idle_a,
                _ => offset,
            };
            (
                c.key,
                c.quantity,
                propid_numerics::stand_model::Sensor {
                    delay_s: c.delay_s.map_or(0.0, |d| d.0),
                    tau_s: c.tau_s.map_or(0.0, |t| t.0),
                    refresh_s: 0.0,
                    offset,
                    creep_per_s: creep,
                },
            )
        })
        .collect()
}

/// The channel key (`thrust`, `torque`, `rpm`, `current`) of a quantity.
pub fn channel_key(q: Quantity) -> &'static str {
    sensor_key(q)
}

#[cfg(test)]
mod tests;
