//! The stabilization diagram as an SVG text ([`svg`]) and in words ([`summary_line`], [`markdown`]):
//! pole frequency on a log x axis, model order on the y axis, one circle per pole entry of
//! [`Stabilization`] (filled: stable against the next order, hollow: not), the published
//! model's row in red. Frequencies below the axis' lower end (slow real poles, `fn` ≈ 0) sit
//! on its left edge.

use std::fmt::Write as _;
use std::io;

use plotters::prelude::*;
use propid_numerics::stabilization::Stabilization;

/// Width of the log frequency axis at most, decades.
const DECADES: f64 = 4.0;

fn to_io<E: std::fmt::Display>(e: E) -> io::Error {
    io::Error::other(e.to_string())
}

/// The frequency axis `(lo, hi)`, Hz: from the decade below the slowest positive pole (at most
/// [`DECADES`] below the fastest) to 10 % above the fastest.
fn freq_range(s: &Stabilization) -> (f64, f64) {
    let f = s.orders.iter().flat_map(|o| &o.poles).map(|p| p.fn_hz);
    let hi = f.clone().fold(0.0f64, f64::max).max(1e-3) * 1.1;
    let min_pos = f.filter(|v| *v > 0.0).fold(f64::INFINITY, f64::min);
    let floor = hi / 10f64.powf(DECADES);
    let lo = if min_pos.is_finite() {
        10f64.powf(min_pos.log10().floor()).max(floor)
    } else {
        floor
    };
    (lo, hi)
}

/// The diagram of `s` as an SVG text: one `<circle>` per pole entry, nothing else drawn as a
/// circle.
pub fn svg(title: &str, s: &Stabilization) -> io::Result<String> {
    let mut text = String::new();
    draw(&mut text, title, s)?;
    Ok(text)
}

fn draw(text: &mut String, title: &str, s: &Stabilization) -> io::Result<()> {
    let (lo, hi) = freq_range(s);
    let top = s.n_max.max(1) as f64 + 0.5;
    let root = SVGBackend::with_string(text, (900, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(to_io)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(50)
        .build_cartesian_2d((lo..hi).log_scale(), 0.5..top)
        .map_err(to_io)?;
    chart
        .configure_mesh()
        .x_desc("pole frequency fn (Hz)")
        .y_desc("model order")
        .y_labels(s.n_max.clamp(2, 30))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .draw()
        .map_err(to_io)?;
    let (grey, red) = (RGBColor(40, 40, 40), RGBColor(210, 40, 30));
    for o in &s.orders {
        let model = o.order == s.model_order;
        let (color, r) = if model { (red, 5) } else { (grey, 4) };
        let pts = o.poles.iter().map(|p| {
            let x = p.fn_hz.clamp(lo, hi);
            let style = if p.stable {
                color.filled()
            } else {
                color.stroke_width(1)
            };
            Circle::new((x, o.order as f64), r, style)
        });
        chart.draw_series(pts).map_err(to_io)?;
    }
    root.present().map_err(to_io)
}

/// `2-5, 7, 9-12`.
fn ranges(orders: &[usize]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < orders.len() {
        let mut j = i;
        while j + 1 < orders.len() && orders[j + 1] == orders[j] + 1 {
            j += 1;
        }
        out.push(if j > i {
            format!("{}-{}", orders[i], orders[j])
        } else {
            orders[i].to_string()
        });
        i = j + 1;
    }
    out.join(", ")
}

/// The pole the summary follows: the model's `(fn, ζ)` when it has a pair, else the first
/// entry of the model's row.
fn reference(s: &Stabilization, fn_hz: f64, zeta: f64) -> Option<(f64, f64)> {
    if fn_hz.is_finite() && zeta.is_finite() {
        return Some((fn_hz, zeta));
    }
    let row = s.orders.iter().find(|o| o.order == s.model_order)?;
    row.poles.first().map(|p| (p.fn_hz, p.zeta))
}

/// One line: in how many of the orders a stable pole lies within the criteria of the model's
/// `(fn, ζ)`, and which.
pub fn summary_line(s: &Stabilization, fn_hz: f64, zeta: f64) -> String {
    let Some((f, z)) = reference(s, fn_hz, zeta) else {
        return format!("no pole in the model's row (orders 1..{})", s.n_max);
    };
    let near = s.stable_orders_near(f, z);
    let c = &s.criteria;
    let which = if near.is_empty() {
        String::new()
    } else {
        format!(": {}", ranges(&near))
    };
    format!(
        "{} of {} orders have a stable pole within {} % / {} % of fn {f:.4} Hz, zeta {z:.4}{which}",
        near.len(),
        s.orders.len(),
        c.freq_rel * 100.0,
        c.zeta_rel * 100.0,
    )
}

/// A Markdown paragraph about the diagram and its image `file`.
pub fn markdown(s: &Stabilization, fn_hz: f64, zeta: f64, file: &str) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "Stabilization diagram: the poles of the models of orders 1..{} realised from the \
         model's own Hankel SVD (truncated at each order), one circle per complex pair or real \
         pole; **filled** = stable (the next order has a pole within {} % in frequency and {} % \
         in damping, both of positive damping), hollow = not; red = the model's order ({}). \
         Physical modes form vertical columns of filled circles; noise poles scatter.\n",
        s.n_max,
        s.criteria.freq_rel * 100.0,
        s.criteria.zeta_rel * 100.0,
        s.model_order
    );
    let _ = writeln!(o, "{}.\n", summary_line(s, fn_hz, zeta));
    let sv: Vec<String> = s
        .singular_values
        .iter()
        .map(|v| format!("{v:.4e}"))
        .collect();
    let _ = writeln!(o, "Singular values σ1..σ{}: {}.\n", s.n_max, sv.join(", "));
    let _ = writeln!(o, "![stabilization diagram]({file})");
    o
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_numerics::stabilization::{Criteria, StabOrder, StabPole};

    fn diagram() -> Stabilization {
        let p = |fn_hz, zeta, stable| StabPole {
            fn_hz,
            zeta,
            stable,
        };
        Stabilization {
            n_max: 3,
            model_order: 2,
            criteria: Criteria::USUAL,
            orders: vec![
                StabOrder {
                    order: 1,
                    poles: vec![p(0.0, 1.0, false)],
                },
                StabOrder {
                    order: 2,
                    poles: vec![p(10.0, 0.2, true)],
                },
                StabOrder {
                    order: 3,
                    poles: vec![p(10.01, 0.2, true), p(300.0, 0.01, false)],
                },
            ],
            singular_values: vec![3.0, 1.0, 0.01],
        }
    }

    #[test]
    fn one_circle_per_pole_and_a_summary() {
        let s = diagram();
        let text = svg("test", &s).unwrap();
        assert!(text.trim_start().starts_with("<svg"), "{}", &text[..40]);
        assert_eq!(text.matches("<circle").count(), 4);
        let line = summary_line(&s, 10.0, 0.2);
        assert!(
            line.starts_with("2 of 3 orders have a stable pole"),
            "{line}"
        );
        assert!(line.ends_with(": 2-3"), "{line}");
        assert_eq!(ranges(&[2, 3, 4, 6, 8, 9]), "2-4, 6, 8-9");
    }
}
