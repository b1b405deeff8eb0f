//! Diagnose on a motor stand: the baseline is the stand model
//! ([`propid_numerics::stand_model`]) fitted jointly on every channel the record has, its
//! figures measured on held-out blocks; the stand catalogue ([`catalogue`]) frees one part of
//! the model at a time; per channel, where the simulation departs from the measurement
//! ([`departures`]).
//!
//! 1. **Which baseline** ([`choose`]): the stand's when the input is a motor command and the
//!    record has the rotor's speed (rpm) and a thrust, torque or current channel beside it,
//!    among which the diagnosed output is (and its samples are shorter than the response),
//!    unless the generic search's final model predicts the output's held-out folds better
//!    beyond their scatter (the paired test of [`HeldOutGain`], [`crate::diagnose_with`]); the
//!    generic 2nd-order one otherwise.
//! 2. **The stand baseline** ([`Structure::default`]): the ESC's dead band, one rotor time
//!    constant, speed linear in the command above the dead band, loads ∝ speed², every channel
//!    on the reference's time (no sensor delay or lag), the supply constant. Fitted on the
//!    estimation part (every sample under blocked cross-validation, the head otherwise), each
//!    channel weighted by its own noise; the weights of this fit are kept for every later fit
//!    so that their weighted residuals compare.
//! 3. **Held-out figure**: per channel, each fold predicted by the model refitted without it
//!    (its readings masked; Levenberg–Marquardt from the fit on all samples, at most
//!    [`crate::folds::FOLD_ITERS`] Jacobians), `100 (1 − ‖y_F − ŷ_F‖ / ‖y_F − ȳ‖)` with `ȳ`
//!    the channel's mean, the mean over the folds; the record's figure is the mean over the
//!    channels (a sensor lag on the thrust moves the thrust's figure alone).
//! 4. **Forward selection** as the generic search's: every candidate is fitted on top of the
//!    current model (all parameters together, from its values); one with score
//!    `S = n ln(SSE_M / SSE_{M+e})` (weighted residuals, `n` readings) at least
//!    [`thresholds::SCORE_THRESHOLD`] and an RMS drop of [`thresholds::MIN_RMS_DROP`] is
//!    cross-validated; it passes when the record's held-out figure rises by more than
//!    [`thresholds::MIN_CV_GAIN_PP`] (the acceptance gate over the folds) and the diagnosed
//!    output's does not fall beyond its folds' scatter (the paired test of [`HeldOutGain`]);
//!    of those, the one that predicts the output's held-out samples best is taken (the
//!    record's figure breaks ties): the baseline is chosen on the output (1.), and an effect
//!    that helps the other channels at the output's cost is no cause of what the output
//!    shows. At most [`thresholds::STAND_MAX_EFFECTS`].

pub mod catalogue;
pub mod departures;

use std::collections::BTreeMap;

use propid_numerics::segment::SegmentRules;
use propid_numerics::stand_model::fit::{
    fit_structured, Channel, FitInput, StandModelError, Structure, StructuredFit, Warm,
};
use propid_numerics::stand_model::report::{report, StandReport};
use propid_numerics::stand_model::Quantity;
use propid_numerics::EffectName;
use serde::Serialize;
use serde_json::{Map, Value};

use crate::finding::Finding;
use crate::folds::{fit_percent_about, Folds, Gate, HeldOutGain, Method, FOLD_ITERS};
use crate::rejected::Rejected;
use crate::spectrum::peaks;
use crate::thresholds;
use catalogue::Candidate;
pub use departures::Departures;

/// A record's stand channels for the stand baseline.
#[derive(Debug, Clone)]
pub struct StandInput<'a> {
    /// The channels (rpm, thrust, torque, current: any the record has).
    pub channels: Vec<Channel<'a>>,
    /// The key of the diagnosed output among them (`thrust`, ...); `None` when the output is
    /// none of them.
    pub output: Option<&'static str>,
}

