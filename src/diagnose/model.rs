//! The parametric model that `diagnose` fits: the 2nd-order linear core, optionally extended by
//! the catalogue's effects, simulated from the input alone (an output-error model: no measured
//! output is fed back, so the simulation on the validation part is a true prediction).
//!
//! ```text
//!   v_k  = u_{k−d}                                   dead_time (d whole samples)
//!   v_k ← min(v_k, L)                                saturation of the throttle
//!   v_k ← u_r · (max(v_k, 0) / u_r)^p                static_nonlinearity (u_r: mean throttle)
//!   v_k ← v_k · (1 + g_V · (V_k − V_r))               supply_sag (V_r: mean voltage)
//!   x_{k+1} = A x_k + B K v_k,  T_k = x_k[0]         2nd-order core, exact ZOH of
//!                                                    T'' + 2ζωn T' + ωn² T = ωn² K v
//!   s_k = (1 − g) T_k + g m_k,  m'' + 2ζm ωm m' + ωm² m = ωm² T     extra_mode (series)
//!   ŷ_k = c + s_k + r t_k + a sin(2π f t_k) + b cos(2π f t_k)       baseline_drift, periodic
//!   ŷ_k ← min(ŷ_k, Y)                                 saturation of the sensor
//! ```
//!
//! The states start in steady state for the first input sample. The same exact discretisation
//! as the simulated plant is used ([`propid_numerics::discretise::discretise_second_order`]).

use propid_numerics::discretise::discretise_second_order;

/// Index of each parameter in [`Params::v`].
pub mod ix {
    /// Natural frequency of the core, Hz.
    pub const FN: usize = 0;
    /// Damping ratio of the core.
    pub const ZETA: usize = 1;
    /// Static gain of the core, output units per unit throttle.
    pub const GAIN: usize = 2;
    /// Output offset, output units.
    pub const OFFSET: usize = 3;
    /// Exponent of the static map.
    pub const EXPONENT: usize = 4;
    /// Natural frequency of the extra mode, Hz.
    pub const MODE_FN: usize = 5;
    /// Damping ratio of the extra mode.
    pub const MODE_ZETA: usize = 6;
    /// Share of the output through the extra mode.
    pub const MODE_GAIN: usize = 7;
    /// Drift rate, output units per second.
    pub const DRIFT: usize = 8;
    /// Sine coefficient of the periodic term.
    pub const SIN_A: usize = 9;
    /// Cosine coefficient of the periodic term.
    pub const SIN_B: usize = 10;
    /// Frequency of the periodic term, Hz.
    pub const SIN_FREQ: usize = 11;
    /// Relative gain change per volt.
    pub const GAIN_PER_VOLT: usize = 12;
    /// Throttle clip level.
    pub const CLIP: usize = 13;
    /// Number of parameters.
    pub const COUNT: usize = 14;
}

/// Which parts of the model are switched on.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Spec {
    /// Input delay, whole samples.
    pub delay: usize,
    /// Power-law static map.
    pub static_map: bool,
    /// Extra series mode.
    pub extra_mode: bool,
    /// Linear drift term.
    pub drift: bool,
    /// Sinusoid term.
    pub periodic: bool,
    /// Voltage-scaled input.
    pub supply: bool,
    /// Throttle clip at [`ix::CLIP`].
    pub clip_throttle: bool,
    /// Sensor clip level (fixed, from the data).
    pub clip_sensor: Option<f64>,
}

impl Spec {
    /// Model order (states of the linear part).
    pub fn order(&self) -> usize {
        if self.extra_mode {
            4
        } else {
            2
        }
    }

    /// The parameters the fit adjusts (the delay and the throttle clip are searched on a grid).
    pub fn free(&self) -> Vec<usize> {
        let mut f = vec![ix::FN, ix::ZETA, ix::GAIN, ix::OFFSET];
        if self.static_map {
            f.push(ix::EXPONENT);
        }
        if self.extra_mode {
            f.extend([ix::MODE_FN, ix::MODE_ZETA, ix::MODE_GAIN]);
        }
        if self.drift {
            f.push(ix::DRIFT);
        }
        if self.periodic {
            f.extend([ix::SIN_A, ix::SIN_B, ix::SIN_FREQ]);
        }
        if self.supply {
            f.push(ix::GAIN_PER_VOLT);
        }
        f
    }
}

/// Parameter values (natural units), indexed by [`ix`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// The values.
    pub v: [f64; ix::COUNT],
}

impl Default for Params {
    fn default() -> Self {
        let mut v = [0.0; ix::COUNT];
        v[ix::FN] = 1.0;
        v[ix::ZETA] = 0.7;
        v[ix::GAIN] = 1.0;
        v[ix::EXPONENT] = 1.0;
        v[ix::MODE_FN] = 10.0;
        v[ix::MODE_ZETA] = 0.05;
        v[ix::MODE_GAIN] = 1.0;
        v[ix::SIN_FREQ] = 1.0;
        v[ix::CLIP] = f64::INFINITY;
        Params { v }
    }
}

