//! The two outputs of `identify`: one JSON object, or a short human summary.

use std::fmt::Write;

use serde::Serialize;

use super::load::{Loaded, Source};
pub use super::stand::StepOut;
use super::Physics;
use propid_numerics::identify::{AnyModel, PathTaken};
use propid_numerics::operating_points::OpTable;
use propid_numerics::quality::{judge, judge_gain, judge_sample_period, Flaw};
use propid_numerics::report::Gain;
use propid_numerics::stabilization::Stabilization;
use propid_numerics::stand::StandFigures;
use propid_numerics::stand_model::report::Stand;
use propid_numerics::static_map::LevelSlope;
use propid_numerics::step_directions::{by_direction, DirectionFigures};
use propid_numerics::ModelReport;

/// Step figures' medians per direction (`"up"`, `"down"`).
type ByDirection = std::collections::BTreeMap<&'static str, DirectionFigures>;

/// The steps of `stand` with their timing per channel from `physics`.
fn steps_out<'a>(stand: &'a StandFigures, physics: &Physics) -> Vec<StepOut<'a>> {
    stand
        .steps
        .iter()
        .enumerate()
        .map(|(i, f)| StepOut {
            figures: f,
            channels: physics.timing.get(i).cloned().unwrap_or_default(),
        })
        .collect()
}

/// Everything `identify` prints.
#[derive(Debug, Clone, Serialize)]
pub struct Output<'a> {
    /// The model (public field names, see `core::report`).
    pub model: &'a ModelReport,
    /// Where the data came from and which path was taken.
    pub source: Source,
    /// The gain schedule.
    pub operating_points: &'a OpTable,
    /// Step figures, one per clean command step (empty without steps), each with its timing
    /// on every output channel.
    pub steps: Vec<StepOut<'a>>,
    /// Their medians per direction, `up` and `down` ([`propid_numerics::step_directions`]);
    /// omitted without steps.
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub steps_by_direction: ByDirection,
    /// Steady levels and fitted curves per output (empty without steps or a ramp).
    pub static_map: &'a std::collections::BTreeMap<&'static str, propid_numerics::stand::StaticMap>,
    /// The stand's physics ([`propid_numerics::stand_model::report`]): `null` when the input is
    /// no stand's command, `{"refused": ...}` when the record cannot give it.
    pub stand: Option<&'a Stand>,
    /// The stabilization diagram of the model's Hankel SVD (null when it cannot be realised).
    pub stabilization: Option<&'a Stabilization>,
    /// The quality checks of the model ([`propid_numerics::quality`], the daemon's rule).
    pub quality: Quality,
    /// Implausible results that do not reject the model (`nonpositive_gain`: the output falls
    /// as the command rises, [`propid_numerics::quality::nonpositive_gain`];
    /// `expo_outside_blend`: the thrust map's expo outside `0..1`; `levels_not_repeatable`: a
    /// command held twice gave two thrusts apart beyond the noise; `thrust_zero_offset`: the
    /// thrust reads beyond zero at zero command, taken out of its curves); empty when none.
    pub warnings: Vec<IdentifyWarning>,
    /// The parameters of every flight controller and simulator `propid params` knows, by
    /// target ([`propid_model::params`]; docs/params.md).
    pub params: serde_json::Map<String, serde_json::Value>,
    /// The output-error refinement of an OKID model
    /// ([`propid_numerics::output_error::Refinement`]), when it ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refinement: Option<serde_json::Value>,
}

/// One entry of `"warnings"`: the shape of `diagnose`'s (`kind`, `message`, `value`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IdentifyWarning {
    /// What is implausible (`nonpositive_gain`, `expo_outside_blend`, `levels_not_repeatable`,
    /// `thrust_zero_offset`).
    pub kind: &'static str,
    /// In words.
    pub message: String,
    /// The offending value.
    pub value: f64,
}

