//! One physical model of a motor–propeller stand: the ESC, the rotor, the propeller's loads, the
//! supply, and a sensor per measured channel. The simulated stand (`propid-sim`'s motor plant)
//! steps these equations; [`fit`] finds their parameters from a record's channels, whichever
//! it has; [`report`] says what a record can show of them. `docs/stand-model.md` has the whole
//! chapter.
//!
//! # The stand
//! The command `u` (throttle 0..1, held over each row) reaches the motor after the ESC's dead
//! time `θ` (any real number of rows: within a row the delayed command switches at the
//! fraction `θ/dt − ⌊θ/dt⌋`, and each part of the row is stepped on its own). The rotor speed
//! `n` follows the steady speed of the command and the supply voltage `V` as a first-order lag
//! whose time constant depends on the direction and on the speed:
//!
//! ```text
//!   n_ss(u, V) = n_ref · (max(u − u₀, 0) / (u_ref − u₀))^a · V / V_ref      (SpeedMap)
//!   n'         = (n_ss − n) / τ(n, dir)
//!   τ(n, dir)  = τ_dir · (n_ref / max(n, n_ref/10))^γ,  dir = up when n_ss ≥ n, else down
//! ```
//!
//! (the ESC applies `u·V` to the motor above a dead band `u₀`, `a = 1` for a duty-cycle ESC;
//! a propeller's drag grows with speed, so the rotor answers faster at speed, `γ > 0`; an ESC
//! brakes less than it drives, `τ_down > τ_up`). Over each part `h` of a row the direction and
//! `τ` are frozen at the part's start and the lag is integrated exactly:
//! `n⁺ = n_ss + (n − n_ss) e^{−h/τ}` ([`RotorLaw::advance`]).
//!
//! The propeller's thrust and torque grow with a power `e` of the speed (momentum theory and
//! the blade-element coefficients give `e = 2`, fitted), the current with the mechanical power
//! `Q·ω ∝ n^{e+1}` plus the power that accelerates the rotor `J ω ω' ∝ n n'`, the supply sags
//! with the current through its internal resistance:
//!
//! ```text
//!   T = k_T nᵉ,   Q = k_Q nᵉ,   I = I₀ + k_I n^{e+1} + k_J n n',   V = V_oc − R I
//! ```
//!
//! (the current law takes the supply as constant: its sag is a few per cent; with a voltage
//! channel the measured voltage drives the speed map instead of `V_oc − R I`).
//!
//! # The sensors
//! Each measured channel sees its quantity `x` through a sensor of its own: a first-order lag
//! `τ_s` (a load cell's filter; `x` taken as linear between rows, so the lag is exact and
//! `τ_s = 0` is no lag at all), a delay `δ` (interpolated between rows), an offset and a creep
//! (a load cell's drift), and a refresh interval `R`: a channel refreshed at 7 Hz inside
//! 143 Hz rows is a held signal, read once per `R` and held in between ([`hold`]):
//!
//! ```text
//!   s' = (x − s)/τ_s,   y(t) = s(t − δ) + c + d·t,   held over R
//! ```
//!
//! ([`Sensor`], [`sense`]). A record's rows where a reader interpolated between a held
//! channel's readings (`propid_wire::record::Channel::interpolated`) are no readings: the fit
//! compares the model only with the readings, and the refresh interval is their spacing.

pub mod fit;
pub mod report;
pub mod sensitivity;
pub mod spans;

#[cfg(test)]
mod tests;

/// The steady speed of a command and a supply voltage (module doc, `n_ss`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedMap {
    /// Speed at `command_ref` and `voltage_ref`, the model's speed unit (rev/min in the
    /// simulated stand; 1 in a fit, whose speed is relative).
    pub speed_ref: f64,
    /// The ESC's dead band: no speed at or below this command, `u₀`.
    pub command_zero: f64,
    /// The command of `speed_ref`, `u_ref` (> `command_zero`).
    pub command_ref: f64,
    /// The map's exponent `a` (1: speed linear in the command above the dead band).
    pub exponent: f64,
    /// The supply voltage of `speed_ref`, volts.
    pub voltage_ref: f64,
}