/// The data a model is fitted to.
#[derive(Debug, Clone, Copy)]
pub struct Signals<'a> {
    /// Sample period, seconds.
    pub dt_s: f64,
    /// Input (throttle 0..1), gaps filled with the previous value.
    pub u: &'a [f64],
    /// Measured output; `NaN` where missing.
    pub y: &'a [f64],
    /// Supply voltage, if measured (gaps filled).
    pub voltage: Option<&'a [f64]>,
    /// Reference throttle of the static map (mean of the input).
    pub u_ref: f64,
    /// Reference voltage of the supply term (mean voltage).
    pub v_ref: f64,
}

/// Largest frequency a fitted mode may take, Hz (just below Nyquist).
pub fn max_freq_hz(dt_s: f64) -> f64 {
    0.49 / dt_s
}

/// Simulates the model on the whole record into `out` (same length as `sig.u`).
pub fn simulate(spec: &Spec, p: &Params, sig: &Signals, out: &mut [f64]) {
    let v = &p.v;
    let n = sig.u.len().min(out.len());
    if n == 0 {
        return;
    }
    let fmax = max_freq_hz(sig.dt_s);
    let (a, b) = discretise_second_order(
        v[ix::FN].clamp(1e-6, fmax),
        v[ix::ZETA].clamp(1e-4, 50.0),
        1.0,
        sig.dt_s,
    );
    let mode = spec.extra_mode.then(|| {
        discretise_second_order(
            v[ix::MODE_FN].clamp(1e-6, fmax),
            v[ix::MODE_ZETA].clamp(1e-4, 50.0),
            1.0,
            sig.dt_s,
        )
    });
    let input = |k: usize| -> f64 {
        let mut x = sig.u[k.saturating_sub(spec.delay)];
        if spec.clip_throttle {
            x = x.min(v[ix::CLIP]);
        }
        if spec.static_map {
            x = sig.u_ref * (x.max(0.0) / sig.u_ref).powf(v[ix::EXPONENT]);
        }
        if spec.supply {
            if let Some(volt) = sig.voltage {
                x *= 1.0 + v[ix::GAIN_PER_VOLT] * (volt[k] - sig.v_ref);
            }
        }
        x * v[ix::GAIN]
    };
    let t0 = input(0);
    let mut x = nalgebra::Vector2::new(t0, 0.0);
    let mut m = nalgebra::Vector2::new(t0, 0.0);
    let w = 2.0 * std::f64::consts::PI * v[ix::SIN_FREQ];
    let g = v[ix::MODE_GAIN];
    for (k, o) in out.iter_mut().enumerate().take(n) {
        let t = k as f64 * sig.dt_s;
        let thrust = x[0];
        let mut s = thrust;
        if let Some((am, bm)) = &mode {
            s = (1.0 - g) * thrust + g * m[0];
            m = am * m + bm * thrust;
        }
        let mut yk = v[ix::OFFSET] + s;
        if spec.drift {
            yk += v[ix::DRIFT] * t;
        }
        if spec.periodic {
            yk += v[ix::SIN_A] * (w * t).sin() + v[ix::SIN_B] * (w * t).cos();
        }
        if let Some(level) = spec.clip_sensor {
            yk = yk.min(level);
        }
        *o = yk;
        x = a * x + b * input(k);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_sim::plant::{Plant, PlantConfig};

    #[test]
    fn baseline_model_reproduces_the_clean_plant_exactly() {
        let cfg = PlantConfig {
            noise_rms_n: 0.0,
            quantum_n: 0.0,
            ..PlantConfig::default()
        };
        let mut plant = Plant::new(&cfg, 2e-3, 1).unwrap();
        let u: Vec<f64> = (0..600)
            .map(|k| if (k / 50) % 2 == 0 { 0.4 } else { 0.55 })
            .collect();
        plant.settle(u[0]);
        let y: Vec<f64> = u.iter().map(|&x| plant.step(x).thrust_n).collect();
        let mut p = Params::default();
        p.v[ix::FN] = cfg.fn_hz;
        p.v[ix::ZETA] = cfg.zeta;
        p.v[ix::GAIN] = cfg.gain_n_per_throttle;
        let sig = Signals {
            dt_s: 2e-3,
            u: &u,
            y: &y,
            voltage: None,
            u_ref: 0.5,
            v_ref: 0.0,
        };
        let mut out = vec![0.0; u.len()];
        simulate(&Spec::default(), &p, &sig, &mut out);
        for (a, b) in out.iter().zip(&y) {
            assert!((a - b).abs() < 1e-9);
        }
    }
}