/// The warnings on `model` identified from a command (`commanded`): a DC gain `≤ 0`; and on
/// the thrust's static map (`thrust`): an expo outside the blend ([`expo_outside_blend`]).
fn warnings_of(
    model: &propid_numerics::ModelReport,
    commanded: bool,
    thrust: Option<&propid_numerics::stand::StaticMap>,
) -> Vec<IdentifyWarning> {
    let gain = commanded
        .then(|| propid_numerics::quality::nonpositive_gain(model))
        .flatten();
    gain.map(|g| IdentifyWarning {
        kind: "nonpositive_gain",
        message: format!(
            "DC gain {g:.4} ≤ 0: the output does not grow with the command (a load cell \
             mounted reversed or a sign convention of the export? the model is printed as \
             measured)"
        ),
        value: g,
    })
    .into_iter()
    .chain(thrust.into_iter().flat_map(thrust_map_warnings))
    .collect()
}

/// What a recording's stream says about its device clock, by the one rule of `propid run` and
/// `replay` (`propid_wire::stream::SampleAssembler`): `clock_jump` (value: how many; the rate is
/// measured without them, no span of time crosses one) and `hello_rate_mismatch` (value: the
/// HELLO's rate; the measured one is `rate_hz`).
fn stream_warnings(source: &super::load::Source) -> Vec<IdentifyWarning> {
    let Some(t) = &source.tsp1 else {
        return Vec::new();
    };
    let mut w = Vec::new();
    let jumps = t.assemble.clock_jumps;
    if jumps > 0 {
        w.push(IdentifyWarning {
            kind: "clock_jump",
            message: format!(
                "the device clock jumped {jumps} time(s) while the sample index ran on: the                  sample period is measured without the jumps ({:.4} Hz)",
                source.rate_hz
            ),
            value: jumps as f64,
        });
    }
    if t.assemble.rate_mismatches > 0 {
        // a mismatch without a nominal rate is a HELLO that claimed 0 Hz
        let n = source.nominal_rate_hz.unwrap_or(0.0);
        w.push(IdentifyWarning {
            kind: "hello_rate_mismatch",
            message: format!(
                "the HELLO claims {n:.4} Hz, the device clock measures {:.4} Hz: the measured                  rate is used",
                source.rate_hz
            ),
            value: n,
        });
    }
    w
}

/// What the thrust's static map warns of: an expo outside the blend, levels that do not
/// repeat, a reading at zero command taken out of the curves.
fn thrust_map_warnings(map: &propid_numerics::stand::StaticMap) -> Vec<IdentifyWarning> {
    expo_outside_blend(map)
        .into_iter()
        .chain(levels_not_repeatable(map))
        .chain(zero_offset(map))
        .collect()
}

/// The thrust's reading at zero command when the map took one out
/// ([`propid_numerics::static_map::offset`]) and it is at least
/// [`propid_numerics::static_map::MIN_SHARE`] of full thrust (the share `levels_not_repeatable`
/// calls a stand's own shift; a smaller one is in `zero_offset` and the summary, unwarned): the
/// levels as printed carry it, the curves do not.
fn zero_offset(map: &propid_numerics::stand::StaticMap) -> Option<IdentifyWarning> {
    let z = map.zero_offset?;
    let full = map
        .levels
        .iter()
        .map(|l| (l.mean - z.value).abs())
        .fold(0.0, f64::max);
    if z.value.abs() < propid_numerics::static_map::MIN_SHARE * full {
        return None;
    }
    Some(IdentifyWarning {
        kind: "thrust_zero_offset",
        message: format!(
            "the thrust reads {:+.4} ± {:.4} {} at zero command ({:.1} % of full thrust): the \
             load cell was not tared, or its zero moved; the power law and the expo describe \
             the thrust above that reading (the levels are printed as read)",
            z.value,
            z.sd,
            map.unit,
            100.0 * z.value.abs() / full.max(f64::MIN_POSITIVE)
        ),
        value: z.value,
    })
}