/// Which baseline a record gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BaselineKind {
    /// The stand model.
    Stand,
    /// The generic 2nd-order output-error model.
    Generic,
}

/// The baseline chosen and why (`baseline.kind`, `baseline.why`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct BaselineChoice {
    /// Which.
    pub kind: BaselineKind,
    /// Why, in words.
    pub why: String,
}

impl BaselineChoice {
    /// The generic baseline, for `why`.
    pub fn generic(why: impl Into<String>) -> BaselineChoice {
        BaselineChoice {
            kind: BaselineKind::Generic,
            why: why.into(),
        }
    }
}

impl Default for BaselineChoice {
    fn default() -> Self {
        BaselineChoice::generic(
            "no rpm, thrust, torque or current channel came with the output: no stand to model",
        )
    }
}

/// Readings of a channel (finite, not interpolated).
fn readings(c: &Channel<'_>) -> usize {
    (0..c.y.len())
        .filter(|&k| c.y[k].is_finite() && !c.interpolated.get(k).copied().unwrap_or(false))
        .count()
}

/// The baseline the data call for (module doc, 1).
pub fn choose(
    input_is_a_command: bool,
    stand: Option<&StandInput<'_>>,
    rules: &SegmentRules,
) -> BaselineChoice {
    use propid_numerics::stand_model::fit::MIN_READINGS;
    if !input_is_a_command {
        return BaselineChoice::generic(
            "the input is a signal in its own units, not a motor command: no stand model",
        );
    }
    let Some(s) = stand else {
        return BaselineChoice::default();
    };
    let usable: Vec<&'static str> = s
        .channels
        .iter()
        .filter(|c| readings(c) >= MIN_READINGS)
        .map(|c| c.key)
        .collect();
    if usable.is_empty() {
        return BaselineChoice::generic(
            "the record has no rpm, thrust, torque or current channel: no stand to model",
        );
    }
    let Some(out) = s.output.filter(|o| usable.contains(o)) else {
        return BaselineChoice::generic(
            "the diagnosed output is none of the stand's rpm, thrust, torque or current \
             channels",
        );
    };
    // The stand model times the rotor on its speed and every other sensor against it: with
    // one channel, or none of them the speed, the rotor's lag and a sensor's cannot be told
    // apart and the model is a first-order Hammerstein the generic catalogue covers.
    let speed = s
        .channels
        .iter()
        .any(|c| c.quantity == Quantity::Speed && usable.contains(&c.key));
    if !speed || usable.len() < 2 {
        return BaselineChoice::generic(format!(
            "the record's stand channels ({}) lack the rotor's speed or a load beside it: the \
             stand model needs both to tell the rotor's lag from a sensor's",
            usable.join(", ")
        ));
    }
    if rules.samples_are_steady() {
        return BaselineChoice::generic(
            "a sample lasts longer than the stand's response takes to settle: no stand \
             dynamics to model",
        );
    }
    BaselineChoice {
        kind: BaselineKind::Stand,
        why: format!(
            "the input is a motor command and the record has the stand's {} channel(s): the \
             stand model (ESC, rotor, loads, supply, a sensor per channel) is the baseline, \
             fitted on all of them jointly and scored on {out}",
            usable.join(", ")
        ),
    }
}

/// The calibrated stand a diagnosis ends with (for a simulated stand's configuration): the
/// baseline's and the extended model's fits, the structure the extensions free, and the
/// effects named, in order.
#[derive(Debug, Clone)]
pub struct StandBaseline {
    /// Row period, s.
    pub dt_s: f64,
    /// The stand baseline fitted on the estimation part.
    pub baseline: StructuredFit,
    /// The model with every effect found (the baseline when none).
    pub extended: StructuredFit,
    /// The parts of the stand the extended model frees.
    pub structure: Structure,
    /// The effects named.
    pub effects: Vec<EffectName>,
    /// The folds its held-out figures were measured on ([`score_on_folds`]).
    pub folds: Folds,
}

