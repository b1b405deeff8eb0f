//! SVG line charts and the Pareto chart of the walkthrough (`plotters`, SVG backend).

use std::path::Path;

use plotters::drawing::DrawingAreaErrorKind;
use plotters::prelude::*;

use super::WalkthroughError;

/// One curve of a line chart.
pub struct Series<'a> {
    /// Legend text.
    pub name: &'a str,
    /// Values at `t = k dt`.
    pub y: &'a [f64],
    /// Line colour.
    pub color: RGBColor,
    /// Draw dots instead of a line (for measurements).
    pub dots: bool,
}

/// A line chart of `series` against time `k dt`. The y range is fitted to `fit` (typically the
/// truth) with a margin; curves leaving it are clipped at the frame, so a diverging model shows
/// as a line running off the chart rather than squashing everything else.
pub fn lines(
    path: &Path,
    title: &str,
    y_label: &str,
    dt_s: f64,
    fit: &[&[f64]],
    series: &[Series<'_>],
) -> Result<(), WalkthroughError> {
    let len = series.iter().map(|s| s.y.len()).max().unwrap_or(0);
    let (lo, hi) = range(fit);
    let t_end = (len.max(2) - 1) as f64 * dt_s;
    let root = SVGBackend::new(path, (900, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..t_end, lo..hi)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc(y_label)
        .draw()
        .map_err(err)?;
    for s in series {
        let color = s.color;
        let pts =
            s.y.iter()
                .enumerate()
                .map(|(k, &y)| (k as f64 * dt_s, clip(y, lo, hi)));
        if s.dots {
            chart
                .draw_series(pts.map(|p| Circle::new(p, 2, color.filled())))
                .map_err(err)?
                .label(s.name)
                .legend(move |(x, y)| Circle::new((x + 10, y), 3, color.filled()));
        } else {
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                .map_err(err)?
                .label(s.name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

/// Pareto chart: the first `shown` singular values as bars (share of the sum of all, %) and
/// the cumulative share (%) as a line with dots.
pub fn pareto(
    path: &Path,
    title: &str,
    sigma: &[f64],
    shown: usize,
) -> Result<(), WalkthroughError> {
    let total: f64 = sigma.iter().sum();
    if !(total.is_finite() && total > 0.0) {
        return Err(WalkthroughError::NoSingularValues);
    }
    let shown = shown.min(sigma.len()).max(1);
    let root = SVGBackend::new(path, (900, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..shown as f64 + 0.5, 0.0..100.0)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("singular value index")
        .y_desc("share of Σσ (%)")
        .draw()
        .map_err(err)?;
    let orange = RGBColor(230, 120, 20);
    let blue = RGBColor(30, 90, 200);
    chart
        .draw_series(sigma[..shown].iter().enumerate().map(|(i, s)| {
            let x = i as f64 + 1.0;
            Rectangle::new(
                [(x - 0.35, 0.0), (x + 0.35, 100.0 * s / total)],
                orange.filled(),
            )
        }))
        .map_err(err)?
        .label("σ_i / Σσ")
        .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 12, y + 4)], orange.filled()));
    let mut acc = 0.0;
    let cumulative: Vec<(f64, f64)> = sigma[..shown]
        .iter()
        .enumerate()
        .map(|(i, s)| {
            acc += s;
            (i as f64 + 1.0, 100.0 * acc / total)
        })
        .collect();
    chart
        .draw_series(LineSeries::new(
            cumulative.iter().copied(),
            blue.stroke_width(2),
        ))
        .map_err(err)?
        .label("cumulative share")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], blue));
    chart
        .draw_series(cumulative.iter().map(|&p| Circle::new(p, 3, blue.filled())))
        .map_err(err)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::MiddleRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

/// y range of the curves in `fit` with 15 % margin (a unit range if they are flat or empty).
fn range(fit: &[&[f64]]) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for y in fit.iter().flat_map(|s| s.iter()).filter(|y| y.is_finite()) {
        lo = lo.min(*y);
        hi = hi.max(*y);
    }
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return (-1.0, 1.0);
    }
    let pad = 0.15 * (hi - lo);
    (lo - pad, hi + pad)
}

/// Keeps a value inside the frame (NaN goes to the bottom edge).
fn clip(y: f64, lo: f64, hi: f64) -> f64 {
    if y.is_nan() {
        lo
    } else {
        y.clamp(lo, hi)
    }
}

fn err(e: DrawingAreaErrorKind<std::io::Error>) -> WalkthroughError {
    WalkthroughError::Plot(e)
}