/// The thrust map's largest shift between visits of one command when it is beyond the noise
/// and a share of full thrust ([`propid_numerics::static_map::not_repeatable`]): the map holds
/// only to that, whatever its curves' uncertainties say.
fn levels_not_repeatable(map: &propid_numerics::stand::StaticMap) -> Option<IdentifyWarning> {
    let (r, share) = propid_numerics::static_map::not_repeatable(&map.levels, &map.repeats)?;
    Some(IdentifyWarning {
        kind: "levels_not_repeatable",
        message: format!(
            "the thrust at throttle {:.3} moved by {:+.4} {} between its first and last visit \
             ({:.1} % of full thrust, beyond its noise): the stand does not repeat itself (a \
             load cell's zero creeping or warming, a motor or battery heating); the static map \
             holds to about that, whatever its fit's uncertainty",
            r.throttle,
            r.shift,
            map.unit,
            100.0 * share
        ),
        value: r.shift,
    })
}

/// The thrust map's expo `a` when it lies outside `0..1` by more than two standard errors: the
/// curve is then no blend of a line and a parabola through throttle 0 (`a > 1` bends up more
/// than a parabola and dips below 0 at low throttle; `a < 0` bends down), which is what a
/// flight controller's `MOT_THST_EXPO` / `THR_MDL_FAC` describes. Seen on vanderploeg's step
/// tables (`a` 1.11–1.17: thrust ∝ (u − u0)^2.5..3 over the ESC's µs); the power law, printed
/// beside it, is then the map to use.
fn expo_outside_blend(map: &propid_numerics::stand::StaticMap) -> Option<IdentifyWarning> {
    let e = map.expo.as_ref()?;
    let sd = e.uncertainty.map_or(0.0, |u| u.a);
    if (0.0..=1.0).contains(&e.a) || (e.a - 1.0).abs().min(e.a.abs()) <= 2.0 * sd {
        return None;
    }
    let bends = match e.a > 1.0 {
        true => "bends up more than a parabola through throttle 0",
        false => "bends down (less than linear)",
    };
    let law = map.power.as_ref().map_or_else(String::new, |p| {
        format!(
            " (the power law: exponent {:.2} from throttle {:.3})",
            p.exponent, p.u0
        )
    });
    Some(IdentifyWarning {
        kind: "expo_outside_blend",
        message: format!(
            "the thrust expo a = {:.2} ± {sd:.2} lies outside 0..1 (0 linear, 1 quadratic): the \
             thrust {bends}{law}, which a flight controller's MOT_THST_EXPO / THR_MDL_FAC \
             cannot describe as it is; use the power law, or fit the expo over the throttle \
             range the controller uses",
            e.a
        ),
        value: e.a,
    })
}

/// `"quality"` in the JSON output: whether the model passed the checks a plant's model always
/// passes, and if not why (`unstable_pole`, `dc_gain_uncertain`, `dc_gain_contradicts_levels`). A rejected model is printed
/// for inspection and `identify` exits 4.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Quality {
    /// The model passed every check.
    pub accepted: bool,
    /// The checks it failed.
    pub flaws: Vec<Flaw>,
    /// What to do about it (rejected models only); names the numbers when the DC gain
    /// contradicts the record's steady levels.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hint: Option<String>,
}

/// Hint printed with a rejected model.
pub const HINT: &str = "not the plant's model: the pulse responses are not resolved above the \
    noise, or the record holds what a model around one operating point cannot (a start-up \
    transient, a drift); use a record that starts settled, wider or larger pulses, more pulses";