/// One channel's figures (`stand.channels.<key>`).
#[derive(Debug, Clone, Serialize)]
pub struct ChannelScore {
    /// The stand baseline's held-out figure, percent.
    pub baseline_fit_percent: f64,
    /// The final model's held-out figure, percent.
    pub fit_percent: f64,
    /// Where the baseline's simulation departs from the channel.
    pub departures: Departures,
}

/// `"stand"` in the JSON of a diagnosis on a stand baseline.
#[derive(Debug, Clone, Serialize)]
pub struct StandDiagnosis {
    /// The channel the rotor is timed on (every other sensor is timed against it).
    pub reference_channel: &'static str,
    /// The diagnosed output's channel.
    pub output: &'static str,
    /// The stand baseline's held-out figure: the mean of the channels'.
    pub baseline_mean_fit_percent: f64,
    /// The final model's.
    pub mean_fit_percent: f64,
    /// The effects named, in order.
    pub effects: Vec<EffectName>,
    /// Per channel.
    pub channels: BTreeMap<&'static str, ChannelScore>,
    /// The final model's figures (the same fields as `identify`'s `"stand"`; a part the model
    /// does not free is shown at its fixed value without uncertainty).
    pub model: StandReport,
}

/// Held-out scores of one model.
#[derive(Debug, Clone, Default)]
pub struct Cv {
    /// Per channel key: each fold's figure.
    pub folds: BTreeMap<&'static str, Vec<f64>>,
    /// Per channel key: the mean of its folds' figures.
    pub channel: BTreeMap<&'static str, f64>,
    /// Per channel key: the held-out prediction (NaN outside the folds).
    pub prediction: BTreeMap<&'static str, Vec<f64>>,
    /// The record's figure: the mean over the channels.
    pub mean: f64,
}

impl Cv {
    /// Each fold's figure, the mean over the channels (the blocks of [`HeldOutGain`]).
    pub fn fold_means(&self) -> Vec<f64> {
        let k = self.folds.values().map(Vec::len).min().unwrap_or(0);
        (0..k)
            .map(|i| {
                let v: Vec<f64> = self.folds.values().map(|f| f[i]).collect();
                v.iter().sum::<f64>() / v.len().max(1) as f64
            })
            .collect()
    }
}

/// What the stand search gives the diagnosis.
#[derive(Debug, Clone)]
pub struct StandRun {
    /// The JSON's `stand`.
    pub report: StandDiagnosis,
    /// The findings, in order, with the final model's parameters.
    pub findings: Vec<Finding>,
    /// Candidates that fitted in-sample and were not taken.
    pub rejected: Vec<Rejected>,
    /// The baseline's held-out scores.
    pub base_cv: Cv,
    /// The final model's.
    pub cv: Cv,
    /// The calibrated stand.
    pub stand: StandBaseline,
}

/// The record as the search sees it.
struct Data<'a> {
    dt_s: f64,
    u: &'a [f64],
    voltage: Option<&'a [f64]>,
    channels: &'a [Channel<'a>],
    rules: SegmentRules,
    folds: &'a Folds,
    /// Per channel, its samples with every non-reading NaN (interpolated rows too).
    read: Vec<Vec<f64>>,
}

impl<'a> Data<'a> {
    /// The record with each channel's samples outside `keep` masked.
    fn masked(&self, keep: impl Fn(usize) -> bool) -> Vec<Vec<f64>> {
        self.channels
            .iter()
            .map(|c| {
                c.y.iter()
                    .enumerate()
                    .map(|(k, &v)| if keep(k) { v } else { f64::NAN })
                    .collect()
            })
            .collect()
    }