impl SpeedMap {
    /// `n_ss(u, V)`.
    pub fn speed_ss(&self, u: f64, voltage_v: f64) -> f64 {
        let x = (u - self.command_zero).max(0.0) / (self.command_ref - self.command_zero);
        let x = if self.exponent == 1.0 {
            x
        } else {
            x.powf(self.exponent)
        };
        self.speed_ref * x * (voltage_v / self.voltage_ref)
    }
}

/// The rotor's lag (module doc, `τ(n, dir)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorLaw {
    /// Spin-up time constant at `speed_ref`, s (> 0).
    pub tau_up_s: f64,
    /// Spin-down time constant at `speed_ref`, s (> 0).
    pub tau_down_s: f64,
    /// `γ`: `τ ∝ (n_ref / n)^γ` (0: one τ per direction at every speed).
    pub tau_speed_exponent: f64,
    /// The speed the time constants are given at, the model's speed unit.
    pub speed_ref: f64,
}

impl RotorLaw {
    /// `τ(n, dir)`, s.
    pub fn tau_s(&self, n: f64, up: bool) -> f64 {
        let base = if up { self.tau_up_s } else { self.tau_down_s };
        let floor = self.speed_ref / 10.0;
        base * (self.speed_ref / n.max(floor)).powf(self.tau_speed_exponent)
    }

    /// The speed after `h` seconds from `n` towards `target` (direction and τ frozen at `n`).
    pub fn advance(&self, n: f64, target: f64, h: f64) -> f64 {
        let tau = self.tau_s(n, target >= n);
        target + (n - target) * (-h / tau).exp()
    }

    /// `n'` at speed `n` under `target`.
    pub fn rate(&self, n: f64, target: f64) -> f64 {
        (target - n) / self.tau_s(n, target >= n)
    }
}

/// The current law (module doc): `I = I₀ + k_I n^{e+1} + k_J n n'`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CurrentLaw {
    /// Current at rest, A.
    pub idle_a: f64,
    /// `k_I`, A per speed^(e+1).
    pub per_power: f64,
    /// `k_J`, A per (speed · speed/s).
    pub per_acceleration: f64,
}

/// The supply: `V = V_oc − R I`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Supply {
    /// Open-circuit voltage, V.
    pub open_circuit_v: f64,
    /// Internal resistance, Ω.
    pub resistance_ohm: f64,
}

/// Every parameter of the stand (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StandParams {
    /// ESC dead time `θ`, s (≥ 0).
    pub dead_time_s: f64,
    /// The steady speed map.
    pub map: SpeedMap,
    /// The rotor's lag.
    pub rotor: RotorLaw,
    /// `e` of `T = k_T nᵉ`, `Q = k_Q nᵉ`.
    pub thrust_exponent: f64,
    /// `k_T`, N per speed^e.
    pub k_t: f64,
    /// `k_Q`, N·m per speed^e.
    pub k_q: f64,
    /// The current law.
    pub current: CurrentLaw,
    /// The supply (used without a measured voltage).
    pub supply: Supply,
}

/// `nᵉ` (`n·n` exactly for `e = 2`).
pub fn speed_power(n: f64, e: f64) -> f64 {
    let n = n.max(0.0);
    if e == 2.0 {
        n * n
    } else {
        n.powf(e)
    }
}

/// `k nᵉ` (`k·n·n` for `e = 2`, as the simulated stand has always computed its thrust).
pub fn load(k: f64, n: f64, e: f64) -> f64 {
    if e == 2.0 {
        let n = n.max(0.0);
        k * n * n
    } else {
        k * speed_power(n, e)
    }
}

/// What the stand's physical quantities are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Quantity {
    /// Rotor speed.
    Speed,
    /// Thrust.
    Thrust,
    /// Torque.
    Torque,
    /// Supply current.
    Current,
}

impl Quantity {
    /// The quantity at speed `n` and acceleration `n_dot` of `p`.
    pub fn of(self, p: &StandParams, n: f64, n_dot: f64) -> f64 {
        let e = p.thrust_exponent;
        match self {
            Quantity::Speed => n,
            Quantity::Thrust => load(p.k_t, n, e),
            Quantity::Torque => load(p.k_q, n, e),
            Quantity::Current => {
                let c = &p.current;
                c.idle_a + c.per_power * speed_power(n, e + 1.0) + c.per_acceleration * n * n_dot
            }
        }
    }
}

