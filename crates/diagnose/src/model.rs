//! The parametric model that `diagnose` fits: the 2nd-order linear core, extended by the terms
//! of the effects found, simulated from the input alone (an output-error model: no measured
//! output is fed back, so the simulation on the validation part is a true prediction).
//!
//! ```text
//!   v_k  = u_k, then the input terms in place order    e.g. v_k = u_{k−d} (dead_time),
//!                                                      min(v_k, L), u_r (v_k/u_r)^p, ...
//!   x_{k+1} = A x_k + B K v_k,  T_k = x_k[0]           2nd-order core, exact ZOH of
//!                                                      T'' + 2ζωn T' + ωn² T = ωn² K v
//!                                                      (a Core term: the nonlinear law of
//!                                                      propid_numerics::nonlinear_core)
//!   s_k = T_k, then the series terms                   e.g. an extra mode (4th order)
//!   ŷ_k = c + s_k, then the output terms               e.g. drift r t_k, a sinusoid, a clip
//! ```
//!
//! With an input lead `α` ([`Core::lead`], [`super::lead`]) the core's step is
//! `x_{k+1} = A_α (A_{1−α} x_k + B_{1−α} K v_k) + B_α K v_{k+1}`: `v_k` acts from `α·dt`
//! before its row.
//!
//! Each effect's term and its formula are in its file under [`super::effects`]; where it acts
//! is its [`Place`]. The states start in steady state for the first input sample. The core is
//! discretised by [`propid_numerics::discretise::discretise_second_order`], the function the
//! simulated plant uses.

use nalgebra::Vector2;
use propid_numerics::discretise::discretise_second_order;
use propid_numerics::nonlinear_core::{CoreLaw, NonlinearCore};

use super::signals::{Core, Signals};
use super::term::{Place, Scale, Term};
use propid_numerics::EffectName;

/// The core's parameters the fit adjusts: `fn`, `ζ` (in logarithm), `K`, `c`.
fn core_free(core: &Core) -> [(f64, Scale); 4] {
    [
        (core.fn_hz, Scale::Log),
        (core.zeta, Scale::Log),
        (core.gain, Scale::Linear),
        (core.offset, Scale::Linear),
    ]
}

/// The index of the core's gain `K` in [`Model::free`].
pub const GAIN_INDEX: usize = 2;
/// The index of the core's offset `c` in [`Model::free`].
pub const OFFSET_INDEX: usize = 3;

/// A model: the core and the terms of the effects it includes (kept in registry order, the
/// order of the free parameters and of the linear regressors).
#[derive(Debug, Clone, Default)]
pub struct Model {
    /// The 2nd-order core and offset.
    pub core: Core,
    terms: Vec<Box<dyn Term>>,
}

impl Model {
    /// The baseline model with core `core`.
    pub fn new(core: Core) -> Model {
        Model {
            core,
            terms: Vec::new(),
        }
    }

    /// This model with `term` added (replacing a term of the same effect).
    pub fn with(&self, term: impl Term + 'static) -> Model {
        self.with_boxed(Box::new(term))
    }

    /// This model with the boxed `term` added (replacing a term of the same effect).
    pub fn with_boxed(&self, term: Box<dyn Term>) -> Model {
        let mut m = self.clone();
        m.terms.retain(|t| t.name() != term.name());
        let at = term.name();
        let i = m.terms.partition_point(|t| t.name() <= at);
        m.terms.insert(i, term);
        m
    }

    /// This model with core `core`.
    pub fn with_core(&self, core: Core) -> Model {
        Model {
            core,
            terms: self.terms.clone(),
        }
    }

    /// The terms, in registry order.
    pub fn terms(&self) -> impl Iterator<Item = &dyn Term> {
        self.terms.iter().map(|t| t.as_ref())
    }

    /// The terms, mutable, in registry order.
    pub fn terms_mut(&mut self) -> impl Iterator<Item = &mut Box<dyn Term>> {
        self.terms.iter_mut()
    }

