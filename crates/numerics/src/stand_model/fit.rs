//! The stand model ([`super`]) fitted jointly to whichever channels a record has (speed,
//! thrust, torque, current; any mix), each weighted by its own noise.
//!
//! # What is fitted
//! The speed is relative in the fit (`n_ref = 1` at the record's highest command `u_ref` and
//! mean supply voltage `V_ref`): every amplitude then enters linearly, and is found by least
//! squares for each value of the others (variable projection, Golub & Pereyra 1973, "The
//! differentiation of pseudo-inverses and nonlinear least squares problems", SIAM J. Numer.
//! Anal. 10(2), 413–432). Per channel, over its readings only (a held channel's interpolated
//! rows are no readings):
//!
//! ```text
//!   speed:          y = n_ref · S[ν]                           (a speed sensor reads no offset)
//!   thrust, torque: y = K · S[νᵉ] + c + d t                    (K = k nᵉ_ref; c, d offset, creep)
//!   current:        y = K_I · S[ν^{e+1}] + K_J · S[ν ν'] + c + d t
//! ```
//!
//! `S` is the channel's sensor (lag `τ_s`, delay `δ`), `ν` the relative speed of the rotor
//! course. The nonlinear parameters — the dead time `θ`, `ln τ_up`, `ln τ_down`, `γ`, the dead
//! band `u₀`, the map's exponent `a`, `e`, and each channel's `δ` and `ln τ_s` — are found by
//! [`crate::levenberg_marquardt`] within bounds, from the step figures of the channels
//! ([`crate::step_response`]: the reference channel's median dead time and τ per direction, each
//! other channel's extra dead time and τ over it) and the power law of the reference channel's
//! static map. The search's Jacobian comes from the model's sensitivities ([`jacobian`],
//! [`super::sensitivity`]: the rotor's course once per point), the covariance's from a forward
//! difference at the optimum.
//!
//! # The reference channel and what cannot be told apart
//! Delays in series add and two first-order lags in series are symmetric in their time
//! constants: the speed sensor's delay and lag cannot be told from the ESC's and the rotor's.
//! The reference channel (the speed when the record has it, else the thrust, torque, current)
//! therefore has no sensor delay or lag of its own: the rotor's figures include them, and every
//! other channel's sensor is timed against it. Without a speed channel the speed's unit and the
//! map's exponent are unknown: the speed is taken `∝ (u − u₀)·V` (`a = 1`), `e` is the thrust's
//! exponent on that speed, and `k_T`, `k_Q` cannot be given in rad/s ([`super::report`] says
//! so). `τ_down` needs the command to fall, `τ_up` to rise; `γ` needs moves to at least two
//! levels: otherwise `τ_down = τ_up`, `γ = 0` are held and reported as not shown.
//!
//! A record longer than [`MAX_ROWS`] rows is fitted over the window of that many rows in which
//! the command moves most often. [`fit`] then compares the rows around the command's moves
//! only ([`super::spans`]: [`SPAN_PRE_S`] before a move, [`SPAN_POST_TAUS`] of the slowest
//! step's time constant after it), the holds between them left out. A channel with more than [`MAX_READINGS`] readings is compared at every m-th of them (the
//! rotor and the sensors still stepped over every row): a pulse experiment of 100 000 rows is
//! fitted in seconds, its uncertainty that of the readings compared.
//!
//! # Weights and uncertainty
//! Each channel's residuals are divided by its noise `σ_c`: first the readings' own (robust
//! standard deviation of the differences of consecutive readings, `1.4826 · MAD / √2`), then,
//! after a first fit, the larger of that and the channel's residual RMS (a channel the model
//! fits worse than its noise — a current's electrical transient — does not outweigh the
//! others), and the fit is run again. The covariance of all parameters (the amplitudes with
//! them) is `s² (JᵀJ)⁻¹` of the weighted residuals ([`crate::levenberg_marquardt::covariance`]);
//! residuals correlated over a step make it optimistic.

mod jacobian;

use nalgebra::{DMatrix, DVector};

use super::{
    delayed_at, fill_held, lag, rotor_course, CurrentLaw, Quantity, RotorLaw, SpeedMap,
    StandParams, Supply,
};
use crate::levenberg_marquardt::{covariance, jacobian, minimise, LmOptions};
use crate::segment::{self, Command, SegmentRules};
use crate::static_map::{fit_power_law, levels};
use crate::step_response::{step_figures, Direction};

/// One measured channel of a record.
#[derive(Debug, Clone, Copy)]
pub struct Channel<'a> {
    /// Its key (`rpm`, `thrust`, `torque`, `current`).
    pub key: &'static str,
    /// What it measures.
    pub quantity: Quantity,
    /// Samples (NaN: missing).
    pub y: &'a [f64],
    /// True where a reader interpolated between readings (empty: every finite sample is one).
    pub interpolated: &'a [bool],
}

/// A record for the fit.
#[derive(Debug, Clone, Copy)]
pub struct FitInput<'a> {
    /// Row period, s.
    pub dt_s: f64,
    /// The command, throttle 0..1, held over each row (NaN holds the last).
    pub command: &'a [f64],
    /// The supply voltage per row when measured.
    pub voltage: Option<&'a [f64]>,
    /// The measured channels.
    pub channels: &'a [Channel<'a>],
    /// The segmentation's rules at the record's rate (steps for the start values).
    pub rules: SegmentRules,
}

/// Why a record gives no stand model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StandModelError {
    /// The command never moves.
    #[error("the command does not change: nothing in the record shows the stand's dynamics")]
    NoCommandChange,
    /// No channel of the stand has enough readings.
    #[error("no channel of the stand (rpm, thrust, torque, current) has {0} readings")]
    TooFewReadings(usize),
    /// The fit found no finite point.
    #[error("the stand model could not be evaluated on this record")]
    NotFitted,
}

/// Fewest readings of a channel for it to take part.
pub const MIN_READINGS: usize = 20;

/// Most readings of a channel compared with the model: a longer record is compared at every
/// m-th reading (its noise and refresh still read from all), which keeps a fit of 100 000 rows
/// to seconds.
pub const MAX_READINGS: usize = 8_000;

/// Most rows a fit steps the stand over: a longer record is fitted over the window of this
/// many rows in which the command moves most often ([`StandFit::window_s`]).
pub const MAX_ROWS: usize = 30_000;

/// Lower bound of a sensor's lag and of the rotor's time constants, s (a lag the rows cannot
/// show ends there).
pub const MIN_TAU_S: f64 = 1e-3;

/// One channel as fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelFit {
    /// Its key.
    pub key: &'static str,
    /// What it measures.
    pub quantity: Quantity,
    /// Whether it is the reference channel (no sensor delay or lag of its own).
    pub reference: bool,
    /// Readings used.
    pub readings: usize,
    /// Refresh interval (median spacing of the readings), s, and the spacing's spread, s.
    pub refresh_s: (f64, f64),
    /// Delay and its standard deviation, s (`None` for the reference).
    pub delay_s: Option<(f64, Option<f64>)>,
    /// Lag and its standard deviation, s (`None` for the reference).
    pub tau_s: Option<(f64, Option<f64>)>,
    /// The amplitudes (module doc), then offset and creep per second where fitted (then a
    /// sinusoid's sine and cosine amplitudes, [`Structure::sinusoid_hz`]).
    pub amplitudes: Vec<f64>,
    /// The exponent of its load, `e` or its own ([`Structure::exponent_per_load`]; `None`
    /// for the speed; a current's base is `n^{e_c + 1}`).
    pub exponent: Option<f64>,
    /// The noise the residuals were divided by.
    pub sigma: f64,
    /// RMS of the residuals, the channel's unit.
    pub rms: f64,
}