/// The rotor's course over a record: speed `n_k` at the start of each row and its rate `n'_k`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RotorCourse {
    /// Speed at the start of row `k`.
    pub speed: Vec<f64>,
    /// `n'` at the start of row `k`.
    pub rate: Vec<f64>,
    /// The supply voltage over row `k` (measured, or `V_oc − R I`).
    pub voltage: Vec<f64>,
}

/// The last finite value of `x` at or before `k` (the first finite one before any; `fallback`
/// when none).
fn held_at(x: &[f64], k: isize, fallback: f64) -> f64 {
    if x.is_empty() {
        return fallback;
    }
    let k = k.clamp(0, x.len() as isize - 1) as usize;
    x[..=k]
        .iter()
        .rev()
        .find(|v| v.is_finite())
        .or_else(|| x[k..].iter().find(|v| v.is_finite()))
        .copied()
        .unwrap_or(fallback)
}

/// Fills NaN cells of `x` with the last finite value (the first finite one before any).
pub fn fill_held(x: &[f64], fallback: f64) -> Vec<f64> {
    let first = x
        .iter()
        .copied()
        .find(|v| v.is_finite())
        .unwrap_or(fallback);
    let mut last = first;
    x.iter()
        .map(|&v| {
            if v.is_finite() {
                last = v;
            }
            last
        })
        .collect()
}

/// The rotor of `p` driven by `command` (held per row; NaN holds the last) every `dt_s`, from
/// the steady state of the first command; the supply `voltage` per row when measured (NaN
/// holds the last), else `V_oc − R I` of the row's start. Module doc for the equations.
pub fn rotor_course(
    p: &StandParams,
    dt_s: f64,
    command: &[f64],
    voltage: Option<&[f64]>,
) -> RotorCourse {
    let len = command.len();
    let u = fill_held(command, 0.0);
    let v_meas = voltage.map(|v| fill_held(v, p.map.voltage_ref));
    let delay = (p.dead_time_s / dt_s).max(0.0);
    let whole = delay.floor();
    let frac = delay - whole;
    let d = whole as isize;
    let supply_at = |n: f64, n_dot: f64| {
        p.supply.open_circuit_v - p.supply.resistance_ohm * Quantity::Current.of(p, n, n_dot)
    };
    // The steady state of the first command (the sag solved by a few fixed-point steps).
    let u0 = held_at(&u, 0, 0.0);
    let mut n = 0.0;
    for _ in 0..20 {
        let v = match &v_meas {
            Some(v) => held_at(v, 0, p.map.voltage_ref),
            None => supply_at(n, 0.0),
        };
        n = p.map.speed_ss(u0, v);
    }
    let mut out = RotorCourse {
        speed: Vec::with_capacity(len),
        rate: Vec::with_capacity(len),
        voltage: Vec::with_capacity(len),
    };
    // The same numbers as `RotorLaw::rate`/`advance`, `SpeedMap::speed_ss` and `supply_at`,
    // with what repeats from row to row computed once: the steady speed of a held command
    // (`ss`), τ's speed factor at the row's speed, the supply without a resistance, and no
    // `exp` once the speed has reached its target exactly.
    let mut ss = SteadyCache::new(&p.map);
    let rotor = &p.rotor;
    let floor = rotor.speed_ref / 10.0;
    let factor_of = |n: f64| {
        if rotor.tau_speed_exponent == 0.0 {
            1.0 // x^0 = 1 for every x, NaN too
        } else {
            (rotor.speed_ref / n.max(floor)).powf(rotor.tau_speed_exponent)
        }
    };
    let tau = |up: bool, factor: f64| {
        let base = if up { rotor.tau_up_s } else { rotor.tau_down_s };
        base * factor
    };
    let rate_of = |n: f64, target: f64, factor: f64| (target - n) / tau(target >= n, factor);
    let advance = |n: f64, target: f64, h: f64, factor: f64| {
        let tau = tau(target >= n, factor);
        if n == target && tau > 0.0 {
            target + 0.0 // (n − target)·e^{−h/τ} = +0
        } else {
            target + (n - target) * (-h / tau).exp()
        }
    };
    let c = &p.current;
    let no_sag = p.supply.resistance_ohm == 0.0
        && [c.idle_a, c.per_power, c.per_acceleration]
            .iter()
            .all(|x| x.abs() < 1e50)
        && p.thrust_exponent.abs() < 10.0;
    let supply = |n: f64, n_dot: f64| {
        // V_oc − 0·I = V_oc while I is finite (bounded n, n' and coefficients)
        if no_sag && n.abs() < 1e20 && n_dot.abs() < 1e200 {
            p.supply.open_circuit_v
        } else {
            supply_at(n, n_dot)
        }
    };
    // `u` is filled: `held_at` is the clamped row
    let last = len as isize - 1;
    let cmd = |j: isize| {
        if len == 0 {
            u0
        } else {
            u[j.clamp(0, last) as usize]
        }
    };
    let mut last_factor: Option<(u64, f64)> = None;
    let mut factor_at = |n: f64| match last_factor {
        Some((bits, x)) if bits == n.to_bits() => x,
        _ => {
            let x = factor_of(n);
            last_factor = Some((n.to_bits(), x));
            x
        }
    };
    let (mut first, mut second) = (Advanced::default(), Advanced::default());
    // A row whose speed, commands and supply are the previous row's has its rate, supply and
    // next speed too (a settled speed under a held command).
    let mut last_row: Option<([u64; 4], (f64, f64, f64))> = None;
    for k in 0..len as isize {
        let (before, after) = (cmd(k - d - 1), cmd(k - d));
        let v_guess = match &v_meas {
            Some(v) => v[k as usize],
            None => p.supply.open_circuit_v,
        };
        let key = [n, before, after, v_guess].map(f64::to_bits);
        let (rate, v, next) = match last_row {
            Some((k0, row)) if k0 == key => row,
            _ => {
                let now = if frac > 0.0 { before } else { after };
                let f = factor_at(n);
                let rate0 = rate_of(n, ss.at(now, v_guess), f);
                let v = match &v_meas {
                    Some(_) => v_guess,
                    None => supply(n, rate0),
                };
                let rate = rate_of(n, ss.at(now, v), f);
                let mut next = n;
                if frac > 0.0 {
                    let target = ss.at(before, v);
                    next = first.get(next, target, || advance(next, target, frac * dt_s, f));
                }
                let f = factor_at(next);
                let target = ss.at(after, v);
                next = second.get(next, target, || {
                    advance(next, target, (1.0 - frac) * dt_s, f)
                });
                last_row = Some((key, (rate, v, next)));
                (rate, v, next)
            }
        };
        out.speed.push(n);
        out.rate.push(rate);
        out.voltage.push(v);
        n = next;
    }
    out
}