    fn fit(
        &self,
        ys: &[Vec<f64>],
        st: &Structure,
        warm: Option<&Warm>,
    ) -> Result<StructuredFit, StandModelError> {
        let channels: Vec<Channel<'_>> = self
            .channels
            .iter()
            .zip(ys)
            .map(|(c, y)| Channel { y, ..*c })
            .collect();
        let input = FitInput {
            dt_s: self.dt_s,
            command: self.u,
            voltage: self.voltage,
            channels: &channels,
            rules: self.rules,
        };
        fit_structured(&input, st, warm)
    }

    /// The estimation part's samples (masked outside `folds.estimation`).
    fn estimation(&self) -> Vec<Vec<f64>> {
        let e = self.folds.estimation.clone();
        self.masked(|k| e.contains(&k))
    }

    /// Weighted SSE of `f` over the estimation readings and their count.
    fn sse(&self, f: &StructuredFit, sigma: &[(&'static str, f64)]) -> (f64, usize) {
        let (mut s, mut n) = (0.0, 0usize);
        for (c, ch) in self.channels.iter().enumerate() {
            let Some(p) = pred(f, ch.key) else { continue };
            let w = sigma
                .iter()
                .find(|(k, _)| *k == ch.key)
                .map_or(1.0, |x| x.1);
            for k in self.folds.estimation.clone() {
                let (y, yh) = (self.read[c][k], p.get(k).copied().unwrap_or(f64::NAN));
                if y.is_finite() && yh.is_finite() {
                    s += ((y - yh) / w).powi(2);
                    n += 1;
                }
            }
        }
        (s, n)
    }

    /// The held-out scores of the structure `st` fitted as `f` on the estimation part.
    fn cv(&self, st: &Structure, f: &StructuredFit, sigma: &[(&'static str, f64)]) -> Cv {
        let len = self.u.len();
        let mut cv = Cv::default();
        let mut preds: Vec<Vec<f64>> = vec![vec![f64::NAN; len]; self.channels.len()];
        for fold in &self.folds.folds {
            let refit;
            let model = match self.folds.method {
                Method::Holdout => f,
                Method::BlockedCv => {
                    let ys = self.masked(|k| !fold.contains(&k));
                    let warm = f.warm.with_weights(sigma.to_vec(), FOLD_ITERS);
                    refit = self.fit(&ys, st, Some(&warm)).ok();
                    refit.as_ref().unwrap_or(f)
                }
            };
            for (c, ch) in self.channels.iter().enumerate() {
                if let Some(p) = pred(model, ch.key) {
                    for k in fold.clone() {
                        preds[c][k] = p.get(k).copied().unwrap_or(f64::NAN);
                    }
                }
            }
        }
        let mut means = Vec::new();
        for (c, ch) in self.channels.iter().enumerate() {
            let Some(fits) = fold_fits(&self.read[c], &preds[c], self.folds) else {
                continue;
            };
            let m = fits.iter().sum::<f64>() / fits.len() as f64;
            means.push(m);
            cv.channel.insert(ch.key, m);
            cv.folds.insert(ch.key, fits);
            cv.prediction.insert(ch.key, preds[c].clone());
        }
        cv.mean = if means.is_empty() {
            f64::NEG_INFINITY
        } else {
            means.iter().sum::<f64>() / means.len() as f64
        };
        cv
    }
}

/// Each fold's figure of the prediction `pred` of a channel's readings `read` (NaN: no
/// reading): `100 (1 − ‖y_F − ŷ_F‖ / ‖y_F − ȳ‖)` with `ȳ` the channel's mean over the record
/// (over the tail under [`Method::Holdout`]); `None` when no fold has a reading.
fn fold_fits(read: &[f64], pred: &[f64], folds: &Folds) -> Option<Vec<f64>> {
    let mean_over = |r: std::ops::Range<usize>| {
        let (s, n) = r
            .filter(|&k| read[k].is_finite())
            .fold((0.0, 0usize), |(s, n), k| (s + read[k], n + 1));
        s / n.max(1) as f64
    };
    let ybar = match folds.method {
        Method::Holdout => mean_over(folds.folds[0].clone()),
        Method::BlockedCv => mean_over(0..read.len()),
    };
    let fits: Vec<f64> = folds
        .folds
        .iter()
        .map(|r| fit_percent_about(read, pred, r.start..r.end.min(read.len()), ybar))
        .filter(|x| x.2 > 0)
        .map(|x| x.0)
        .collect();
    (!fits.is_empty()).then_some(fits)
}

/// A simulation of a record's channels scored as the stand's held-out figure is (module doc,
/// 3): per channel, the mean over `folds` of each fold's fit percent about the channel's mean,
/// at its readings (finite, not interpolated). `sim`: channel key and the simulation at every
/// row. The same function of the same rows as `stand.channels.<key>.fit_percent`: a
/// simulation of the fitted stand scores the fit diagnose reports (`diagnose --sim-config`).
pub fn score_on_folds(
    channels: &[Channel<'_>],
    sim: &[(&str, Vec<f64>)],
    folds: &Folds,
) -> BTreeMap<&'static str, f64> {
    channels
        .iter()
        .filter_map(|c| {
            let (_, p) = sim.iter().find(|(k, _)| *k == c.key)?;
            let read: Vec<f64> = (0..c.y.len().min(p.len()))
                .map(|k| {
                    if c.interpolated.get(k).copied().unwrap_or(false) {
                        f64::NAN
                    } else {
                        c.y[k]
                    }
                })
                .collect();
            let fits = fold_fits(&read, p, folds)?;
            Some((c.key, fits.iter().sum::<f64>() / fits.len() as f64))
        })
        .collect()
}

/// How candidates that pass the test rank (module doc, 4): by the diagnosed output's held-out
/// figure, then the record's.
fn rank(cv: &Cv, output: &str) -> (f64, f64) {
    (
        cv.channel.get(output).copied().unwrap_or(f64::NEG_INFINITY),
        cv.mean,
    )
}

fn pred<'f>(f: &'f StructuredFit, key: &str) -> Option<&'f [f64]> {
    f.prediction
        .iter()
        .find(|(k, _)| *k == key)
        .map(|(_, p)| p.as_slice())
}

/// The strongest steady peak of the output's estimation residual of `f` (a sinusoid's and a
/// resonance's start), between 20 periods per record and 0.45 of the row rate.
fn residual_peak(d: &Data<'_>, f: &StructuredFit, output: &str) -> Option<f64> {
    let c = d.channels.iter().position(|c| c.key == output)?;
    let p = pred(f, output)?;
    let r: Vec<f64> = d
        .folds
        .estimation
        .clone()
        .map(|k| {
            let y = d.channels[c].y[k];
            if y.is_finite() && p[k].is_finite() {
                y - p[k]
            } else {
                f64::NAN
            }
        })
        .collect();
    let span = r.len() as f64 * d.dt_s;
    peaks(&r, d.dt_s, 20.0 / span, 0.45 / d.dt_s, 1)
        .first()
        .map(|p| p.0)
}

/// The stand diagnosis (module doc) of command `u` every `dt_s` with the supply `voltage`
/// and the stand channels of `input`, on the folds of the generic diagnosis, with the
/// segmentation's `rules` and the acceptance test `gate`.
pub fn search(
    dt_s: f64,
    u: &[f64],
    voltage: Option<&[f64]>,
    input: &StandInput<'_>,
    output: &'static str,
    folds: &Folds,
    (rules, gate): (SegmentRules, Gate),
) -> Result<StandRun, StandModelError> {
    let read: Vec<Vec<f64>> = input
        .channels
        .iter()
        .map(|c| {
            (0..c.y.len())
                .map(|k| {
                    if c.interpolated.get(k).copied().unwrap_or(false) {
                        f64::NAN
                    } else {
                        c.y[k]
                    }
                })
                .collect()
        })
        .collect();
    let d = Data {
        dt_s,
        u,
        voltage,
        channels: &input.channels,
        rules,
        folds,
        read,
    };
    let est = d.estimation();
    let base_st = Structure::default();
    let base = d.fit(&est, &base_st, None)?;
    let sigma = base.warm.sigma.clone().unwrap_or_default();
    let base_cv = d.cv(&base_st, &base, &sigma);
    let reference = base
        .fit
        .channels
        .iter()
        .find(|c| c.reference)
        .map_or(output, |c| c.key);
    let timed: Vec<&'static str> = base
        .fit
        .channels
        .iter()
        .filter(|c| !c.reference)
        .map(|c| c.key)
        .collect();
    let shows = base.fit.shows;
    let v_ref = voltage.map_or(1.0, |v| {
        let fin: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        fin.iter().sum::<f64>() / fin.len().max(1) as f64
    });

    let (mut st, mut cur, mut cur_cv) = (base_st.clone(), base.clone(), base_cv.clone());
    let mut taken: Vec<(Candidate, f64, f64, String)> = Vec::new();
    let mut ledger: Vec<(Candidate, Rejected)> = Vec::new();
    while taken.len() < thresholds::STAND_MAX_EFFECTS {
        let (sse0, n) = d.sse(&cur, &sigma);
        let peak_hz = residual_peak(&d, &cur, output);
        let rec = catalogue::Record {
            timed: timed.clone(),
            voltage: voltage.is_some(),
            both_directions: shows.rises && shows.falls,
            several_levels: shows.several_levels,
            peak_hz,
        };
        let mut best: Option<(Candidate, Structure, StructuredFit, Cv, f64)> = None;
        for c in catalogue::candidates(&st, &rec) {
            let st1 = catalogue::with(&st, c, peak_hz);
            let warm = cur.warm.with_weights(sigma.clone(), 40);
            let Ok(f1) = d.fit(&est, &st1, Some(&warm)) else {
                continue;
            };
            let (sse1, _) = d.sse(&f1, &sigma);
            let score = n as f64 * (sse0 / sse1.max(1e-300)).ln();
            let drop = 1.0 - (sse1 / sse0.max(1e-300)).sqrt();
            if !(score >= thresholds::SCORE_THRESHOLD && drop >= thresholds::MIN_RMS_DROP) {
                ledger.retain(|(k, _)| *k != c);
                continue;
            }
            let cv1 = d.cv(&st1, &f1, &sigma);
            let gain = cv1.mean - cur_cv.mean;
            ledger.retain(|(k, _)| *k != c);
            ledger.push((c, Rejected::held_out(c.effect, score, gain)));
            // The acceptance test against the folds' scatter (`HeldOutGain`); one hold-out
            // tail has no folds to scatter: its gain alone. The diagnosed output's figure
            // must not fall (module doc, 4).
            let (b0, b1) = (cur_cv.fold_means(), cv1.fold_means());
            let accepted = if b0.len() >= 2 && b0.len() == b1.len() {
                HeldOutGain::paired(&b0, &b1, gain).accepted(gate)
            } else {
                gain > thresholds::MIN_CV_GAIN_PP
            };
            let on_output = |cv: &Cv| cv.channel.get(output).copied().unwrap_or(f64::NAN);
            // The output's figure falls beyond its folds' scatter (the paired test, the
            // other way round).
            let fold_of = |cv: &Cv| cv.folds.get(output).cloned().unwrap_or_default();
            let (o0, o1) = (fold_of(&cur_cv), fold_of(&cv1));
            let keeps_output = if o0.len() >= 2 && o0.len() == o1.len() {
                !HeldOutGain::paired(&o1, &o0, on_output(&cur_cv) - on_output(&cv1)).significant()
            } else {
                on_output(&cv1) >= on_output(&cur_cv)
            };
            if accepted
                && keeps_output
                && best
                    .as_ref()
                    .map_or(true, |b| rank(&cv1, output) > rank(&b.3, output))
            {
                best = Some((c, st1, f1, cv1, score));
            }
        }
        let Some((c, st1, f1, cv1, score)) = best else {
            break;
        };
        let gain = cv1.mean - cur_cv.mean;
        let (sse1, _) = d.sse(&f1, &sigma);
        let drop = format!(
            "the weighted residual RMS of the estimation readings fell by {:.1} %",
            100.0 * (1.0 - (sse1 / sse0.max(1e-300)).sqrt())
        );
        ledger.retain(|(k, _)| *k != c);
        taken.push((c, score, gain, drop));
        st = st1;
        cur = f1;
        cur_cv = cv1;
    }
    // A sensor's lag taken early can collapse once a later effect explains what it stood in
    // for (a resonance's phase lag): at the end its figures read with the reference
    // ([`catalogue::resolved`]), the model without it is the same model, and it is dropped.
    let collapsed: Vec<Candidate> = taken
        .iter()
        .map(|t| t.0)
        .filter(|&c| !catalogue::resolved(c, &cur, dt_s))
        .collect();
    if !collapsed.is_empty() {
        let mut st1 = st.clone();
        st1.lagged
            .retain(|k| !collapsed.iter().any(|c| c.channel == Some(*k)));
        let warm = cur.warm.with_weights(sigma.clone(), 40);
        if let Ok(f1) = d.fit(&est, &st1, Some(&warm)) {
            cur_cv = d.cv(&st1, &f1, &sigma);
            cur = f1;
            st = st1;
            taken.retain(|t| !collapsed.contains(&t.0));
        }
    }

    let findings: Vec<Finding> = taken
        .iter()
        .map(|(c, score, gain, drop)| {
            let params = catalogue::params(*c, &cur, output, dt_s, v_ref);
            Finding {
                effect: c.effect,
                score: *score,
                cv_gain_pp: *gain,
                evidence: catalogue::evidence(*c, &params, drop),
                params,
                drop: drop.clone(),
            }
        })
        .collect();
    let rejected: Vec<Rejected> = ledger.into_iter().map(|(_, r)| r).collect();
    let effects: Vec<EffectName> = taken.iter().map(|t| t.0.effect).collect();
    let channels = input
        .channels
        .iter()
        .enumerate()
        .filter_map(|(c, ch)| {
            let b = *base_cv.channel.get(ch.key)?;
            let p = base_cv.prediction.get(ch.key)?;
            let r: Vec<f64> = d.read[c].iter().zip(p).map(|(y, p)| y - p).collect();
            Some((
                ch.key,
                ChannelScore {
                    baseline_fit_percent: b,
                    fit_percent: cur_cv.channel.get(ch.key).copied().unwrap_or(b),
                    departures: departures::departures(u, &r, dt_s, &rules),
                },
            ))
        })
        .collect();
    let report_ = StandDiagnosis {
        reference_channel: reference,
        output,
        baseline_mean_fit_percent: base_cv.mean,
        mean_fit_percent: cur_cv.mean,
        effects: effects.clone(),
        channels,
        model: report(&cur.fit),
    };
    Ok(StandRun {
        report: report_,
        findings,
        rejected,
        base_cv,
        cv: cur_cv,
        stand: StandBaseline {
            dt_s,
            baseline: base,
            extended: cur,
            structure: st,
            effects,
            folds: folds.clone(),
        },
    })
}

/// The findings' parameters as JSON (tests).
pub fn params_of(f: &Finding) -> &Map<String, Value> {
    &f.params
}

/// The quantity a channel key names (`rpm`, `thrust`, `torque`, `current`).
pub fn quantity(key: &str) -> Option<Quantity> {
    match key {
        "rpm" => Some(Quantity::Speed),
        "thrust" => Some(Quantity::Thrust),
        "torque" => Some(Quantity::Torque),
        "current" => Some(Quantity::Current),
        _ => None,
    }
}

#[cfg(test)]
mod tests;