    /// Samples by which the model's terms delay the throttle (its dead time; 0 without one).
    pub fn input_delay(&self) -> usize {
        self.terms().map(|t| t.input_delay()).max().unwrap_or(0)
    }

    /// This model with each share of its dead time on the output's side
    /// ([`Term::voltage_delay_shares`]: from none to all of it, ascending), paired with the
    /// share; empty without a dead time.
    pub fn with_each_voltage_delay(&self) -> Vec<(usize, Model)> {
        let Some(delayed) = self.terms().find(|t| !t.voltage_delay_shares().is_empty()) else {
            return Vec::new();
        };
        delayed
            .voltage_delay_shares()
            .into_iter()
            .filter_map(|s| {
                let t = self.terms().find_map(|t| t.with_voltage_delay(s))?;
                Some((s, self.with_boxed(t)))
            })
            .collect()
    }

    /// The term of effect `name`, if the model has it.
    pub fn term(&self, name: EffectName) -> Option<&dyn Term> {
        self.terms().find(|t| t.name() == name)
    }

    /// The terms at `place`, in registry order.
    fn at(&self, place: Place) -> impl Iterator<Item = &dyn Term> {
        self.terms().filter(move |t| t.place() == place)
    }

    /// The free parameters: the core's, then each term's in registry order.
    pub fn free(&self) -> Vec<(f64, Scale)> {
        let mut f = core_free(&self.core).to_vec();
        for t in self.terms() {
            f.extend(t.free());
        }
        f
    }

    /// Sets the free parameters (natural values, in the order of [`Model::free`]).
    pub fn set_free(&mut self, values: &[f64]) {
        self.core.fn_hz = values[0];
        self.core.zeta = values[1];
        self.core.gain = values[2];
        self.core.offset = values[3];
        let mut i = 4;
        for t in self.terms.iter_mut() {
            let k = t.free().len();
            t.set_free(&values[i..i + k]);
            i += k;
        }
    }

    /// True when the simulated output is `ŷ = K g + c + a` with `g` and `a` independent of the
    /// core's gain `K` and offset `c`: every term before the core (the gain scales the shaped
    /// input), in series after it (linear filters) or added to the output ([`Place`]'s
    /// contract), none changing the core's law or limiting the output. Then `∂ŷ/∂c = 1` and
    /// `∂ŷ/∂K = (ŷ − c − a)/K` ([`crate::fit`]'s Jacobian).
    pub fn affine_in_gain_and_offset(&self) -> bool {
        self.terms().all(|t| {
            matches!(
                t.place(),
                Place::InputShift
                    | Place::InputLimit
                    | Place::InputMap
                    | Place::InputScale
                    | Place::Series
                    | Place::OutputAdd
            )
        })
    }

    /// The part `a` added to the output by the terms at [`Place::OutputAdd`] over the first
    /// `n` samples (zero without them).
    pub fn output_added(&self, sig: &Signals, n: usize, out: &mut Vec<f64>) {
        out.clear();
        out.resize(n, 0.0);
        for t in self.at(Place::OutputAdd) {
            t.shape_output(out, sig);
        }
    }

    /// True when a free parameter is NaN.
    pub fn has_nan(&self) -> bool {
        self.free().iter().any(|(v, _)| v.is_nan())
    }
}

/// Steps per sample of a core with a nonlinear law (exponential midpoint rule in each).
pub const CORE_SUBSTEPS: usize = 2;

/// Largest frequency a fitted mode may take, Hz (just below Nyquist).
pub fn max_freq_hz(dt_s: f64) -> f64 {
    0.49 / dt_s
}

/// Simulates the model on the whole record into `out` (same length as `sig.u`; a shorter `out`
/// gets the first `out.len()` samples of the simulation on the whole record: every term is
/// causal, an output sample depending on the input up to it, and the fits on a head of the
/// record simulate only that head).
pub fn simulate(m: &Model, sig: &Signals, out: &mut [f64]) {
    simulate_places(m, sig, out, true);
}