/// The last speed a row's part advanced to from a speed under a target (a speed that settled
/// within a unit in the last place of its target stays there: the same `exp` is not taken
/// again). The part's length and τ's law are the same on every row.
#[derive(Default)]
struct Advanced(Option<(u64, u64, f64)>);

impl Advanced {
    fn get(&mut self, n: f64, target: f64, advance: impl FnOnce() -> f64) -> f64 {
        match self.0 {
            Some((a, b, x)) if a == n.to_bits() && b == target.to_bits() => x,
            _ => {
                let x = advance();
                self.0 = Some((n.to_bits(), target.to_bits(), x));
                x
            }
        }
    }
}

/// [`SpeedMap::speed_ss`] of the last few (command, voltage) pairs: a held command's steady
/// speed is computed once (the same number).
struct SteadyCache<'a> {
    map: &'a SpeedMap,
    keys: [Option<(u64, u64)>; 4],
    values: [f64; 4],
    next: usize,
}

impl<'a> SteadyCache<'a> {
    fn new(map: &'a SpeedMap) -> Self {
        SteadyCache {
            map,
            keys: [None; 4],
            values: [f64::NAN; 4],
            next: 0,
        }
    }

    fn at(&mut self, u: f64, v: f64) -> f64 {
        let key = (u.to_bits(), v.to_bits());
        if let Some(i) = self.keys.iter().position(|&k| k == Some(key)) {
            return self.values[i];
        }
        let x = self.map.speed_ss(u, v);
        self.keys[self.next] = Some(key);
        self.values[self.next] = x;
        self.next = (self.next + 1) % self.keys.len();
        x
    }
}