impl Quality {
    /// The verdict on `model`: the daemon's checks ([`judge`]), its DC gain against the
    /// slope of the record's steady levels when it has some ([`judge_gain`]), and, for a stand's
    /// command (`command`), whether the record's sample period can show dynamics at all
    /// ([`judge_sample_period`]).
    pub fn of(
        model: &propid_numerics::ModelReport,
        levels: Option<&LevelSlope>,
        command: bool,
    ) -> Quality {
        let mut flaws = judge(model);
        let contradiction = levels.and_then(|s| judge_gain(model, s));
        let mut hints = Vec::new();
        if let Some(c) = contradiction {
            flaws.push(Flaw::DcGainContradictsLevels);
            hints.push(c.to_string());
        }
        if let Some(f) = judge_sample_period(model.dt_s).filter(|_| command) {
            flaws.push(f);
            hints.push(format!(
                "a sample every {:.3} s is longer than a motor-propeller takes to settle (a \
                 third of a second): every sample is a steady state and the record holds no \
                 dynamics; its static map is what it shows",
                model.dt_s
            ));
        }
        if flaws.len() > hints.len() {
            hints.push(HINT.to_string());
        }
        let accepted = flaws.is_empty();
        Quality {
            accepted,
            flaws,
            hint: (!accepted).then(|| hints.join("; ")),
        }
    }