/// Simulates the model; with `limits` false the output limits ([`Place::OutputLimit`]) are
/// left out, so that the output is affine in the core's gain, its offset and the linear terms.
pub fn simulate_places(m: &Model, sig: &Signals, out: &mut [f64], limits: bool) {
    simulate_staged(m, sig, out, limits, Start::Input, None);
}

/// Where a simulation starts ([`simulate_staged`]): from the input, or from a stage kept by an
/// earlier simulation of a model that differs from this one only after that stage.
#[derive(Debug, Clone, Copy)]
pub enum Start<'a> {
    /// From the input (every stage).
    Input,
    /// From the core's input `K v` ([`Stages::core_in`]).
    Core(&'a [f64]),
    /// From the core's output ([`Stages::core_out`]): the series terms on.
    Series(&'a [f64]),
}

/// The intermediate signals of a simulation from the input, kept so that a model differing
/// only in later parameters is simulated from them ([`Start`], [`Model::start_of_free`]):
/// the same operations on the same values, so the same output, bit for bit.
#[derive(Debug, Clone, Default)]
pub struct Stages {
    /// The core's input: the shaped input times the gain `K`.
    pub core_in: Vec<f64>,
    /// The core's output, before the series terms.
    pub core_out: Vec<f64>,
}

impl Model {
    /// The first stage free parameter `j` ([`Model::free`]) acts in: the core's `fn` and `ζ`
    /// and a [`Place::Core`] term's parameters in the core, the offset and the parameters of
    /// the terms after the core in the series stage, the rest (the gain, the input terms) in
    /// the input's. The stages are given as a [`Start`] built from `stages`.
    pub fn start_of_free<'a>(&self, j: usize, stages: &'a Stages) -> Start<'a> {
        let core = Start::Core(&stages.core_in);
        let series = Start::Series(&stages.core_out);
        match j {
            0 | 1 => return core,
            GAIN_INDEX => return Start::Input,
            OFFSET_INDEX => return series,
            _ => {}
        }
        let mut i = 4;
        for t in self.terms() {
            let k = t.free().len();
            if j < i + k {
                return match t.place() {
                    Place::Core => core,
                    Place::Series | Place::OutputAdd | Place::OutputLimit => series,
                    _ => Start::Input,
                };
            }
            i += k;
        }
        Start::Input
    }
}

/// [`simulate_places`] from `start` (the stages it names must come from a simulation of a
/// model equal to `m` before them, on the same signals), keeping the stages it computes in
/// `keep` (a simulation from the input keeps both).
pub fn simulate_staged(
    m: &Model,
    sig: &Signals,
    out: &mut [f64],
    limits: bool,
    start: Start,
    keep: Option<&mut Stages>,
) {
    let n = sig.u.len().min(out.len());
    if n == 0 {
        return;
    }
    let out = &mut out[..n];
    let lag = m.terms().map(|t| t.voltage_delay()).max().unwrap_or(0);
    let late: Option<Vec<f64>> = sig.voltage.filter(|_| lag > 0).map(|volt| {
        (0..volt.len())
            .map(|k| volt[k.saturating_sub(lag)])
            .collect()
    });
    let input_sig = Signals {
        voltage: late.as_deref().or(sig.voltage),
        ..*sig
    };
    match start {
        Start::Input => {
            // The shaped input is built in `out` and the core's output written over it, each
            // sample read before it is overwritten.
            out.copy_from_slice(&sig.u[..n]);
            for place in Place::ALL.into_iter().filter(|p| p.is_input()) {
                for t in m.at(place) {
                    t.shape_input(out, &input_sig);
                }
            }
            for x in out.iter_mut() {
                *x *= m.core.gain;
            }
            if let Some(k) = keep {
                k.core_in.clear();
                k.core_in.extend_from_slice(out);
                run_core(m, sig, out);
                k.core_out.clear();
                k.core_out.extend_from_slice(out);
            } else {
                run_core(m, sig, out);
            }
        }
        Start::Core(core_in) => {
            out.copy_from_slice(&core_in[..n]);
            run_core(m, sig, out);
        }
        Start::Series(core_out) => out.copy_from_slice(&core_out[..n]),
    }
    for t in m.at(Place::Series) {
        t.filter(out, sig.dt_s);
    }
    for t in m.terms() {
        t.scale_output(out, &input_sig);
    }
    for o in out.iter_mut() {
        *o += m.core.offset;
    }
    for t in m.at(Place::OutputAdd) {
        t.shape_output(out, sig);
    }
    if limits {
        for t in m.at(Place::OutputLimit) {
            t.shape_output(out, sig);
        }
    }
}