/// What the data can show, decided before the fit (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shows {
    /// The command rises somewhere.
    pub rises: bool,
    /// The command falls somewhere.
    pub falls: bool,
    /// Moves end at two levels or more.
    pub several_levels: bool,
    /// The record has a speed channel.
    pub speed: bool,
    /// `e` has a channel (thrust, torque or current).
    pub exponent: bool,
}

/// A value and its standard deviation (`None`: not given: fixed, or at a bound).
pub type Estimate = (f64, Option<f64>);

/// The fitted stand.
#[derive(Debug, Clone, PartialEq)]
pub struct StandFit {
    /// The parameters in the record's units (`speed_ref` the speed channel's rev/min at
    /// `u_ref` and `V_ref`, 1 without a speed channel; `k_t`, `k_q` per that speed unit^e).
    pub params: StandParams,
    /// What the data can show.
    pub shows: Shows,
    /// `θ`, s.
    pub dead_time_s: Estimate,
    /// `τ_up` at `speed_ref`, s.
    pub tau_up_s: Estimate,
    /// `τ_down` at `speed_ref`, s.
    pub tau_down_s: Estimate,
    /// `γ`.
    pub tau_speed_exponent: Estimate,
    /// `u₀`.
    pub command_zero: Estimate,
    /// `a`.
    pub map_exponent: Estimate,
    /// `e`.
    pub thrust_exponent: Estimate,
    /// `k_T` in N per (rad/s)^e (speed channel and thrust).
    pub k_t_rad: Option<Estimate>,
    /// `k_Q` in N·m per (rad/s)^e (speed channel and torque).
    pub k_q_rad: Option<Estimate>,
    /// The speed at `u_ref`, rev/min (speed channel only).
    pub speed_ref_rpm: Option<Estimate>,
    /// The supply's internal resistance from the measured voltage against the measured
    /// current, Ω.
    pub supply_resistance_ohm: Option<Estimate>,
    /// The channels.
    pub channels: Vec<ChannelFit>,
    /// Jacobians computed.
    pub iterations: usize,
    /// The span of the record fitted, s from its start ([`MAX_ROWS`]).
    pub window_s: (f64, f64),
}

/// A channel ready for the fit.
#[derive(Debug, Clone)]
struct Prepared {
    key: &'static str,
    quantity: Quantity,
    y: Vec<f64>,
    rows: Vec<usize>,
    noise: f64,
    sigma: f64,
    refresh: (f64, f64),
    reference: bool,
}

/// The nonlinear parameters (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
enum P {
    Dead,
    TauUp,
    TauDown,
    Gamma,
    Zero,
    MapExp,
    Exp,
    Delay(usize),
    Lag(usize),
    Limit,
    Freq,
    ModeFn,
    ModeZeta,
    VoltExp,
    ExpShift(usize),
}

/// Values of every nonlinear parameter (fixed or free).
#[derive(Debug, Clone, PartialEq)]
struct Values {
    dead: f64,
    tau_up: f64,
    tau_down: Option<f64>,
    gamma: f64,
    zero: f64,
    map_exp: f64,
    exp: f64,
    delay: Vec<f64>,
    lag: Vec<f64>,
    /// The command's upper clip ([`Structure::command_limit`]).
    limit: Option<f64>,
    /// A sinusoid's frequency, Hz ([`Structure::sinusoid_hz`]).
    freq: Option<f64>,
    /// A stand resonance's frequency, Hz, and damping ratio ([`Structure::mode`]).
    mode: Option<(f64, f64)>,
    /// `b` of the speed map's `(V/V_ref)^b` ([`Structure::voltage_exponent`]; 1 otherwise).
    volt_exp: f64,
    /// Per channel, its load exponent less `e` ([`Structure::exponent_per_load`]; 0 otherwise).
    exp_shift: Vec<f64>,
}

struct Problem {
    dt: f64,
    u: Vec<f64>,
    voltage: Option<Vec<f64>>,
    v_ref: f64,
    u_ref: f64,
    t_span: f64,
    channels: Vec<Prepared>,
    shows: Shows,
    layout: Vec<P>,
    bounds: Vec<(f64, f64)>,
    base: Values,
    /// Each load and current channel has a creep column.
    creep: bool,
    /// The record's row of each row fitted, when spans of it were joined ([`fit`]).
    origin: Option<Vec<usize>>,
}

fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    Some(v[v.len() / 2])
}

/// The readings' noise: `1.4826 · MAD / √2` of the differences of consecutive readings.
pub fn reading_noise(y: &[f64], rows: &[usize]) -> f64 {
    let mut d: Vec<f64> = rows.windows(2).map(|w| y[w[1]] - y[w[0]]).collect();
    let Some(m) = median(&mut d) else {
        return 0.0;
    };
    let mut dev: Vec<f64> = d.iter().map(|x| (x - m).abs()).collect();
    median(&mut dev).unwrap_or(0.0) * 1.4826 / std::f64::consts::SQRT_2
}

fn prepare(c: &Channel<'_>, missing_len: usize) -> Prepared {
    let rows: Vec<usize> = (0..c.y.len().min(missing_len))
        .filter(|&k| c.y[k].is_finite() && !c.interpolated.get(k).copied().unwrap_or(false))
        .collect();
    let mut gaps: Vec<f64> = rows.windows(2).map(|w| (w[1] - w[0]) as f64).collect();
    let var = if gaps.is_empty() {
        0.0
    } else {
        let m = gaps.iter().sum::<f64>() / gaps.len() as f64;
        gaps.iter().map(|g| (g - m) * (g - m)).sum::<f64>() / gaps.len() as f64
    };
    let refresh = median(&mut gaps).unwrap_or(1.0);
    let noise = reading_noise(c.y, &rows);
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &k| {
            (a.min(c.y[k]), b.max(c.y[k]))
        });
    let floor = 1e-6 * (hi - lo).abs().max(1e-9);
    // A long record is compared at every m-th reading (the rotor still stepped over every row).
    let m = rows.len().div_ceil(MAX_READINGS).max(1);
    let rows: Vec<usize> = rows.into_iter().step_by(m).collect();
    Prepared {
        key: c.key,
        quantity: c.quantity,
        y: c.y.to_vec(),
        rows,
        noise: noise.max(floor),
        sigma: noise.max(floor),
        refresh: (refresh, (var + 1.0 / 12.0).sqrt()),
        reference: false,
    }
}

/// [`super::speed_power`] of every speed, a speed held from one row to the next computed once
/// (the same numbers).
fn powers(speed: &[f64], e: f64) -> Vec<f64> {
    let mut last: Option<(u64, f64)> = None;
    speed
        .iter()
        .map(|&n| match last {
            Some((bits, x)) if bits == n.to_bits() => x,
            _ => {
                let x = super::speed_power(n, e);
                last = Some((n.to_bits(), x));
                x
            }
        })
        .collect()
}

/// Whether the command rises, falls, and to how many levels its moves lead (a move: a change
/// beyond 2 % of its range from one row to the next).
fn moves(u: &[f64]) -> (bool, bool, usize) {
    let (lo, hi) = u
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let range = hi - lo;
    if range.is_nan() || range <= 0.0 {
        return (false, false, 0);
    }
    let (mut up, mut down) = (false, false);
    let mut ends: Vec<i64> = Vec::new();
    for w in u.windows(2) {
        let d = w[1] - w[0];
        if d.abs() > 0.02 * range {
            up |= d > 0.0;
            down |= d < 0.0;
            let level = ((w[1] - lo) / (0.05 * range)).round() as i64;
            if !ends.contains(&level) {
                ends.push(level);
            }
        }
    }
    (up, down, ends.len())
}

