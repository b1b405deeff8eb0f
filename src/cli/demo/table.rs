//! The demo's table: each model as a row beside the simulator's truth, then the gain schedule.
//! The 2nd-order plant has one truth everywhere (`fn_hz`, `zeta`, `gain_n_per_throttle`); the
//! motor plant's truth is its linearisation at each level ([`super::truth`]), printed with how
//! far a linear model must be off it because spin-down is slower than spin-up.

use std::fmt::Write as _;

use crate::daemon::line::{ScheduleRow, WindowModel};
use propid_sim::plant::{PlantConfig, PlantKind};
use propid_sim::truth::{self, Expected, Figures, DEAD_TOL_SAMPLES, GAIN_TOL, TAU_TOL};

/// One motor model as the table shows it: its level, its figures and the truth there.
#[derive(Debug, Clone, Copy)]
pub struct MotorRow {
    /// Device time of the window's last sample, s.
    pub t_s: f64,
    /// Operating point, throttle.
    pub level: f64,
    /// Jackknife standard deviation of the DC gain.
    pub gain_sd: f64,
    /// The model's figures.
    pub model: Figures,
    /// The truth there.
    pub expected: Expected,
}

impl MotorRow {
    /// The row of model `m` of the motor `plant` (`None` for the 2nd-order plant).
    pub fn of(m: &WindowModel, plant: &PlantConfig) -> Option<MotorRow> {
        let r = &m.report;
        let expected = truth::expected(plant, m.window.operating_point, r.dt_s, m.window.t_s)?;
        Some(MotorRow {
            t_s: m.window.t_s,
            level: m.window.operating_point,
            gain_sd: r.uncertainty.dc_gain.get(0),
            model: truth::model_figures(r),
            expected,
        })
    }
}

/// `value ± sd`, the sd when it is known.
fn with_sd(x: f64, sd: f64) -> String {
    if sd.is_finite() {
        format!("{x:.3} ± {sd:.3}")
    } else {
        format!("{x:.3}")
    }
}

/// Milliseconds with one decimal, `-` when unknown.
fn ms(s: Option<f64>) -> String {
    s.map_or("-".into(), |s| format!("{:.1}", s * 1e3))
}

/// The header of the live rows.
pub fn header(plant: &PlantConfig) -> String {
    match plant.kind {
        PlantKind::SecondOrder => format!(
            "{:>6} {:>8} {:>22} {:>20} {:>22}",
            "t_s", "throttle", "fn_hz (true)", "zeta (true)", "dc_gain N (true)"
        ),
        PlantKind::Motor => format!(
            "{:>6} {:>8} {:>24} {:>8} {:>20} {:>14}",
            "t_s", "throttle", "dc_gain N (truth)", "off", "tau_ms (up/down)", "dead_ms"
        ),
    }
}

/// One live row of a 2nd-order plant's model: identified values beside the true ones.
pub fn second_order_row(m: &WindowModel, p: &PlantConfig) -> String {
    let (r, u) = (&m.report, &m.report.uncertainty);
    format!(
        "{:>6.2} {:>8.3} {:>14} ({:>5.2}) {:>12} ({:>5.3}) {:>14} ({:>5.2})",
        m.window.t_s,
        m.window.operating_point,
        with_sd(r.fn_hz, u.fn_hz),
        p.fn_hz,
        with_sd(r.zeta, u.zeta),
        p.zeta,
        with_sd(r.dc_gain.get(0), u.dc_gain.get(0)),
        p.gain_n_per_throttle,
    )
}

/// One live row of a motor model: `gain ± sd (truth) off % τ (τ_up/τ_down) θ (θ_truth)`.
pub fn motor_row(r: &MotorRow) -> String {
    let t = &r.expected.truth;
    format!(
        "{:>6.2} {:>8.3} {:>15} ({:>6.2}) {:>+7.1}% {:>6} ({:>5.1}/{:>5.1}) {:>5} ({:>4.1})",
        r.t_s,
        r.level,
        with_sd(r.model.gain, r.gain_sd),
        t.gain_n_per_throttle,
        100.0 * truth::off(r.model.gain, t.gain_n_per_throttle),
        ms(r.model.tau_s),
        t.tau_up_s * 1e3,
        t.tau_down_s * 1e3,
        ms(r.model.dead_time_s),
        t.dead_time_s * 1e3,
    )
}