/// One channel's sensor (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sensor {
    /// Delay, s (may be negative: a channel ahead of the reference one).
    pub delay_s: f64,
    /// First-order lag, s (≥ 0; 0 = none).
    pub tau_s: f64,
    /// Refresh interval, s (≤ one row: read every row).
    pub refresh_s: f64,
    /// Offset, the channel's unit.
    pub offset: f64,
    /// Creep, the channel's unit per second.
    pub creep_per_s: f64,
}

/// The first-order lag `τ` (s) of `x` sampled every `dt_s`, `x` linear between samples (exact
/// first-order-hold discretisation: `s⁺ = a s + (1 − a) x_k + (1 − τ(1 − a)/dt)(x_{k+1} − x_k)`,
/// `a = e^{−dt/τ}`), from the steady state of `x_0`.
pub fn lag(x: &[f64], dt_s: f64, tau_s: f64) -> Vec<f64> {
    let Some(&first) = x.first() else {
        return Vec::new();
    };
    if tau_s.is_nan() || tau_s <= 0.0 {
        return x.to_vec();
    }
    let a = (-dt_s / tau_s).exp();
    let ramp = 1.0 - tau_s * (1.0 - a) / dt_s;
    let mut s = first;
    let mut out = Vec::with_capacity(x.len());
    out.push(s);
    for w in x.windows(2) {
        s = a * s + (1.0 - a) * w[0] + ramp * (w[1] - w[0]);
        out.push(s);
    }
    out
}

/// `x` delayed by `delay_s` (linear interpolation between samples; held at the record's ends).
pub fn delay(x: &[f64], dt_s: f64, delay_s: f64) -> Vec<f64> {
    if delay_s == 0.0 {
        return x.to_vec();
    }
    (0..x.len())
        .map(|k| delayed_at(x, dt_s, delay_s, k))
        .collect()
}

/// Row `k` of `x` delayed by `delay_s` (as [`delay`]).
pub fn delayed_at(x: &[f64], dt_s: f64, delay_s: f64, k: usize) -> f64 {
    let len = x.len();
    if len == 0 {
        return f64::NAN;
    }
    let t = (k as f64 - delay_s / dt_s).clamp(0.0, (len - 1) as f64);
    let i = t.floor() as usize;
    let f = t - i as f64;
    if i + 1 < len {
        x[i] + f * (x[i + 1] - x[i])
    } else {
        x[i]
    }
}

/// `x` read every `refresh_s` (from the record's start) and held in between; as it is when the
/// refresh is at most a row.
pub fn hold(x: &[f64], dt_s: f64, refresh_s: f64) -> Vec<f64> {
    let period = refresh_s / dt_s;
    if period.is_nan() || period <= 1.0 + 1e-9 {
        return x.to_vec();
    }
    let mut last_slot = usize::MAX;
    let mut value = f64::NAN;
    x.iter()
        .enumerate()
        .map(|(k, &v)| {
            let slot = (k as f64 / period + 1e-9).floor() as usize;
            if slot != last_slot {
                last_slot = slot;
                value = v;
            }
            value
        })
        .collect()
}

/// What the sensor `s` logs of `x` every `dt_s`: lag, delay, offset and creep, held over its
/// refresh interval.
pub fn sense(s: &Sensor, dt_s: f64, x: &[f64]) -> Vec<f64> {
    let y = delay(&lag(x, dt_s, s.tau_s), dt_s, s.delay_s);
    let y: Vec<f64> = y
        .iter()
        .enumerate()
        .map(|(k, v)| v + s.offset + s.creep_per_s * k as f64 * dt_s)
        .collect();
    hold(&y, dt_s, s.refresh_s)
}

/// The stand `p` under `command` (and the measured `voltage`, when given) every `dt_s`: each
/// channel of `sensors` as it logs its quantity.
pub fn simulate(
    p: &StandParams,
    dt_s: f64,
    command: &[f64],
    voltage: Option<&[f64]>,
    sensors: &[(Quantity, Sensor)],
) -> Vec<Vec<f64>> {
    let course = rotor_course(p, dt_s, command, voltage);
    sensors
        .iter()
        .map(|(q, s)| {
            let x: Vec<f64> = course
                .speed
                .iter()
                .zip(&course.rate)
                .map(|(&n, &r)| q.of(p, n, r))
                .collect();
            sense(s, dt_s, &x)
        })
        .collect()
}