    /// The flaws by name, comma separated.
    pub fn names(&self) -> String {
        self.flaws
            .iter()
            .map(|f| f.name())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl<'a> Output<'a> {
    /// Assembles the output.
    pub fn new(
        loaded: &Loaded,
        model: &'a AnyModel,
        ops: &'a OpTable,
        stand: &'a StandFigures,
        levels: Option<&LevelSlope>,
        physics: &'a Physics,
    ) -> Self {
        let mut source = loaded.source.clone();
        source.path = path_name(model.path);
        source.okid = model.okid.clone();
        Self {
            model: &model.report,
            source,
            operating_points: ops,
            steps: steps_out(stand, physics),
            steps_by_direction: by_direction(&stand.steps),
            static_map: &stand.static_map,
            stand: physics.stand.as_ref(),
            stabilization: model.stabilization.as_ref(),
            quality: Quality::of(&model.report, levels, loaded.input_is_a_command),
            warnings: stream_warnings(&loaded.source)
                .into_iter()
                .chain(warnings_of(
                    &model.report,
                    loaded.commanded,
                    stand.static_map.get("thrust"),
                ))
                .collect(),
            params: serde_json::Map::new(),
            refinement: None,
        }
    }

    /// Exactly one JSON object.
    pub fn json(&self) -> serde_json::Result<String> {
        serde_json::to_string(self)
    }

    /// The human summary.
    pub fn human(&self) -> String {
        let (m, s) = (self.model, &self.source);
        let mut o = String::new();
        let _ = writeln!(o, "file      {} ({})", s.file, s.format);
        let _ = writeln!(o, "input     {}", s.input);
        if let Some(line) = s.read.input_range_line() {
            let _ = writeln!(o, "          {line}");
        }
        if let Some(line) = s.read.units_line() {
            let _ = writeln!(o, "units     {line}");
        }
        for u in s.csv.iter().flat_map(|c| &c.unread) {
            let _ = writeln!(o, "left out  {}: {}", u.column, u.reason);
        }
        let _ = writeln!(o, "outputs   {}", s.outputs.join(", "));
        let nominal = s
            .nominal_rate_hz
            .map_or(String::new(), |n| format!(" (HELLO: {n:.4} Hz)"));
        let _ = writeln!(
            o,
            "rate      {:.4} Hz{nominal}, {} samples ({} missing)",
            s.rate_hz, s.samples, s.missing
        );
        if let Some(w) = &s.window {
            let _ = writeln!(
                o,
                "window    samples {}..{} of the file's {} ({:.1} s from its start; the \
                 command's {} of {} moves): the span identified",
                w.start,
                w.start + w.samples,
                w.file_samples,
                w.start_s,
                w.moves,
                w.file_moves
            );
        }
        if s.outliers > 0 {
            let _ = writeln!(
                o,
                "outliers  {} isolated sample(s) left out (marked missing)",
                s.outliers
            );
        }
        if s.start_up_transient > 0 {
            let _ = writeln!(
                o,
                "start-up  the first {} samples ({:.3} s) left out (marked missing): the output \
                 was still settling under the first command level",
                s.start_up_transient,
                s.start_up_transient as f64 / s.rate_hz
            );
        }
        for (key, c) in s.csv.iter().flat_map(|c| &c.channels) {
            if let Some(rows) = c.held_rows {
                let _ = writeln!(
                    o,
                    "held      {key} repeats each reading for {rows} rows: read at its own rate \
                     ({} readings, interpolated between them)",
                    c.values
                );
            }
            if c.interpolated_rows > 0 {
                let _ = writeln!(
                    o,
                    "lines     {key} was interpolated by the exporter on {} of its rows: kept, \
                     marked as not read (its noise is measured at its readings)",
                    c.interpolated_rows
                );
            }
            if c.command_held > 0 {
                let _ = writeln!(
                    o,
                    "held      {key} written only where it changes: {} empty cells hold the last \
                     command",
                    c.command_held
                );
            }
        }
        if let Some(c) = s.csv.as_ref() {
            if let Some(e) = c.encoding {
                let name = serde_json::to_value(e).unwrap_or_default();
                let _ = writeln!(o, "encoding  {}", name.as_str().unwrap_or("?"));
            }
            let k = &c.skipped;
            if k.total() > 0 {
                let _ = writeln!(
                    o,
                    "rows      {} read; skipped: {} with a bad checksum, {} with text in a number \
                     field, {} too short",
                    c.rows, k.bad_checksum, k.not_a_number, k.short_row
                );
            }
        }
        if let Some(j) = s.csv.as_ref().and_then(|c| c.jitter.as_ref()) {
            let _ = writeln!(
                o,
                "timing    median dt {:.4} s, p5..p95 {:.4}..{:.4} s, rms jitter {:.4} s{}",
                j.median_dt_s,
                j.p5_dt_s,
                j.p95_dt_s,
                j.rms_jitter_s,
                match (j.steady_rows, j.resampled) {
                    (true, _) => ", a table of steady states (every channel held from row to row)",
                    (false, true) => ", resampled",
                    (false, false) => "",
                }
            );
            if let Some(c) = j.coarse_clock {
                let _ = writeln!(
                    o,
                    "          stamps every {} s, {} rows each: the clock is coarser than the \
                     rows; each stamp's rows spread evenly over its tick ({} rows)",
                    c.tick_s, c.rows_per_tick, c.rows_spread
                );
            }
            if j.non_increasing > 0 {
                let _ = writeln!(
                    o,
                    "          {} rows dropped: their time did not increase (repeated stamps, \
                     or the clock going back: a second run appended?)",
                    j.non_increasing
                );
            }
        }
        if let Some(steps) = &s.steps {
            let _ = writeln!(o, "steps     {} found from the response:", steps.len());
            for st in steps {
                let _ = writeln!(
                    o,
                    "          t = {:.3} s  {:.4} -> {:.4}",
                    st.t_s, st.from, st.to
                );
            }
        }
        match &s.okid {
            Some(k) => {
                let _ = writeln!(
                    o,
                    "path      OKID ({} observer parameters of max {}, by {}; condition {:.2e}, rank {}/{}{})",
                    k.observer_order,
                    k.observer_order_max,
                    k.observer_order_from,
                    k.condition,
                    k.rank,
                    k.params,
                    if k.regularised { ", regularised" } else { "" }
                );
            }
            None => {
                let _ = writeln!(o, "path      pulse ({} pulses averaged)", m.pulses);
            }
        }
        match m.order_stepped_down_from {
            Some(count) => {
                let _ = writeln!(
                    o,
                    "order     {} ({count} singular values above the noise; the orders above {} \
                     realised a pole that does not settle: noise, stepped down)",
                    m.order, m.order
                );
            }
            None => {
                let _ = writeln!(o, "order     {}", m.order);
            }
        }
        let _ = writeln!(o, "fn        {:.4} Hz", m.fn_hz);
        let _ = writeln!(o, "zeta      {:.4}", m.zeta);
        let _ = writeln!(o, "tau       {}", taus(&m.time_constants_s));
        let _ = writeln!(o, "dc gain   {}", gain(&m.dc_gain));
        match &self.quality {
            q if q.accepted => {
                let _ = writeln!(o, "quality   accepted");
            }
            q => {
                let hint = q.hint.as_deref().unwrap_or(HINT);
                let _ = writeln!(o, "quality   REJECTED ({}): {hint}", q.names());
            }
        }
        for w in &self.warnings {
            let _ = writeln!(o, "warning   {}: {}", w.kind, w.message);
        }
        if let Some(st) = self.stabilization {
            let line = crate::plot::stabilization::summary_line(st, m.fn_hz, m.zeta);
            let _ = writeln!(o, "stability {line}");
        }
        let ops = self.operating_points;
        if !ops.points.is_empty() || !ops.skipped.is_empty() {
            let _ = writeln!(o, "operating points ({}):", ops.kind);
            let _ = writeln!(
                o,
                "  {:>10}  {:>6}  {:>9}  {:>7}  {:<16}  gain",
                "level", "path", "fn (Hz)", "zeta", "tau (s)"
            );
            for p in &ops.points {
                let _ = writeln!(
                    o,
                    "  {:>10.4}  {:>6}  {:>9.3}  {:>7.3}  {:<16}  {}",
                    p.level,
                    path_name(p.path),
                    p.fn_hz,
                    p.zeta,
                    taus(&p.time_constants_s),
                    gain(&p.dc_gain)
                );
            }
            for sk in &ops.skipped {
                let _ = writeln!(o, "  {:>10.4}  skipped: {}", sk.level, sk.reason);
            }
        }
        super::stand::write_tables(
            &mut o,
            &StandFigures {
                command: "",
                steps: self.steps.iter().map(|s| s.figures.clone()).collect(),
                static_map: self.static_map.clone(),
            },
        );
        super::stand::write_channel_timing(&mut o, &self.steps);
        super::stand::write_physics(&mut o, self.stand);
        o
    }
}

/// What `identify` prints when the identification failed but the record has steps or a static
/// map (exit 4 all the same): `{"model": null, "error": "...", "source": {...}, "steps": [...],
/// "static_map": {...}}`.
#[derive(Debug, Clone, Serialize)]
pub struct Partial<'a> {
    /// Always null: no model.
    pub model: Option<&'a ModelReport>,
    /// Why the identification failed.
    pub error: String,
    /// Where the data came from.
    pub source: Source,
    /// Step figures, one per clean command step, with their timing per channel.
    pub steps: Vec<StepOut<'a>>,
    /// Their medians per direction (as [`Output::steps_by_direction`]).
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub steps_by_direction: ByDirection,
    /// Steady levels and fitted curves per output.
    pub static_map: &'a std::collections::BTreeMap<&'static str, propid_numerics::stand::StaticMap>,
    /// The stand's physics (as [`Output::stand`]).
    pub stand: Option<&'a Stand>,
    /// Implausible figures (`expo_outside_blend`, `levels_not_repeatable`,
    /// `thrust_zero_offset`); empty when none.
    pub warnings: Vec<IdentifyWarning>,
    /// All the figures (for the human tables).
    #[serde(skip)]
    figures: &'a StandFigures,
}

impl<'a> Partial<'a> {
    /// The figures of `stand` with the failure `error`.
    pub fn new(
        loaded: &Loaded,
        error: &impl std::fmt::Display,
        stand: &'a StandFigures,
        physics: &'a Physics,
    ) -> Self {
        Self {
            model: None,
            error: error.to_string(),
            source: loaded.source.clone(),
            steps: steps_out(stand, physics),
            steps_by_direction: by_direction(&stand.steps),
            static_map: &stand.static_map,
            stand: physics.stand.as_ref(),
            warnings: stream_warnings(&loaded.source)
                .into_iter()
                .chain(
                    stand
                        .static_map
                        .get("thrust")
                        .into_iter()
                        .flat_map(thrust_map_warnings),
                )
                .collect(),
            figures: stand,
        }
    }