impl Problem {
    /// Row `k`'s distance from the first row fitted, in rows of the record.
    fn row(&self, k: usize) -> f64 {
        match &self.origin {
            Some(o) => (o[k] - o[0]) as f64,
            None => k as f64,
        }
    }

    fn values(&self, z: &[f64]) -> Values {
        let mut v = self.base.clone();
        for (p, &x) in self.layout.iter().zip(z) {
            match *p {
                P::Dead => v.dead = x,
                P::TauUp => v.tau_up = x.exp(),
                P::TauDown => v.tau_down = Some(x.exp()),
                P::Gamma => v.gamma = x,
                P::Zero => v.zero = x,
                P::MapExp => v.map_exp = x,
                P::Exp => v.exp = x,
                P::Delay(c) => v.delay[c] = x,
                P::Lag(c) => v.lag[c] = x.exp(),
                P::Limit => v.limit = Some(x),
                P::Freq => v.freq = Some(x),
                P::ModeFn => v.mode = v.mode.map(|(_, z)| (x.exp(), z)),
                P::ModeZeta => v.mode = v.mode.map(|(f, _)| (f, x.exp())),
                P::VoltExp => v.volt_exp = x,
                P::ExpShift(c) => v.exp_shift[c] = x,
            }
        }
        v
    }

    fn z_of(&self, v: &Values) -> Vec<f64> {
        self.layout
            .iter()
            .map(|p| match *p {
                P::Dead => v.dead,
                P::TauUp => v.tau_up.ln(),
                P::TauDown => v.tau_down.unwrap_or(v.tau_up).ln(),
                P::Gamma => v.gamma,
                P::Zero => v.zero,
                P::MapExp => v.map_exp,
                P::Exp => v.exp,
                P::Delay(c) => v.delay[c],
                P::Lag(c) => v.lag[c].max(MIN_TAU_S).ln(),
                P::Limit => v.limit.unwrap_or(self.u_ref),
                P::Freq => v.freq.unwrap_or(1.0),
                P::ModeFn => v.mode.map_or(1.0, |m| m.0).ln(),
                P::ModeZeta => v.mode.map_or(0.1, |m| m.1).ln(),
                P::VoltExp => v.volt_exp,
                P::ExpShift(c) => v.exp_shift[c],
            })
            .collect()
    }

    /// The voltage that drives the speed map at `v`: the measured one, as `V_ref (V/V_ref)^b`
    /// when the map's voltage exponent `b` is not 1 ([`Structure::voltage_exponent`]).
    fn drive_voltage(&self, v: &Values) -> Option<std::borrow::Cow<'_, [f64]>> {
        let meas = self.voltage.as_deref()?;
        if v.volt_exp == 1.0 {
            return Some(std::borrow::Cow::Borrowed(meas));
        }
        let r = self.v_ref;
        Some(std::borrow::Cow::Owned(
            meas.iter()
                .map(|&x| r * (x / r).max(0.0).powf(v.volt_exp))
                .collect(),
        ))
    }

    /// The relative stand (`n_ref = 1`, unit amplitudes) of `v`.
    fn relative(&self, v: &Values) -> StandParams {
        StandParams {
            dead_time_s: v.dead,
            map: SpeedMap {
                speed_ref: 1.0,
                command_zero: v.zero,
                command_ref: self.u_ref,
                exponent: v.map_exp,
                voltage_ref: self.v_ref,
            },
            rotor: RotorLaw {
                tau_up_s: v.tau_up,
                tau_down_s: v.tau_down.unwrap_or(v.tau_up),
                tau_speed_exponent: v.gamma,
                speed_ref: 1.0,
            },
            thrust_exponent: v.exp,
            k_t: 1.0,
            k_q: 1.0,
            current: CurrentLaw {
                idle_a: 0.0,
                per_power: 1.0,
                per_acceleration: 0.0,
            },
            supply: Supply {
                open_circuit_v: self.v_ref,
                resistance_ohm: 0.0,
            },
        }
    }

    /// Per channel, the design columns at its readings (module doc): the sensed bases, then
    /// offset and creep for all but a speed.
    fn design(&self, v: &Values) -> Option<Vec<Vec<Vec<f64>>>> {
        let p = self.relative(v);
        let clipped: Vec<f64>;
        let command = match v.limit {
            Some(l) => {
                clipped = self.u.iter().map(|&x| x.min(l)).collect();
                &clipped
            }
            None => &self.u,
        };
        let course = rotor_course(&p, self.dt, command, self.drive_voltage(v).as_deref());
        if course.speed.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let out = self
            .channels
            .iter()
            .enumerate()
            .map(|(c, ch)| {
                let e = v.exp + v.exp_shift[c];
                let bases: Vec<Vec<f64>> = match ch.quantity {
                    Quantity::Speed => vec![course.speed.clone()],
                    Quantity::Thrust | Quantity::Torque => {
                        let load = powers(&course.speed, e);
                        vec![match v.mode {
                            Some((fn_hz, zeta)) => resonance(&load, self.dt, fn_hz, zeta),
                            None => load,
                        }]
                    }
                    Quantity::Current => vec![
                        powers(&course.speed, e + 1.0),
                        course
                            .speed
                            .iter()
                            .zip(&course.rate)
                            .map(|(&n, &r)| n.max(0.0) * r)
                            .collect(),
                    ],
                };
                let mut cols: Vec<Vec<f64>> = bases
                    .iter()
                    .map(|b| {
                        let s = lag(b, self.dt, v.lag[c]);
                        ch.rows
                            .iter()
                            .map(|&k| delayed_at(&s, self.dt, v.delay[c], k))
                            .collect()
                    })
                    .collect();
                if ch.quantity != Quantity::Speed {
                    cols.push(vec![1.0; ch.rows.len()]);
                    if self.creep {
                        cols.push(
                            ch.rows
                                .iter()
                                .map(|&k| self.row(k) * self.dt / self.t_span)
                                .collect(),
                        );
                    }
                    if let Some(f) = v.freq {
                        let w = std::f64::consts::TAU * f * self.dt;
                        cols.push(ch.rows.iter().map(|&k| (w * self.row(k)).sin()).collect());
                        cols.push(ch.rows.iter().map(|&k| (w * self.row(k)).cos()).collect());
                    }
                }
                cols
            })
            .collect();
        Some(out)
    }

    /// Least squares of each channel's readings on its columns (a tiny ridge keeps a column of
    /// zeros — a speed never above the dead band — solvable).
    fn solve(&self, design: &[Vec<Vec<f64>>]) -> Vec<Vec<f64>> {
        design
            .iter()
            .zip(&self.channels)
            .map(|(cols, ch)| {
                let m = cols.len();
                let mut aty = DVector::<f64>::zeros(m);
                for i in 0..m {
                    aty[i] = cols[i]
                        .iter()
                        .zip(&ch.rows)
                        .map(|(a, &k)| a * ch.y[k])
                        .sum();
                }
                ridged_gram(cols)
                    .cholesky()
                    .map(|c| c.solve(&aty).iter().copied().collect())
                    .unwrap_or_else(|| vec![0.0; m])
            })
            .collect()
    }

    /// Weighted residuals at `v` with the amplitudes `lin` (solved when `None`).
    fn residuals(&self, v: &Values, lin: Option<&[Vec<f64>]>, r: &mut Vec<f64>) -> bool {
        let Some(design) = self.design(v) else {
            return false;
        };
        let solved;
        let lin = match lin {
            Some(l) => l,
            None => {
                solved = self.solve(&design);
                &solved
            }
        };
        r.clear();
        for ((cols, ch), beta) in design.iter().zip(&self.channels).zip(lin) {
            for (i, &k) in ch.rows.iter().enumerate() {
                let fit: f64 = cols.iter().zip(beta).map(|(c, b)| c[i] * b).sum();
                r.push((ch.y[k] - fit) / ch.sigma);
            }
        }
        r.iter().all(|x| x.is_finite())
    }

    fn rms(&self, v: &Values) -> Vec<f64> {
        let Some(design) = self.design(v) else {
            return vec![f64::NAN; self.channels.len()];
        };
        let lin = self.solve(&design);
        design
            .iter()
            .zip(&self.channels)
            .zip(&lin)
            .map(|((cols, ch), beta)| {
                let s: f64 = ch
                    .rows
                    .iter()
                    .enumerate()
                    .map(|(i, &k)| {
                        let f: f64 = cols.iter().zip(beta).map(|(c, b)| c[i] * b).sum();
                        (ch.y[k] - f).powi(2)
                    })
                    .sum();
                (s / ch.rows.len().max(1) as f64).sqrt()
            })
            .collect()
    }

    fn run(&self, z0: &[f64], max_iter: usize) -> Option<(Vec<f64>, f64, usize)> {
        let mut f = jacobian::Search(self);
        let opts = LmOptions {
            max_iter,
            ..LmOptions::default()
        };
        let res = minimise(&mut f, z0, &self.bounds, &opts)?;
        Some((res.z, res.cost, res.iterations))
    }
}