/// The core (with its [`Place::Core`] terms' law and the input's lead) run over its input `v`
/// (`K` times the shaped input), its output written over it.
fn run_core(m: &Model, sig: &Signals, v: &mut [f64]) {
    let n = v.len();
    let fmax = max_freq_hz(sig.dt_s);
    let mut law = CoreLaw::default();
    for t in m.at(Place::Core) {
        t.core_law(&mut law);
    }
    // With a lead α, the sample interval [t_k, t_k+1) holds v_k for (1 − α)·dt, then v_k+1.
    let lead = m.core.lead.clamp(0.0, 1.0);
    let (fn_hz, zeta) = (
        m.core.fn_hz.clamp(1e-6, fmax),
        m.core.zeta.clamp(1e-4, 50.0),
    );
    if law.is_linear() && lead == 0.0 {
        let (a, b) = discretise_second_order(fn_hz, zeta, 1.0, sig.dt_s);
        let mut x = Vector2::new(v[0], 0.0);
        for o in v.iter_mut() {
            let vk = *o;
            *o = x[0];
            x = a * x + b * vk;
        }
    } else if law.is_linear() {
        let (a1, b1) = discretise_second_order(fn_hz, zeta, 1.0, (1.0 - lead) * sig.dt_s);
        let (a2, b2) = discretise_second_order(fn_hz, zeta, 1.0, lead * sig.dt_s);
        let mut x = Vector2::new(v[0], 0.0);
        for k in 0..n {
            let (vk, vnext) = (v[k], v[(k + 1).min(n - 1)]);
            v[k] = x[0];
            x = a2 * (a1 * x + b1 * vk) + b2 * vnext;
        }
    } else {
        // A part of no length has no core (a zero step would not discretise).
        let core = |share: f64| {
            (share > 0.0)
                .then(|| NonlinearCore::new(fn_hz, zeta, 1.0, share * sig.dt_s, law, CORE_SUBSTEPS))
        };
        let (first, second) = (core(1.0 - lead), core(lead));
        let mut x = Vector2::new(0.0, 0.0);
        if let Some(c) = first.as_ref().or(second.as_ref()) {
            x = c.settle(v[0]);
        }
        for k in 0..n {
            let (vk, vnext) = (v[k], v[(k + 1).min(n - 1)]);
            v[k] = x[0];
            if let Some(c) = &first {
                x = c.step(x, vk);
            }
            if let Some(c) = &second {
                x = c.step(x, vnext);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::saturation::{Clipped, SaturationParams};
    use crate::effects::static_nonlinearity::StaticNonlinearityParams;
    use crate::effects::supply_sag::SupplySagParams;
    use propid_sim::plant::{Plant, PlantConfig};

    fn signals<'a>(u: &'a [f64], y: &'a [f64]) -> Signals<'a> {
        Signals {
            dt_s: 1e-3,
            u,
            y,
            voltage: None,
            u_ref: 0.5,
            v_ref: 0.0,
        }
    }

    #[test]
    fn a_lead_of_a_whole_sample_is_the_input_one_sample_early_and_keeps_the_gain() {
        let u: Vec<f64> = (0..200)
            .map(|k| if (k / 40) % 2 == 1 { 0.6 } else { 0.2 })
            .collect();
        let y = vec![0.0; u.len()];
        let sig = Signals {
            dt_s: 0.02,
            ..signals(&u, &y)
        };
        let core = |lead| Core {
            fn_hz: 3.0,
            zeta: 0.8,
            gain: 2.0,
            lead,
            ..Core::default()
        };
        let run = |lead, u: &[f64]| {
            let mut out = vec![0.0; u.len()];
            simulate(&Model::new(core(lead)), &Signals { u, ..sig }, &mut out);
            out
        };
        let plain = run(0.0, &u);
        // Lead 1: the plain hold of the input advanced by one sample.
        let early: Vec<f64> = (0..u.len()).map(|k| u[(k + 1).min(u.len() - 1)]).collect();
        let whole = run(1.0, &u);
        let advanced = run(0.0, &early);
        for k in 0..u.len() - 1 {
            assert!((whole[k] - advanced[k]).abs() < 1e-12, "{k}");
        }
        // A half sample lies between, and every lead settles at the same gain.
        let half = run(0.5, &u);
        for k in 41..60 {
            let (lo, hi) = (plain[k].min(whole[k]), plain[k].max(whole[k]));
            assert!(half[k] >= lo - 1e-12 && half[k] <= hi + 1e-12, "{k}");
        }
        for out in [&plain, &half, &whole] {
            assert!((out[79] - 1.2).abs() < 1e-3, "{}", out[79]);
        }
    }

    #[test]
    fn terms_act_in_place_order_whatever_order_they_were_added_in() {
        // Clip at 0.6 before the square law around 0.5: 0.5 (0.6/0.5)² = 0.72. The other way
        // round it would be min(0.5 (0.8/0.5)², 0.6) = 0.6.
        let u = vec![0.8; 50];
        let y = vec![0.0; 50];
        let clip = SaturationParams {
            level: 0.6,
            clipped: Clipped::Throttle,
        };
        let map = StaticNonlinearityParams { exponent: 2.0 };
        let core = Core {
            fn_hz: 5.0,
            gain: 1.0,
            ..Core::default()
        };
        for m in [
            Model::new(core).with(map).with(clip),
            Model::new(core).with(clip).with(map),
        ] {
            let mut out = vec![0.0; 50];
            simulate(&m, &signals(&u, &y), &mut out);
            assert!(out.iter().all(|v| (v - 0.72).abs() < 1e-12), "{out:?}");
        }
    }

    #[test]
    fn free_parameters_follow_the_registry_and_a_term_is_replaced_not_doubled() {
        let m = Model::default()
            .with(SupplySagParams::drive(0.1))
            .with(StaticNonlinearityParams { exponent: 2.0 })
            .with(SupplySagParams::drive(0.2));
        let names: Vec<EffectName> = m.terms().map(|t| t.name()).collect();
        assert_eq!(
            names,
            [EffectName::StaticNonlinearity, EffectName::SupplySag]
        );
        let values: Vec<f64> = m.free().iter().map(|f| f.0).collect();
        assert_eq!(values, [1.0, 0.7, 1.0, 0.0, 2.0, 0.2]);
        let mut m2 = m.clone();
        m2.set_free(&[2.0, 0.5, 3.0, 0.1, 1.5, -0.05]);
        assert_eq!(m2.core.gain, 3.0);
        assert_eq!(m2.free()[4].0, 1.5);
        assert_eq!(m2.free()[5].0, -0.05);
    }

    #[test]
    fn the_voltage_is_as_late_as_the_output_side_of_the_delay() {
        use crate::effects::dead_time::DeadTimeParams;
        // Throttle 1 throughout, a voltage step at sample 10, a static core (fast, gain 1):
        // the sag scales the input by 1 + g (V − V_r).
        let u = vec![1.0; 30];
        let y = vec![0.0; 30];
        let volt: Vec<f64> = (0..30).map(|k| if k < 10 { 16.0 } else { 15.0 }).collect();
        let sig = Signals {
            voltage: Some(&volt),
            v_ref: 16.0,
            ..signals(&u, &y)
        };
        let core = Core {
            fn_hz: 400.0,
            zeta: 1.0,
            gain: 1.0,
            offset: 0.0,
            lead: 0.0,
        };
        let sag = SupplySagParams::drive(0.1);
        let first_low = |sensor: usize| {
            let m = Model::new(core).with(sag).with(DeadTimeParams {
                delay_samples: 4,
                sensor_samples: sensor,
            });
            let mut out = vec![0.0; 30];
            simulate(&m, &sig, &mut out);
            out.iter().position(|v| *v < 0.95).unwrap()
        };
        // All on the throttle's side: the voltage acts at its own time; all on the output's
        // side: 4 samples later.
        assert_eq!(first_low(4) - first_low(0), 4);
        assert_eq!(first_low(1) - first_low(0), 1);
    }

    #[test]
    fn a_simulation_from_a_kept_stage_is_the_whole_simulation_bit_for_bit() {
        use crate::effects::dead_time::DeadTimeParams;
        use crate::effects::extra_mode::ExtraModeParams;
        use crate::effects::static_nonlinearity::StaticNonlinearityParams;
        use crate::effects::stiffness_nonlinearity::StiffnessNonlinearityParams;
        let u: Vec<f64> = (0..400)
            .map(|k| 0.3 + 0.1 * ((k / 50) % 4) as f64)
            .collect();
        let y = vec![0.0; u.len()];
        let sig = signals(&u, &y);
        let core = Core {
            fn_hz: 30.0,
            zeta: 0.5,
            gain: 2.0,
            offset: 0.1,
            lead: 0.3,
        };
        let m = Model::new(core)
            .with(DeadTimeParams::throttle(4))
            .with(StaticNonlinearityParams { exponent: 1.6 })
            .with(StiffnessNonlinearityParams {
                k3_per_k1: 0.01,
                scale_sq: 1.0,
            })
            .with(ExtraModeParams {
                fn_hz: 80.0,
                zeta: 0.2,
                gain: 0.3,
            });
        let mut stages = Stages::default();
        let mut out = vec![0.0; u.len()];
        simulate_staged(&m, &sig, &mut out, true, Start::Input, Some(&mut stages));
        let free: Vec<f64> = m.free().iter().map(|f| f.0).collect();
        let mut starts = Vec::new();
        for j in 0..free.len() {
            let mut values = free.clone();
            values[j] *= 1.01;
            let mut mj = m.clone();
            mj.set_free(&values);
            let (mut whole, mut staged) = (vec![0.0; u.len()], vec![0.0; u.len()]);
            simulate(&mj, &sig, &mut whole);
            let start = m.start_of_free(j, &stages);
            starts.push(match start {
                Start::Input => 'i',
                Start::Core(_) => 'c',
                Start::Series(_) => 's',
            });
            simulate_staged(&mj, &sig, &mut staged, true, start, None);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&whole), bits(&staged), "parameter {j}");
        }
        // fn, ζ, K, c, then in registry order the exponent (input), the cubic spring (core),
        // the mode's fn, ζ and share (series).
        let got: String = starts.iter().collect();
        assert_eq!(&got[..4], "ccis");
        let count = |c: char| got.chars().filter(|&x| x == c).count();
        assert_eq!((count('i'), count('c'), count('s')), (2, 3, 4), "{got}");
    }

    #[test]
    fn a_sensor_clip_is_left_out_when_limits_are_off() {
        let u = vec![1.0; 20];
        let y = vec![0.0; 20];
        let m = Model::new(Core {
            gain: 2.0,
            ..Core::default()
        })
        .with(SaturationParams {
            level: 1.5,
            clipped: Clipped::Sensor { samples: 20 },
        });
        let (mut with, mut without) = (vec![0.0; 20], vec![0.0; 20]);
        simulate_places(&m, &signals(&u, &y), &mut with, true);
        simulate_places(&m, &signals(&u, &y), &mut without, false);
        assert!(with.iter().all(|&v| v == 1.5));
        assert!(without.iter().all(|&v| (v - 2.0).abs() < 1e-12));
    }

    #[test]
    fn core_terms_reproduce_the_plants_nonlinear_core() {
        use crate::effects::asymmetric_dynamics::AsymmetricDynamicsParams;
        use crate::effects::stiffness_nonlinearity::StiffnessNonlinearityParams;
        use propid_sim::effects::{AsymmetricDynamics, EffectsConfig, StiffnessNonlinearity};
        let effects = EffectsConfig {
            asymmetric_dynamics: Some(AsymmetricDynamics {
                up_scale: 0.7,
                down_scale: 1.4,
            }),
            stiffness_nonlinearity: Some(StiffnessNonlinearity { k3_per_k1: 0.004 }),
            ..EffectsConfig::default()
        };
        let cfg = PlantConfig {
            noise_rms_n: 0.0,
            quantum_n: 0.0,
            effects,
            ..PlantConfig::default()
        };
        let mut plant = Plant::new(&cfg, 2e-3, 1).unwrap();
        let u: Vec<f64> = (0..600)
            .map(|k| if (k / 50) % 2 == 0 { 0.4 } else { 0.65 })
            .collect();
        plant.settle(u[0]);
        let y: Vec<f64> = u.iter().map(|&x| plant.step(x).thrust_n).collect();
        // The plant's time scales 0.7 and 1.4 are the model's 1/√2 and √2 (down/up = 2)
        // around a core at fn / √(0.7 · 1.4).
        let m = Model::new(Core {
            fn_hz: cfg.fn_hz / (0.7f64 * 1.4).sqrt(),
            zeta: cfg.zeta,
            gain: cfg.gain_n_per_throttle,
            offset: 0.0,
            lead: 0.0,
        })
        .with(AsymmetricDynamicsParams {
            log_ratio: 2f64.ln(),
        })
        .with(StiffnessNonlinearityParams {
            k3_per_k1: 0.004,
            scale_sq: 1.0,
        });
        let sig = Signals {
            dt_s: 2e-3,
            u: &u,
            y: &y,
            voltage: None,
            u_ref: 0.5,
            v_ref: 0.0,
        };
        let mut out = vec![0.0; u.len()];
        simulate(&m, &sig, &mut out);
        let span =
            y.iter().fold(0.0f64, |a, &b| a.max(b)) - y.iter().fold(9e9f64, |a, &b| a.min(b));
        for (k, (a, b)) in out.iter().zip(&y).enumerate() {
            // 2 substeps against the plant's 8: the same law; the direction switches on a coarser grid.
            assert!((a - b).abs() < 1e-2 * span, "k {k}: {a} vs {b}");
        }
        // Without the terms the core is the linear one: the asymmetry and the spring show.
        let mut lin = vec![0.0; u.len()];
        simulate(&Model::new(m.core), &sig, &mut lin);
        let dev = lin
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(dev > 0.05 * span, "{dev}");
    }

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
        let m = Model::new(Core {
            fn_hz: cfg.fn_hz,
            zeta: cfg.zeta,
            gain: cfg.gain_n_per_throttle,
            offset: 0.0,
            lead: 0.0,
        });
        let sig = Signals {
            dt_s: 2e-3,
            u: &u,
            y: &y,
            voltage: None,
            u_ref: 0.5,
            v_ref: 0.0,
        };
        let mut out = vec![0.0; u.len()];
        simulate(&m, &sig, &mut out);
        for (a, b) in out.iter().zip(&y) {
            assert!((a - b).abs() < 1e-9);
        }
    }
}