    /// Exactly one JSON object.
    pub fn json(&self) -> serde_json::Result<String> {
        serde_json::to_string(self)
    }

    /// The human summary: the source, the failure, the step and static-map tables.
    pub fn human(&self) -> String {
        let s = &self.source;
        let mut o = String::new();
        let _ = writeln!(o, "file      {} ({})", s.file, s.format);
        let _ = writeln!(o, "input     {}", s.input);
        let _ = writeln!(o, "identification failed: {}", self.error);
        for w in &self.warnings {
            let _ = writeln!(o, "warning   {}: {}", w.kind, w.message);
        }
        let _ = writeln!(o, "(the step figures and the static map need no model:)");
        super::stand::write_tables(&mut o, self.figures);
        super::stand::write_channel_timing(&mut o, &self.steps);
        super::stand::write_physics(&mut o, self.stand);
        o
    }
}

fn path_name(p: PathTaken) -> &'static str {
    match p {
        PathTaken::Pulse => "pulse",
        PathTaken::Okid => "okid",
    }
}

fn taus(t: &[f64]) -> String {
    if t.is_empty() {
        return "-".into();
    }
    t.iter()
        .map(|v| format!("{v:.4}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn gain(g: &Gain) -> String {
    match g {
        Gain::Scalar(v) => format!("{v:.4}"),
        Gain::List(v) => v
            .iter()
            .map(|x| format!("{x:.4}"))
            .collect::<Vec<_>>()
            .join(", "),
        Gain::Matrix(m) => format!("{m:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_numerics::stand::StaticMap;
    use propid_numerics::static_map::{fit_expo, fit_power_law, Level};

    /// The static map of levels `t(u)` at throttle 0.15, 0.20, …, 0.80.
    fn map(t: impl Fn(f64) -> f64) -> StaticMap {
        let levels: Vec<Level> = (3..=16)
            .map(|i| {
                let u = 0.05 * f64::from(i);
                Level {
                    throttle: u,
                    mean: t(u),
                    std: 0.0,
                    samples: 1,
                }
            })
            .collect();
        StaticMap {
            unit: "N",
            power: fit_power_law(&levels),
            expo: fit_expo(&levels),
            zero_offset: None,
            k_t: None,
            falls_with_command: false,
            repeats: Vec::new(),
            levels,
        }
    }

    #[test]
    fn an_expo_outside_the_blend_is_a_warning_and_a_blend_is_not() {
        // Thrust ∝ u³ (as vanderploeg's µs tables): a > 1, warned, with the power law's exponent.
        let w = expo_outside_blend(&map(|u| 20.0 * u * u * u)).unwrap();
        assert_eq!(w.kind, "expo_outside_blend");
        assert!(w.value > 1.1, "{w:?}");
        assert!(w.message.contains("exponent 3.00"), "{}", w.message);
        // A square root: a < 0.
        assert!(expo_outside_blend(&map(|u| 10.0 * u.sqrt())).unwrap().value < 0.0);
        // The blends flight controllers take: none.
        for a in [0.0, 0.35, 0.65, 1.0] {
            let m = map(|u| 12.0 * ((1.0 - a) * u + a * u * u));
            assert!(expo_outside_blend(&m).is_none(), "{a}: {:?}", m.expo);
        }
    }
}