/// The median dead time and time constant of the steps of `y` in `dir` (all steps when none
/// is in `dir`).
fn step_timing(
    y: &[f64],
    dt: f64,
    steps: &[segment::Step],
    dir: Direction,
) -> (Option<f64>, Option<f64>) {
    let figs: Vec<_> = steps.iter().map(|s| step_figures(y, dt, s)).collect();
    let pick = |want: Option<Direction>| {
        let mut dead: Vec<f64> = figs
            .iter()
            .filter(|f| want.map_or(true, |d| f.direction == d))
            .filter_map(|f| f.dead_time_s)
            .collect();
        let mut tau: Vec<f64> = figs
            .iter()
            .filter(|f| want.map_or(true, |d| f.direction == d))
            .filter_map(|f| f.time_constant_s.or(f.dead_time_s.map(|_| dt)))
            .collect();
        (median(&mut dead), median(&mut tau))
    };
    match pick(Some(dir)) {
        (Some(d), t) => (Some(d), t),
        _ => pick(None),
    }
}

/// Fits the stand model to `input` (module doc) over the rows around the command's moves
/// ([`super::spans`], [`SPAN_PRE_S`], [`SPAN_POST_TAUS`]).
pub fn fit(input: &FitInput<'_>) -> Result<StandFit, StandModelError> {
    windowed(input, |within| {
        let Some((joined, origin)) = join_spans(within) else {
            return fit_rows(within, &Structure::full(), None, None).map(|(f, _, _)| f);
        };
        let channels: Vec<Channel<'_>> = joined
            .channels
            .iter()
            .zip(within.channels)
            .map(|((y, flags), c)| Channel {
                y,
                interpolated: flags,
                ..*c
            })
            .collect();
        let input = FitInput {
            command: &joined.command,
            voltage: joined.voltage.as_deref(),
            channels: &channels,
            ..*within
        };
        fit_rows(&input, &Structure::full(), None, Some(origin)).map(|(f, _, _)| f)
    })
}

/// Rows kept before a move, s (at least: three dead times of the steps when longer).
pub const SPAN_PRE_S: f64 = 0.1;

/// Rows kept after a move: this many of the slowest step's time constant plus its dead time
/// (on any channel), and at least [`SPAN_POST_MIN_S`]: `e^{−20}` of a step left when the
/// rows left out begin.
pub const SPAN_POST_TAUS: f64 = 20.0;

/// The fewest seconds kept after a move.
pub const SPAN_POST_MIN_S: f64 = 0.5;

/// A record's rows joined from its spans around the moves.
struct Joined {
    command: Vec<f64>,
    voltage: Option<Vec<f64>>,
    channels: Vec<(Vec<f64>, Vec<bool>)>,
}

/// `input` over the spans around its command's moves ([`super::spans::around_moves`]) and the
/// record's row of each row kept; `None` when every row is kept.
fn join_spans(input: &FitInput<'_>) -> Option<(Joined, Vec<usize>)> {
    let dt = input.dt_s;
    let u = fill_held(input.command, 0.0);
    let steps = segment::steps(Command::new(&u), &input.rules);
    let (mut slowest, mut dead) = (0.0f64, 0.0f64);
    for c in input.channels {
        for dir in [Direction::Up, Direction::Down] {
            let (d, t) = step_timing(c.y, dt, &steps, dir);
            slowest = slowest.max(t.unwrap_or(0.0));
            dead = dead.max(d.unwrap_or(0.0));
        }
    }
    let pre = (SPAN_PRE_S.max(3.0 * dead) / dt).ceil() as usize;
    let post_s = (SPAN_POST_TAUS * (slowest + dead)).max(SPAN_POST_MIN_S);
    let post = (post_s / dt).ceil() as usize;
    let kept = super::spans::around_moves(&u, pre, post);
    if kept == [(0, u.len())] {
        return None;
    }
    // A channel shorter than the command is missing (NaN) past its end, as `prepare` reads it.
    let pick = |x: &[f64]| -> Vec<f64> {
        kept.iter()
            .flat_map(|&(a, b)| (a..b).map(|k| x.get(k).copied().unwrap_or(f64::NAN)))
            .collect()
    };
    let flags = |x: &[bool]| -> Vec<bool> {
        if x.is_empty() {
            return Vec::new();
        }
        kept.iter()
            .flat_map(|&(a, b)| (a..b).map(|k| x.get(k).copied().unwrap_or(false)))
            .collect()
    };
    let joined = Joined {
        command: pick(input.command),
        voltage: input.voltage.map(pick),
        channels: input
            .channels
            .iter()
            .map(|c| (pick(c.y), flags(c.interpolated)))
            .collect(),
    };
    let origin = kept.iter().flat_map(|&(a, b)| a..b).collect();
    Some((joined, origin))
}