/// The 2nd-order plant's gain schedule (the last model per operating point), appended to `t`.
pub fn second_order_schedule(t: &mut String, rows: &[ScheduleRow], p: &PlantConfig) {
    let _ = writeln!(
        t,
        "\ngain schedule (true plant: fn {} Hz, zeta {}, gain {} N per unit throttle):",
        p.fn_hz, p.zeta, p.gain_n_per_throttle
    );
    let _ = writeln!(
        t,
        "{:>8} {:>8} {:>8} {:>10}",
        "throttle", "fn_hz", "zeta", "dc_gain"
    );
    for m in rows {
        let _ = writeln!(
            t,
            "{:>8.3} {:>8.3} {:>8.3} {:>10.3}",
            m.operating_point,
            m.fn_hz,
            m.zeta,
            m.dc_gain.get(0)
        );
    }
}

/// The motor's gain schedule (the last model per level, `rows` in level order) beside the
/// truth, what an exact linear fit would show, and the tolerances, appended to `t`.
pub fn motor_schedule(t: &mut String, rows: &[MotorRow], p: &PlantConfig) {
    let m = &p.motor;
    let _ = writeln!(
        t,
        "\ngain schedule of the motor plant (thrust ∝ speed², tau {:.0}/{:.0} ms up/down at \
         {:.0} rpm, dead time {:.0} ms, supply sag);\ntruth = the plant linearised at each \
         level; 'linear fit' = what an exact linear model of ± pulses would show:",
        m.tau_up_s * 1e3,
        m.tau_down_s * 1e3,
        p.rpm_at_reference,
        m.dead_time_s * 1e3
    );
    let _ = writeln!(
        t,
        "{:>8} {:>8} {:>8} {:>8} {:>8} | {:>7} {:>13} {:>7} | {:>7} {:>6} {:>6} | within",
        "throttle",
        "gain",
        "truth",
        "off",
        "lin.fit",
        "tau_ms",
        "truth up/dn",
        "lin.fit",
        "dead_ms",
        "truth",
        "fit",
    );
    for r in rows {
        let (tr, fit) = (&r.expected.truth, &r.expected.linear_fit);
        let off = 100.0 * truth::off(r.model.gain, tr.gain_n_per_throttle);
        let fit_off = 100.0 * (tr.pulse_gain_factor - 1.0);
        let _ = writeln!(
            t,
            "{:>8.3} {:>8.2} {:>8.2} {:>+7.1}% {:>+7.1}% | {:>7} {:>6.1}/{:<6.1} {:>7} | {:>7} \
             {:>6.1} {:>6} | {}",
            r.level,
            r.model.gain,
            tr.gain_n_per_throttle,
            off,
            fit_off,
            ms(r.model.tau_s),
            tr.tau_up_s * 1e3,
            tr.tau_down_s * 1e3,
            ms(fit.tau_s),
            ms(r.model.dead_time_s),
            tr.dead_time_s * 1e3,
            ms(fit.dead_time_s),
            if truth::within(&r.model, tr) {
                "yes"
            } else {
                "NO"
            }
        );
    }
    let dt_ms = rows
        .first()
        .map_or(f64::NAN, |r| r.expected.truth.dt_s * 1e3);
    let _ = writeln!(
        t,
        "spin-down is slower than spin-up: a linear model averages the two directions, so even \
         an exact fit is off the truth\nby 'lin.fit' (gain above the small-signal dT/du, tau \
         between tau_up and tau_down). The daemon's order-2 model holds one\nsample of dead \
         time: a longer one reads short.\ntolerance: gain within {:.0} % of the truth, tau \
         within [{:.1}·tau_up, {:.1}·tau_down], dead time within {:.1} ms ({} samples).",
        100.0 * GAIN_TOL,
        1.0 - TAU_TOL,
        1.0 + TAU_TOL,
        DEAD_TOL_SAMPLES * dt_ms,
        DEAD_TOL_SAMPLES
    );
}
