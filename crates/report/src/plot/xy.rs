//! A plain x–y chart as SVG: series of points or lines on linear or logarithmic axes (the
//! experiment kinds' run report: thrust curve, τ against throttle, Bode plot).

use std::io;

use plotters::coord::Shift;
use plotters::prelude::*;

/// One series.
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// Points (non-finite ones left out).
    pub points: Vec<(f64, f64)>,
    /// Drawn as a line (else as circles).
    pub line: bool,
}

/// One panel: axis titles, a log x axis or not, its series.
pub struct Panel<'a> {
    /// Caption.
    pub title: &'a str,
    /// x axis title.
    pub x_desc: &'a str,
    /// y axis title.
    pub y_desc: &'a str,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// The series.
    pub series: Vec<Series<'a>>,
}

fn to_io<E: std::fmt::Display>(e: E) -> io::Error {
    io::Error::other(e.to_string())
}

const COLORS: [RGBColor; 4] = [
    RGBColor(30, 90, 200),
    RGBColor(210, 40, 30),
    RGBColor(40, 150, 60),
    RGBColor(120, 120, 120),
];

fn range(v: impl Iterator<Item = f64> + Clone, log: bool) -> (f64, f64) {
    let v = v.filter(|x| x.is_finite() && (!log || *x > 0.0));
    let lo = v.clone().fold(f64::INFINITY, f64::min);
    let hi = v.fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 1.2, hi * 1.2)
    } else {
        let pad = ((hi - lo) * 0.05).max(1e-9);
        (lo - pad, hi + pad)
    }
}

fn draw(area: &DrawingArea<SVGBackend<'_>, Shift>, p: &Panel<'_>) -> io::Result<()> {
    let pts = || p.series.iter().flat_map(|s| s.points.iter().copied());
    let (x0, x1) = range(pts().map(|q| q.0), p.log_x);
    let (y0, y1) = range(pts().map(|q| q.1), false);
    let mut b = ChartBuilder::on(area);
    b.caption(p.title, ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(55);
    macro_rules! body {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(p.x_desc)
                .y_desc(p.y_desc)
                .draw()
                .map_err(to_io)?;
            for (i, s) in p.series.iter().enumerate() {
                let c = COLORS[i % COLORS.len()];
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|q| q.0.is_finite() && q.1.is_finite() && (!p.log_x || q.0 > 0.0))
                    .collect();
                if s.line {
                    chart
                        .draw_series(LineSeries::new(pts, c.stroke_width(2)))
                        .map_err(to_io)?
                        .label(s.label)
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c));
                } else {
                    chart
                        .draw_series(pts.into_iter().map(|q| Circle::new(q, 4, c.filled())))
                        .map_err(to_io)?
                        .label(s.label)
                        .legend(move |(x, y)| Circle::new((x + 8, y), 4, c.filled()));
                }
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(to_io)?;
        }};
    }
    if p.log_x {
        body!(b
            .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
            .map_err(to_io)?);
    } else {
        body!(b.build_cartesian_2d(x0..x1, y0..y1).map_err(to_io)?);
    }
    Ok(())
}

/// `panels` stacked one above the other, as SVG text.
pub fn svg(panels: &[Panel<'_>]) -> io::Result<String> {
    let h = 420 * panels.len().max(1) as u32;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (900, h)).into_drawing_area();
        root.fill(&WHITE).map_err(to_io)?;
        let areas = root.split_evenly((panels.len().max(1), 1));
        for (a, p) in areas.iter().zip(panels) {
            draw(a, p)?;
        }
        root.present().map_err(to_io)?;
    }
    Ok(text)
}