/// `f` on the rows of `input` the fit steps over ([`window`]), its [`StandFit::window_s`] set.
fn windowed<T: WithWindow>(
    input: &FitInput<'_>,
    f: impl FnOnce(&FitInput<'_>) -> Result<T, StandModelError>,
) -> Result<T, StandModelError> {
    let (start, end) = window(input.command);
    let channels: Vec<Channel<'_>> = input
        .channels
        .iter()
        .map(|c| Channel {
            y: &c.y[start.min(c.y.len())..end.min(c.y.len())],
            interpolated: &c.interpolated
                [start.min(c.interpolated.len())..end.min(c.interpolated.len())],
            ..*c
        })
        .collect();
    let within = FitInput {
        command: &input.command[start..end],
        voltage: input
            .voltage
            .map(|v| &v[start.min(v.len())..end.min(v.len())]),
        channels: &channels,
        ..*input
    };
    let mut f = f(&within)?;
    f.set_window(start, end, input.dt_s, input.command.len());
    Ok(f)
}

/// A fit's result that records the rows it was fitted over.
trait WithWindow {
    fn set_window(&mut self, start: usize, end: usize, dt_s: f64, len: usize);
}

impl WithWindow for StandFit {
    fn set_window(&mut self, start: usize, _end: usize, dt_s: f64, _len: usize) {
        let at = start as f64 * dt_s;
        self.window_s = (at + self.window_s.0, at + self.window_s.1);
    }
}

/// The rows fitted: all of a record of at most [`MAX_ROWS`], else the window of [`MAX_ROWS`]
/// rows (on a grid of a twentieth of it) in which the command moves most often.
fn window(command: &[f64]) -> (usize, usize) {
    let len = command.len();
    if len <= MAX_ROWS {
        return (0, len);
    }
    let u = fill_held(command, 0.0);
    let (lo, hi) = u
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let moved: Vec<usize> = u
        .windows(2)
        .map(|w| usize::from((w[1] - w[0]).abs() > 0.02 * (hi - lo)))
        .collect();
    let mut sum = vec![0usize; moved.len() + 1];
    for (i, m) in moved.iter().enumerate() {
        sum[i + 1] = sum[i] + m;
    }
    let stride = (MAX_ROWS / 20).max(1);
    let best = (0..=len - MAX_ROWS)
        .step_by(stride)
        .max_by_key(|&s| {
            (
                sum[(s + MAX_ROWS - 1).min(moved.len())] - sum[s],
                usize::MAX - s,
            )
        })
        .unwrap_or(0);
    (best, best + MAX_ROWS)
}

fn fit_rows(
    input: &FitInput<'_>,
    st: &Structure,
    warm: Option<&Warm>,
    origin: Option<Vec<usize>>,
) -> Result<(StandFit, Problem, Vec<f64>), StandModelError> {
    let dt = input.dt_s;
    let len = input.command.len();
    let u = fill_held(input.command, 0.0);
    let (rises, falls, n_levels) = moves(&u);
    if !(rises || falls) {
        return Err(StandModelError::NoCommandChange);
    }
    let mut channels: Vec<Prepared> = input
        .channels
        .iter()
        .map(|c| prepare(c, len))
        .filter(|c| c.rows.len() >= MIN_READINGS)
        .collect();
    channels.sort_by_key(|c| c.quantity);
    if channels.is_empty() {
        return Err(StandModelError::TooFewReadings(MIN_READINGS));
    }
    channels[0].reference = true;
    let speed = channels[0].quantity == Quantity::Speed;
    let exponent = channels.iter().any(|c| c.quantity != Quantity::Speed);
    let shows = Shows {
        rises,
        falls,
        several_levels: n_levels >= 2,
        speed,
        exponent,
    };
    let u_lo = u.iter().copied().fold(f64::INFINITY, f64::min);
    let u_ref = u.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let range = u_ref - u_lo;
    let voltage = input.voltage.map(|v| {
        let mean = v.iter().filter(|x| x.is_finite()).sum::<f64>()
            / v.iter().filter(|x| x.is_finite()).count().max(1) as f64;
        fill_held(v, mean)
    });
    let v_ref = voltage
        .as_ref()
        .map(|v| v.iter().sum::<f64>() / v.len().max(1) as f64)
        .filter(|m| m.is_finite() && *m > 0.0)
        .unwrap_or(1.0);
    let voltage = voltage.filter(|_| v_ref != 1.0 && st.voltage);

    // Start values from the step figures and the reference channel's static map.
    let cmd = Command::new(&u);
    let steps = segment::steps(cmd, &input.rules);
    let reference = &channels[0];
    let (dead_up, tau_up) = step_timing(&reference.y, dt, &steps, Direction::Up);
    let (_, tau_down) = step_timing(&reference.y, dt, &steps, Direction::Down);
    let dead0 = dead_up.unwrap_or(2.0 * dt).clamp(0.0, 1.0);
    let tau_up0 = tau_up.unwrap_or(0.05).max(dt);
    let tau_down0 = tau_down.unwrap_or(tau_up0).max(dt);
    let holds: Vec<segment::Run> = segment::holds(cmd, &input.rules).collect();
    let law = fit_power_law(&levels(&reference.y, &holds));
    let zero0 = law
        .map(|l| l.u0)
        .filter(|z| z.is_finite() && *z < u_ref - 0.05 * range)
        .unwrap_or(u_lo - 0.1 * range.max(1e-3));
    let (map0, exp0) = match (speed, law) {
        (true, Some(l)) => (l.exponent.clamp(0.5, 2.5), 2.0),
        (false, Some(l)) if reference.quantity != Quantity::Current => {
            (1.0, l.exponent.clamp(1.0, 3.5))
        }
        _ => (1.0, 2.0),
    };
    let mut delay0 = vec![0.0; channels.len()];
    let mut lag0 = vec![0.0; channels.len()];
    for (c, ch) in channels.iter().enumerate().skip(1) {
        let (d, t) = step_timing(&ch.y, dt, &steps, Direction::Up);
        delay0[c] = d.map_or(0.0, |d| (d - dead0).clamp(0.0, 0.5));
        lag0[c] = t.map_or(0.01, |t| (t - tau_up0).max(0.3 * dt).max(2.0 * MIN_TAU_S));
    }
    let base = Values {
        dead: dead0,
        tau_up: tau_up0,
        tau_down: None,
        gamma: 0.0,
        zero: zero0,
        map_exp: map0,
        exp: exp0,
        delay: delay0,
        lag: lag0,
        limit: None,
        freq: None,
        mode: None,
        volt_exp: 1.0,
        exp_shift: vec![0.0; channels.len()],
    };
    let mut layout = vec![];
    let mut bounds = vec![];
    let mut base = base;
    if st.dead_time {
        layout.push(P::Dead);
        bounds.push((0.0, 1.0));
    } else {
        base.dead = 0.0;
    }
    layout.push(P::TauUp);
    bounds.push((MIN_TAU_S.ln(), 5f64.ln()));
    if rises && falls && st.asymmetric {
        layout.push(P::TauDown);
        bounds.push((MIN_TAU_S.ln(), 5f64.ln()));
        base.tau_down = Some(tau_down0);
    }
    if shows.several_levels && st.speed_dependent_tau {
        layout.push(P::Gamma);
        bounds.push((-1.0, 3.0));
    }
    layout.push(P::Zero);
    bounds.push((u_lo - range.max(0.1), u_ref - 0.05 * range));
    if speed && st.static_map {
        layout.push(P::MapExp);
        bounds.push((0.3, 3.0));
    } else if speed {
        base.map_exp = 1.0;
    }
    if exponent && st.static_map {
        layout.push(P::Exp);
        bounds.push((0.5, 4.5));
        // `e` is the first load channel's (the thrust's when the record has it); each other
        // load channel's exponent is `e` plus its own shift.
        let first_load = channels.iter().position(|c| c.quantity != Quantity::Speed);
        for (c, ch) in channels.iter().enumerate() {
            if st.exponent_per_load && ch.quantity != Quantity::Speed && Some(c) != first_load {
                layout.push(P::ExpShift(c));
                bounds.push((-1.5, 1.5));
            }
        }
    } else if exponent {
        base.exp = 2.0;
    }
    for c in 1..channels.len() {
        if !st.lags(channels[c].key) {
            base.delay[c] = 0.0;
            base.lag[c] = 0.0;
            continue;
        }
        layout.push(P::Delay(c));
        bounds.push((-0.5, 1.0));
        layout.push(P::Lag(c));
        bounds.push((MIN_TAU_S.ln(), 3f64.ln()));
    }
    if voltage.is_some() && st.voltage_exponent {
        layout.push(P::VoltExp);
        bounds.push((0.0, 2.0));
    }
    if st.command_limit && range > 0.0 {
        layout.push(P::Limit);
        bounds.push((u_lo + 0.3 * range, u_ref));
        base.limit = Some(u_ref - 0.1 * range);
    }
    if let Some(f0) = st.sinusoid_hz.filter(|f| f.is_finite() && *f > 0.0) {
        layout.push(P::Freq);
        bounds.push((0.97 * f0, 1.03 * f0));
        base.freq = Some(f0);
    }
    if let Some((f0, z0)) = st.mode.filter(|m| m.0.is_finite() && m.0 > 0.0) {
        let top = 0.45 / dt;
        let f0 = f0.min(0.9 * top);
        layout.push(P::ModeFn);
        bounds.push(((0.6 * f0).ln(), (1.5 * f0).min(top).ln()));
        layout.push(P::ModeZeta);
        bounds.push((0.01f64.ln(), 1f64.ln()));
        base.mode = Some((f0, z0.clamp(0.011, 0.99)));
    }
    if let Some(w) = warm {
        w.overlay(&mut base, &channels);
    }
    let t_span = match &origin {
        Some(o) if o.len() >= 2 => (o[o.len() - 1] - o[0]) as f64 * dt,
        _ => (len.max(2) - 1) as f64 * dt,
    };
    let mut problem = Problem {
        dt,
        u,
        voltage,
        v_ref,
        u_ref,
        t_span,
        channels,
        shows,
        layout,
        bounds,
        base,
        creep: st.creep,
        origin,
    };
    let z0 = problem.z_of(&problem.base);
    let (z, cost, iterations) = match warm.and_then(|w| w.sigma.as_ref().map(|s| (w, s))) {
        // Given weights (a diagnosis compares its models on the baseline's): one pass.
        Some((w, sigma)) => {
            for ch in problem.channels.iter_mut() {
                if let Some(&(_, s)) = sigma.iter().find(|(k, _)| *k == ch.key) {
                    ch.sigma = s;
                }
            }
            problem
                .run(&z0, w.max_iter)
                .ok_or(StandModelError::NotFitted)?
        }
        // Two passes: the readings' noise as weights, then the larger of it and the
        // residuals'.
        None => {
            let (z1, _, it1) = problem.run(&z0, 30).ok_or(StandModelError::NotFitted)?;
            let rms = problem.rms(&problem.values(&z1));
            for (ch, r) in problem.channels.iter_mut().zip(&rms) {
                if r.is_finite() {
                    ch.sigma = ch.noise.max(*r);
                }
            }
            let (z, cost, it2) = problem.run(&z1, 40).ok_or(StandModelError::NotFitted)?;
            (z, cost, it1 + it2)
        }
    };
    if !cost.is_finite() {
        return Err(StandModelError::NotFitted);
    }
    let f = summarise(&problem, &z, cost, iterations);
    Ok((f, problem, z))
}

/// The covariance of the nonlinear parameters and the amplitudes at `z` (module doc), the
/// amplitudes, and which parameters sit at a bound.
fn uncertainty(
    problem: &Problem,
    z: &[f64],
    cost: f64,
) -> (Option<DMatrix<f64>>, Vec<Vec<f64>>, Vec<bool>) {
    let v = problem.values(z);
    let Some(design) = problem.design(&v) else {
        return (None, Vec::new(), Vec::new());
    };
    let lin = problem.solve(&design);
    let p = z.len();
    let n_lin: usize = lin.iter().map(Vec::len).sum();
    let mut r = Vec::new();
    if !problem.residuals(&v, Some(&lin), &mut r) {
        return (None, lin, Vec::new());
    }
    let mut f =
        |zz: &[f64], out: &mut Vec<f64>| problem.residuals(&problem.values(zz), Some(&lin), out);
    let Some(jz) = jacobian(&mut f, z, &r, &problem.bounds, 1e-6) else {
        return (None, lin, Vec::new());
    };
    let mut jac = DMatrix::<f64>::zeros(r.len(), p + n_lin);
    jac.view_mut((0, 0), (r.len(), p)).copy_from(&jz);
    let mut row = 0;
    let mut col = p;
    for (cols, ch) in design.iter().zip(&problem.channels) {
        for i in 0..ch.rows.len() {
            for (j, c) in cols.iter().enumerate() {
                jac[(row + i, col + j)] = -c[i] / ch.sigma;
            }
        }
        row += ch.rows.len();
        col += cols.len();
    }
    let at_bound: Vec<bool> = z
        .iter()
        .zip(&problem.bounds)
        .map(|(&x, &(lo, hi))| {
            let tol = 1e-6 * (hi - lo);
            x <= lo + tol || x >= hi - tol
        })
        .chain(std::iter::repeat(false).take(n_lin))
        .collect();
    (covariance(&jac, cost, &at_bound), lin, at_bound)
}

fn summarise(problem: &Problem, z: &[f64], cost: f64, iterations: usize) -> StandFit {
    let v = problem.values(z);
    let (cov, lin, at_bound) = uncertainty(problem, z, cost);
    let p = z.len();
    let sd = |i: usize| -> Option<f64> {
        let c = cov.as_ref()?;
        (!at_bound.get(i).copied().unwrap_or(true)).then(|| c[(i, i)].max(0.0).sqrt())
    };
    let index = |want: P| problem.layout.iter().position(|&q| q == want);
    let plain = |want: P, value: f64| -> Estimate { (value, index(want).and_then(sd)) };
    // τ = e^z: sd_τ = τ · sd_z.
    let logged =
        |want: P, value: f64| -> Estimate { (value, index(want).and_then(sd).map(|s| s * value)) };
    // Offsets of each channel's amplitudes in the covariance.
    let mut lin_at = Vec::new();
    let mut col = p;
    for l in &lin {
        lin_at.push(col);
        col += l.len();
    }
    let rms = problem.rms(&v);
    let speed_c = problem
        .channels
        .iter()
        .position(|c| c.quantity == Quantity::Speed);
    let amp = |c: usize| lin.get(c).and_then(|l| l.first()).copied();
    let speed_ref = speed_c.and_then(amp).unwrap_or(1.0);
    let var = |a: usize, b: usize| cov.as_ref().map(|c| c[(a, b)]);
    // k in N per (rad/s)^e from K (per relative speed^e), n_ref (rev/min) and e: the delta
    // method on (K, n_ref, e).
    let per_rad = |c: usize| -> Option<Estimate> {
        let s = speed_c?;
        let k = amp(c)?;
        let w = speed_ref * std::f64::consts::TAU / 60.0;
        let e = v.exp + v.exp_shift[c];
        let value = k / w.powf(e);
        let (ik, is) = (lin_at[c], lin_at[s]);
        let ie = index(P::Exp);
        let g_k = 1.0 / w.powf(e);
        let g_n = -e * value / speed_ref;
        let g_e = -value * w.ln();
        let mut idx = vec![(ik, g_k), (is, g_n)];
        if let Some(ie) = ie.filter(|&i| !at_bound[i]) {
            idx.push((ie, g_e));
        }
        let mut s2 = 0.0;
        for &(a, ga) in &idx {
            for &(b, gb) in &idx {
                s2 += ga * gb * var(a, b)?;
            }
        }
        Some((value, Some(s2.max(0.0).sqrt())))
    };
    let find = |q: Quantity| problem.channels.iter().position(|c| c.quantity == q);
    let k_t_rad = find(Quantity::Thrust).and_then(per_rad);
    let k_q_rad = find(Quantity::Torque).and_then(per_rad);
    let speed_ref_rpm = speed_c.map(|c| {
        (
            speed_ref,
            var(lin_at[c], lin_at[c]).map(|x| x.max(0.0).sqrt()),
        )
    });
    let channels: Vec<ChannelFit> = problem
        .channels
        .iter()
        .enumerate()
        .map(|(c, ch)| {
            let amplitudes = lin.get(c).cloned().unwrap_or_default();
            let amplitudes = match ch.quantity {
                Quantity::Speed => amplitudes,
                // creep per second: the column was t / t_span (after the bases and the
                // offset; a sinusoid's pair follows it).
                q => {
                    let mut a = amplitudes;
                    let at = if q == Quantity::Current { 3 } else { 2 };
                    if let Some(creep) = a.get_mut(at).filter(|_| problem.creep) {
                        *creep /= problem.t_span;
                    }
                    a
                }
            };
            ChannelFit {
                key: ch.key,
                quantity: ch.quantity,
                reference: ch.reference,
                readings: ch.rows.len(),
                refresh_s: (ch.refresh.0 * problem.dt, ch.refresh.1 * problem.dt),
                delay_s: (!ch.reference).then(|| plain(P::Delay(c), v.delay[c])),
                tau_s: (!ch.reference).then(|| logged(P::Lag(c), v.lag[c])),
                amplitudes,
                exponent: (ch.quantity != Quantity::Speed).then(|| v.exp + v.exp_shift[c]),
                sigma: ch.sigma,
                rms: rms[c],
            }
        })
        .collect();
    let supply_resistance_ohm = supply_resistance(problem);
    let rel = problem.relative(&v);
    let amp_of = |q: Quantity| find(q).and_then(amp).unwrap_or(0.0);
    let e = v.exp;
    let e_of = |q: Quantity| e + find(q).map_or(0.0, |c| v.exp_shift[c]);
    let params = StandParams {
        map: SpeedMap {
            speed_ref,
            ..rel.map
        },
        rotor: RotorLaw {
            speed_ref,
            ..rel.rotor
        },
        k_t: amp_of(Quantity::Thrust) / speed_ref.powf(e),
        k_q: amp_of(Quantity::Torque) / speed_ref.powf(e_of(Quantity::Torque)),
        current: match find(Quantity::Current) {
            Some(c) => CurrentLaw {
                idle_a: lin[c].get(2).copied().unwrap_or(0.0),
                per_power: lin[c][0] / speed_ref.powf(e_of(Quantity::Current) + 1.0),
                per_acceleration: lin[c][1] / (speed_ref * speed_ref),
            },
            None => CurrentLaw::default(),
        },
        supply: Supply {
            open_circuit_v: problem.v_ref,
            resistance_ohm: supply_resistance_ohm.map_or(0.0, |r| r.0),
        },
        ..rel
    };
    let tau_down = v.tau_down.unwrap_or(v.tau_up);
    StandFit {
        params,
        shows: problem.shows,
        dead_time_s: plain(P::Dead, v.dead),
        tau_up_s: logged(P::TauUp, v.tau_up),
        tau_down_s: logged(P::TauDown, tau_down),
        tau_speed_exponent: plain(P::Gamma, v.gamma),
        command_zero: plain(P::Zero, v.zero),
        map_exponent: plain(P::MapExp, v.map_exp),
        thrust_exponent: plain(P::Exp, e),
        k_t_rad,
        k_q_rad,
        speed_ref_rpm,
        supply_resistance_ohm,
        channels,
        iterations,
        window_s: match &problem.origin {
            Some(o) => (
                o[0] as f64 * problem.dt,
                (o[o.len() - 1] + 1) as f64 * problem.dt,
            ),
            None => (0.0, problem.t_span + problem.dt),
        },
    }
}

/// `V = V_oc − R I` by least squares over the rows where both the voltage and the current are
/// read; `R` and its standard error.
fn supply_resistance(problem: &Problem) -> Option<Estimate> {
    let v = problem.voltage.as_ref()?;
    let cur = problem
        .channels
        .iter()
        .find(|c| c.quantity == Quantity::Current)?;
    let pts: Vec<(f64, f64)> = cur.rows.iter().map(|&k| (cur.y[k], v[k])).collect();
    let n = pts.len() as f64;
    if pts.len() < 3 {
        return None;
    }
    let (mi, mv) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), (i, v)| (a + i / n, b + v / n));
    let sii: f64 = pts.iter().map(|(i, _)| (i - mi).powi(2)).sum();
    if sii.is_nan() || sii <= 0.0 {
        return None;
    }
    let siv: f64 = pts.iter().map(|(i, v)| (i - mi) * (v - mv)).sum();
    let slope = siv / sii;
    let sse: f64 = pts
        .iter()
        .map(|(i, v)| (v - mv - slope * (i - mi)).powi(2))
        .sum();
    let sd = (sse / (n - 2.0) / sii).sqrt();
    Some((-slope, Some(sd)))
}

