//! `propid demo --http`: the page's `truth` line, the simulator's truth beside each level's
//! model as the terminal prints it ([`super::table`]), sent to the web page's clients only
//! (never stdout, the file or the socket) after every model:
//!
//! `{"type":"truth", "plant":"motor"|"second_order", "levels":[{"operating_point", "gain", …}]}`
//!
//! one row per level so far, in level order (the last model per level), the shape of the
//! page's gain schedule. The motor's row ([`TruthRow::motor`]) holds the plant linearised at
//! the level (`gain` = dT/du, `tau_up_s`, `tau_down_s`, `dead_time_s`), what an exact linear
//! fit to pulses of both signs would show (`linear_fit`), the model's own figures read the
//! same way (`model`) and whether they are within the demo's tolerances (`within`); the
//! 2nd-order plant's row ([`TruthRow::second_order`]) holds its one truth (`gain`, `fn_hz`,
//! `zeta`).

use serde::Serialize;

use super::table::MotorRow;
use propid_numerics::nullable;
use propid_sim::plant::PlantConfig;
use propid_sim::truth::{self, Figures};

/// Gain, time constant and dead time of one response, as the page shows them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FiguresJson {
    /// DC gain, N per unit throttle.
    #[serde(with = "nullable::num")]
    pub gain: f64,
    /// Time constant, s (`null` when the step figures have none).
    pub tau_s: Option<f64>,
    /// Dead time, s (`null` when the step figures have none).
    pub dead_time_s: Option<f64>,
}

impl From<&Figures> for FiguresJson {
    fn from(f: &Figures) -> Self {
        FiguresJson {
            gain: f.gain,
            tau_s: f.tau_s,
            dead_time_s: f.dead_time_s,
        }
    }
}

/// One level's truth.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TruthRow {
    /// The model's operating point, throttle.
    pub operating_point: f64,
    /// The true small-signal gain, N per unit throttle.
    #[serde(with = "nullable::num")]
    pub gain: f64,
    /// The 2nd-order plant's natural frequency, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fn_hz: Option<f64>,
    /// The 2nd-order plant's damping ratio.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zeta: Option<f64>,
    /// The motor's linearised spin-up time constant, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tau_up_s: Option<f64>,
    /// The motor's linearised spin-down time constant, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tau_down_s: Option<f64>,
    /// The motor's dead time, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dead_time_s: Option<f64>,
    /// What an exact linear fit to ± pulses would show (motor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linear_fit: Option<FiguresJson>,
    /// The model's figures, read as the truth's (motor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<FiguresJson>,
    /// Whether the model is within the demo's tolerances of the truth (motor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub within: Option<bool>,
}

impl TruthRow {
    /// The motor's row of one model (the terminal's [`MotorRow`]).
    pub fn motor(r: &MotorRow) -> TruthRow {
        let t = &r.expected.truth;
        TruthRow {
            operating_point: r.level,
            gain: t.gain_n_per_throttle,
            fn_hz: None,
            zeta: None,
            tau_up_s: Some(t.tau_up_s),
            tau_down_s: Some(t.tau_down_s),
            dead_time_s: Some(t.dead_time_s),
            linear_fit: Some((&r.expected.linear_fit).into()),
            model: Some((&r.model).into()),
            within: Some(truth::within(&r.model, t)),
        }
    }

    /// The 2nd-order plant's row at `level` (one truth everywhere).
    pub fn second_order(level: f64, p: &PlantConfig) -> TruthRow {
        TruthRow {
            operating_point: level,
            gain: p.gain_n_per_throttle,
            fn_hz: Some(p.fn_hz),
            zeta: Some(p.zeta),
            tau_up_s: None,
            tau_down_s: None,
            dead_time_s: None,
            linear_fit: None,
            model: None,
            within: None,
        }
    }
}

/// The `truth` line.
#[derive(Debug, Serialize)]
pub struct TruthLine<'a> {
    /// Always `"truth"`.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// `"motor"` or `"second_order"`.
    pub plant: &'static str,
    /// One row per level so far, in level order.
    pub levels: &'a [TruthRow],
}

/// Keeps `row` as its level's (replacing an earlier one), in level order.
pub fn keep(rows: &mut Vec<TruthRow>, row: TruthRow) {
    rows.retain(|r| r.operating_point != row.operating_point);
    rows.push(row);
    rows.sort_by(|a, b| a.operating_point.total_cmp(&b.operating_point));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_line_keeps_one_row_per_level_in_order_and_names_its_fields() {
        let p = PlantConfig::default();
        let mut rows = Vec::new();
        keep(&mut rows, TruthRow::second_order(0.6, &p));
        keep(&mut rows, TruthRow::second_order(0.3, &p));
        keep(&mut rows, TruthRow::second_order(0.6, &p));
        let text = serde_json::to_string(&TruthLine {
            kind: "truth",
            plant: "second_order",
            levels: &rows,
        })
        .unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["type"], "truth");
        let levels = v["levels"].as_array().unwrap();
        assert_eq!(levels.len(), 2, "{text}");
        assert_eq!(levels[0]["operating_point"], 0.3);
        assert_eq!(levels[1]["fn_hz"], p.fn_hz);
        assert!(levels[0].get("tau_up_s").is_none(), "{text}");
    }
}