/// Which parts of the stand a fit frees ([`fit_structured`]). [`Structure::full`] is what
/// [`fit`] fits: every part the data can show. `propid diagnose` starts from
/// [`Structure::default`] — the ESC's dead band, one rotor time constant, `a = 1`, `e = 2`, the
/// amplitudes and offsets, no dead time, no sensor delay or lag, no creep, the supply taken
/// constant — and names what each part it frees gains on held-out data.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Structure {
    /// The ESC's dead time `θ` is fitted (else 0).
    pub dead_time: bool,
    /// `τ_down` is fitted apart from `τ_up` (else equal).
    pub asymmetric: bool,
    /// `γ` is fitted (else 0).
    pub speed_dependent_tau: bool,
    /// The map's exponent `a` and the load's exponent `e` are fitted (else 1 and 2).
    pub static_map: bool,
    /// Every non-reference channel's sensor delay and lag are fitted.
    pub lag_all: bool,
    /// These channels' sensor delay and lag are fitted (by key).
    pub lagged: Vec<&'static str>,
    /// Load and current channels have a creep.
    pub creep: bool,
    /// The measured supply voltage drives the speed map (else the supply is constant).
    pub voltage: bool,
    /// With [`Structure::voltage`], the speed follows `(V/V_ref)^b` with `b` fitted (else
    /// `b = 1`, a duty-cycle ESC on an unloaded motor): under a propeller's load the winding's
    /// resistance takes part of a sag (`n ≈ K_v (d V − I R_m)`), and a loaded rotor slows by
    /// less than the voltage falls (`b < 1`).
    pub voltage_exponent: bool,
    /// With [`Structure::static_map`], every load channel but the first (the thrust when the
    /// record has it) has its own exponent `e_c` (else all share `e`): a propeller's thrust
    /// and torque coefficients change differently with its Reynolds number.
    pub exponent_per_load: bool,
    /// The command is clipped at a fitted level `L` (`u → min(u, L)`: the top of the ESC's
    /// range, a power limit).
    pub command_limit: bool,
    /// Every load and current channel has a sinusoid `a sin 2πft + b cos 2πft` (`a`, `b`
    /// amplitudes per channel, `f` fitted within 3 % of this start, Hz).
    pub sinusoid_hz: Option<f64>,
    /// Thrust and torque reach their sensor through a resonance of the stand, unit gain at
    /// rest: `ωm² / (s² + 2ζm ωm s + ωm²)`, fitted from this start `(fn Hz, ζ)`.
    pub mode: Option<(f64, f64)>,
}

impl Structure {
    /// The whole stand model ([`fit`]).
    pub fn full() -> Structure {
        Structure {
            dead_time: true,
            asymmetric: true,
            speed_dependent_tau: true,
            static_map: true,
            lag_all: true,
            creep: true,
            voltage: true,
            ..Structure::default()
        }
    }

    fn lags(&self, key: &str) -> bool {
        self.lag_all || self.lagged.contains(&key)
    }
}

/// A fit's parameters as a start for another fit of the same record ([`fit_structured`]):
/// the values of its free parameters, and, when given, the channels' weights (one pass of
/// `max_iter` Jacobians with them, instead of the two passes that set them).
#[derive(Debug, Clone, PartialEq)]
pub struct Warm {
    values: Values,
    free: Vec<P>,
    keys: Vec<&'static str>,
    /// The weights (channel key, noise) to keep; `None`: the fit sets its own.
    pub sigma: Option<Vec<(&'static str, f64)>>,
    /// Most Jacobians of the one pass with given weights.
    pub max_iter: usize,
}

impl Warm {
    /// This start with the weights `sigma` (channel key, noise) kept and at most `max_iter`
    /// Jacobians.
    pub fn with_weights(&self, sigma: Vec<(&'static str, f64)>, max_iter: usize) -> Warm {
        Warm {
            sigma: Some(sigma),
            max_iter,
            ..self.clone()
        }
    }

    /// Sets `base`'s values of the parameters this start had free (channels matched by key).
    fn overlay(&self, base: &mut Values, channels: &[Prepared]) {
        let chan = |c: usize| {
            let key = self.keys.get(c)?;
            channels.iter().position(|ch| ch.key == *key)
        };
        for p in &self.free {
            match *p {
                P::Dead => base.dead = self.values.dead,
                P::TauUp => base.tau_up = self.values.tau_up,
                P::TauDown => base.tau_down = self.values.tau_down.or(base.tau_down),
                P::Gamma => base.gamma = self.values.gamma,
                P::Zero => base.zero = self.values.zero,
                P::MapExp => base.map_exp = self.values.map_exp,
                P::Exp => base.exp = self.values.exp,
                P::Delay(c) => {
                    if let Some(to) = chan(c).filter(|&t| t < base.delay.len()) {
                        base.delay[to] = self.values.delay[c];
                    }
                }
                P::Lag(c) => {
                    if let Some(to) = chan(c).filter(|&t| t < base.lag.len()) {
                        base.lag[to] = self.values.lag[c];
                    }
                }
                P::Limit => base.limit = base.limit.and(self.values.limit),
                P::Freq => base.freq = base.freq.and(self.values.freq),
                P::ModeFn | P::ModeZeta => base.mode = base.mode.and(self.values.mode),
                P::VoltExp => base.volt_exp = self.values.volt_exp,
                P::ExpShift(c) => {
                    if let Some(to) = chan(c).filter(|&t| t < base.exp_shift.len()) {
                        base.exp_shift[to] = self.values.exp_shift[c];
                    }
                }
            }
        }
    }
}

/// A fit of a [`Structure`] ([`fit_structured`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StructuredFit {
    /// The fitted stand (figures the structure holds fixed are reported at their fixed value
    /// with no uncertainty).
    pub fit: StandFit,
    /// Its parameters as a start for another fit of the record.
    pub warm: Warm,
    /// Per channel (key): the model on every row of the record (NaN outside the rows fitted,
    /// [`MAX_ROWS`]), not held over the refresh interval (compared at the readings).
    pub prediction: Vec<(&'static str, Vec<f64>)>,
    /// The command's clip level ([`Structure::command_limit`]).
    pub command_limit: Option<f64>,
    /// The sinusoid's frequency, Hz ([`Structure::sinusoid_hz`]).
    pub sinusoid_hz: Option<f64>,
    /// The resonance's frequency, Hz, and damping ratio ([`Structure::mode`]).
    pub mode: Option<(f64, f64)>,
    /// The speed map's voltage exponent `b` ([`Structure::voltage_exponent`]; `None`: 1).
    pub voltage_exponent: Option<f64>,
}

impl WithWindow for StructuredFit {
    fn set_window(&mut self, start: usize, end: usize, dt_s: f64, len: usize) {
        self.fit.set_window(start, end, dt_s, len);
        for (_, p) in self.prediction.iter_mut() {
            let mut full = vec![f64::NAN; len];
            for (k, v) in p.iter().enumerate() {
                if start + k < len {
                    full[start + k] = *v;
                }
            }
            *p = full;
        }
    }
}

/// Fits the parts of the stand `st` frees to `input` (as [`fit`] does the whole model),
/// from `warm` when given.
pub fn fit_structured(
    input: &FitInput<'_>,
    st: &Structure,
    warm: Option<&Warm>,
) -> Result<StructuredFit, StandModelError> {
    windowed(input, |within| {
        let (fit, problem, z) = fit_rows(within, st, warm, None)?;
        let v = problem.values(&z);
        let prediction = problem.predict(&v);
        Ok(StructuredFit {
            fit,
            warm: Warm {
                values: v.clone(),
                free: problem.layout.clone(),
                keys: problem.channels.iter().map(|c| c.key).collect(),
                sigma: Some(problem.channels.iter().map(|c| (c.key, c.sigma)).collect()),
                max_iter: 20,
            },
            prediction,
            command_limit: v.limit,
            sinusoid_hz: v.freq,
            mode: v.mode,
            voltage_exponent: problem.layout.contains(&P::VoltExp).then_some(v.volt_exp),
        })
    })
}

impl Problem {
    /// Per channel, the model at every row (the amplitudes solved at the readings).
    fn predict(&self, v: &Values) -> Vec<(&'static str, Vec<f64>)> {
        let Some(design) = self.design(v) else {
            return Vec::new();
        };
        let lin = self.solve(&design);
        let mut all = Problem {
            dt: self.dt,
            u: self.u.clone(),
            voltage: self.voltage.clone(),
            v_ref: self.v_ref,
            u_ref: self.u_ref,
            t_span: self.t_span,
            channels: self.channels.clone(),
            shows: self.shows,
            layout: Vec::new(),
            bounds: Vec::new(),
            base: v.clone(),
            creep: self.creep,
            origin: self.origin.clone(),
        };
        let len = self.u.len();
        for ch in all.channels.iter_mut() {
            ch.rows = (0..len).collect();
        }
        let Some(full) = all.design(v) else {
            return Vec::new();
        };
        full.iter()
            .zip(&self.channels)
            .zip(&lin)
            .map(|((cols, ch), beta)| {
                let y = (0..len)
                    .map(|i| cols.iter().zip(beta).map(|(c, b)| c[i] * b).sum())
                    .collect();
                (ch.key, y)
            })
            .collect()
    }
}

/// `x` through a resonance of unit gain at rest, `ωm² / (s² + 2ζm ωm s + ωm²)`, exactly
/// discretised with `x` held over each row ([`crate::discretise::discretise_second_order`]),
/// from rest at `x_0`.
pub fn resonance(x: &[f64], dt_s: f64, fn_hz: f64, zeta: f64) -> Vec<f64> {
    let (a, b) = crate::discretise::discretise_second_order(fn_hz, zeta, 1.0, dt_s);
    let Some(&first) = x.first() else {
        return Vec::new();
    };
    let mut s = nalgebra::Vector2::new(first, 0.0);
    x.iter()
        .map(|&u| {
            let out = s[0];
            s = a * s + b * u;
            out
        })
        .collect()
}

/// `AᵀA` of the columns `cols` with a ridge of 1e-12 times its largest diagonal entry on the
/// diagonal: a column of zeros (a speed never above the dead band) keeps it positive definite.
/// The amplitudes' least squares (`Problem::solve`) and their projection's derivative
/// (`fit/jacobian.rs`) factor the same matrix.
pub(super) fn ridged_gram(cols: &[Vec<f64>]) -> DMatrix<f64> {
    let m = cols.len();
    let mut g = DMatrix::<f64>::zeros(m, m);
    for i in 0..m {
        for j in i..m {
            let v: f64 = cols[i].iter().zip(&cols[j]).map(|(a, b)| a * b).sum();
            g[(i, j)] = v;
            g[(j, i)] = v;
        }
    }
    let scale = (0..m).map(|i| g[(i, i)]).fold(0.0, f64::max).max(1e-300);
    for i in 0..m {
        g[(i, i)] += 1e-12 * scale;
    }
    g
}
