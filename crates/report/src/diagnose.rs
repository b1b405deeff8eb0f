//! `propid diagnose --report DIR`: a Markdown page (`index.md`) with SVG plots (plotters):
//! measured output against the baseline and extended simulations, their residuals, the residual
//! spectra, the response against pulse amplitude, the Hankel singular values of the data's
//! Markov parameters (OKID, [`propid_numerics::okid::okid`]) and, when the identification
//! core gave the baseline an ERA start, the stabilization diagram of that start's Hankel SVD
//! ([`crate::plot::stabilization`]).

use std::fmt::Write as _;
use std::io;

use plotters::prelude::*;

use crate::plot::stabilization;
use propid_diagnose::result::{Diagnosis, Traces};
use propid_diagnose::spectrum::periodogram;
use propid_numerics::okid::{okid, OkidOptions};
use propid_numerics::segment::{self, Command, SegmentRules};

pub type Series<'a> = (&'a str, Vec<(f64, f64)>, RGBColor);

fn to_io<E: std::fmt::Display>(e: E) -> io::Error {
    io::Error::other(e.to_string())
}

/// `series` as lines (or points when `points`) in an SVG text (`None` without a finite point).
pub fn plot(
    title: &str,
    xl: &str,
    yl: &str,
    series: &[Series],
    log_y: bool,
    points: bool,
) -> io::Result<Option<String>> {
    let mut text = String::new();
    let drawn = draw(&mut text, title, xl, yl, series, log_y, points)?;
    Ok(drawn.then_some(text))
}

/// [`plot`] into `text`; false when there is nothing to draw.
fn draw(
    text: &mut String,
    title: &str,
    xl: &str,
    yl: &str,
    series: &[Series],
    log_y: bool,
    points: bool,
) -> io::Result<bool> {
    let pts = series
        .iter()
        .flat_map(|s| s.1.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite() && (!log_y || p.1 > 0.0));
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in pts {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1);
        y1 = y1.max(p.1);
    }
    if !(x0.is_finite() && y0.is_finite()) {
        return Ok(false);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1.0;
    }
    let root = SVGBackend::with_string(text, (900, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(to_io)?;
    let mut b = ChartBuilder::on(&root);
    b.caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70);
    macro_rules! draw {
        ($chart:expr) => {{
            let mut c = $chart;
            c.configure_mesh()
                .x_desc(xl)
                .y_desc(yl)
                .draw()
                .map_err(to_io)?;
            for (name, data, color) in series {
                let color = *color;
                let data = data
                    .iter()
                    .copied()
                    .filter(|p| p.0.is_finite() && p.1.is_finite() && (!log_y || p.1 > 0.0));
                if points {
                    c.draw_series(data.map(|p| Circle::new(p, 3, color.filled())))
                        .map_err(to_io)?
                        .label(*name)
                        .legend(move |(x, y)| Circle::new((x + 8, y), 3, color.filled()));
                } else {
                    c.draw_series(LineSeries::new(data, &color))
                        .map_err(to_io)?
                        .label(*name)
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
                }
            }
            c.configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(to_io)?;
        }};
    }
    if log_y {
        draw!(b
            .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
            .map_err(to_io)?);
    } else {
        let pad = 0.05 * (y1 - y0);
        draw!(b
            .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
            .map_err(to_io)?);
    }
    root.present().map_err(to_io)?;
    Ok(true)
}

fn time_series(t: &Traces, v: &[f64], range: std::ops::Range<usize>) -> Vec<(f64, f64)> {
    range.map(|k| (k as f64 * t.dt_s, v[k])).collect()
}

/// Pulses in the input ([`segment::pulses`] under the diagnosis' `rules`). Returns `(start,
/// amplitude)`.
pub fn find_pulses(u: &[f64], rules: &SegmentRules) -> Vec<(usize, f64)> {
    segment::pulses(Command::new(u), rules)
        .map(|p| (p.start, p.amplitude))
        .collect()
}

/// Peak signed deviation of `y` from its mean over the 10 samples before `start`, within
/// `window` samples from `start`.
fn pulse_response(y: &[f64], start: usize, window: usize) -> f64 {
    if start < 10 || start + window > y.len() {
        return f64::NAN;
    }
    let base = y[start - 10..start].iter().sum::<f64>() / 10.0;
    y[start..start + window]
        .iter()
        .map(|v| v - base)
        .fold(0.0, |m: f64, d| if d.abs() > m.abs() { d } else { m })
}

/// Hankel singular values of the Markov parameters that OKID recovers from the record.
pub fn hankel_singular_values(t: &Traces) -> Vec<f64> {
    let miss: Vec<bool> = t.y.iter().map(|v| !v.is_finite()).collect();
    let Ok(r) = okid(&[&t.u], &[&t.y], Some(&miss), &OkidOptions::default()) else {
        return Vec::new();
    };
    let blocks = (r.len.saturating_sub(1) / 2).min(25);
    if blocks < 2 || r.q != 1 || r.p != 1 {
        return Vec::new();
    }
    let h = nalgebra::DMatrix::from_fn(blocks, blocks, |a, b| r.markov[a + b + 1]);
    let mut s: Vec<f64> = h.singular_values().iter().copied().collect();
    s.sort_by(|a, b| b.total_cmp(a));
    s
}

/// The report's files: the SVG plots (a plot without a finite point left out) and
/// `index.md`, by file name, in the order they are written.
pub fn render(title: &str, output: &str, d: &Diagnosis) -> io::Result<Vec<(&'static str, String)>> {
    let mut files = Vec::new();
    let mut add = |name: &'static str, svg: Option<String>| {
        if let Some(svg) = svg {
            files.push((name, svg));
        }
    };
    let t = &d.traces;
    let n = t.y.len();
    let val = d.split.validation[0]..d.split.validation[1].min(n);
    let ext_name = if d.extended.is_some() {
        "extended"
    } else {
        "extended (= baseline)"
    };
    let (blue, red, green) = (
        RGBColor(30, 90, 200),
        RGBColor(210, 50, 40),
        RGBColor(20, 150, 60),
    );
    add(
        "fit.svg",
        plot(
            "validation part: measured, baseline, extended",
            "time (s)",
            output,
            &[
                ("measured", time_series(t, &t.y, val.clone()), BLACK),
                ("baseline", time_series(t, &t.baseline, val.clone()), red),
                (ext_name, time_series(t, &t.extended, val.clone()), blue),
            ],
            false,
            false,
        )?,
    );
    let res = |sim: &[f64]| -> Vec<f64> { t.y.iter().zip(sim).map(|(a, b)| a - b).collect() };
    let (rb, re) = (res(&t.baseline), res(&t.extended));
    add(
        "residuals.svg",
        plot(
            "residuals (measured − simulated), whole record",
            "time (s)",
            output,
            &[
                ("baseline", time_series(t, &rb, 0..n), red),
                ("extended", time_series(t, &re, 0..n), blue),
            ],
            false,
            false,
        )?,
    );
    let spec = |r: &[f64]| {
        let (f, p) = periodogram(r, t.dt_s);
        f.into_iter().zip(p).skip(1).collect::<Vec<_>>()
    };
    add(
        "spectrum.svg",
        plot(
            "residual spectrum (Hann periodogram)",
            "frequency (Hz)",
            "power",
            &[("baseline", spec(&rb), red), ("extended", spec(&re), blue)],
            true,
            false,
        )?,
    );
    let window = ((0.3 / t.dt_s).round() as usize).max(5);
    let pulses = find_pulses(&t.u, &t.rules);
    let resp = |y: &[f64]| {
        pulses
            .iter()
            .map(|&(k, a)| (a, pulse_response(y, k, window)))
            .collect::<Vec<_>>()
    };
    add(
        "pulses.svg",
        plot(
            "peak response against pulse amplitude",
            "pulse amplitude (throttle)",
            output,
            &[
                ("measured", resp(&t.y), BLACK),
                ("baseline", resp(&t.baseline), red),
                (ext_name, resp(&t.extended), green),
            ],
            false,
            true,
        )?,
    );
    let sv = hankel_singular_values(t);
    let svp: Vec<(f64, f64)> = sv
        .iter()
        .enumerate()
        .map(|(i, s)| ((i + 1) as f64, *s))
        .collect();
    add(
        "singular_values.svg",
        plot(
            "Hankel singular values (OKID Markov parameters)",
            "index",
            "singular value",
            &[("σ", svp, blue)],
            true,
            true,
        )?,
    );
    let mut md = markdown(title, d, pulses.len(), &sv);
    if let Some((s, fn_hz, zeta)) = &t.stabilization {
        let caption = "stabilization diagram of the identification core's ERA start";
        add("stabilization.svg", Some(stabilization::svg(caption, s)?));
        md.push_str("\nThe identification core's ERA start (estimation part). ");
        md.push_str(&stabilization::markdown(
            s,
            *fn_hz,
            *zeta,
            "stabilization.svg",
        ));
    }
    files.push(("index.md", md));
    Ok(files)
}

fn markdown(title: &str, d: &Diagnosis, pulses: usize, sv: &[f64]) -> String {
    let mut s = String::new();
    let b = &d.baseline;
    let _ = writeln!(s, "# propid diagnose: {title}\n");
    let _ = writeln!(s, "Validation: {}.\n", d.validation.describe(&d.split));
    let _ = writeln!(
        s,
        "**Baseline** (2nd order, output-error fit): fn = {:.3} Hz, ζ = {:.3}, DC gain = {:.4}; validation fit **{:.2} %**.\n",
        b.model.report.fn_hz,
        b.model.report.zeta,
        b.model.report.dc_gain.get(0),
        b.fit_percent
    );
    if let Some(c) = &b.core_model {
        let _ = writeln!(
            s,
            "Identification core ({:?} path): fn = {:.3} Hz, ζ = {:.3}, DC gain = {:.4}; validation fit {:.2} %.\n",
            c.path, c.fn_hz, c.zeta, c.dc_gain, c.fit_percent
        );
    }
    if d.findings.is_empty() {
        let _ = writeln!(
            s,
            "**No effect found**: the 2nd-order model explains the data down to the noise.\n"
        );
    } else {
        let _ = writeln!(
            s,
            "| effect | score | parameters | evidence |\n|---|---|---|---|"
        );
        for f in &d.findings {
            let params: Vec<String> = f.params.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            let _ = writeln!(
                s,
                "| `{}` | {:.0} | {} | {} |",
                f.effect,
                f.score,
                params.join(", "),
                f.evidence
            );
        }
        if let (Some(e), Some(g)) = (&d.extended, &d.gain) {
            let _ = writeln!(
                s,
                "\n**Extended** by {}: validation fit **{:.2} %** ({:+.2} points; residual RMS × {:.3}).\n",
                e.effects.iter().map(|e| e.as_str()).collect::<Vec<_>>().join(", "),
                e.fit_percent,
                g.fit_percent_points,
                g.rms_ratio
            );
        }
    }
    let _ = writeln!(
        s,
        "![fit](fit.svg)\n\n![residuals](residuals.svg)\n\n![spectrum](spectrum.svg)\n"
    );
    let _ = writeln!(s, "Response against pulse amplitude ({pulses} pulses found in the input; a linear model gives a straight line through 0):\n\n![pulses](pulses.svg)\n");
    let shown: Vec<String> = sv.iter().take(6).map(|v| format!("{v:.4e}")).collect();
    let _ = writeln!(
        s,
        "Hankel singular values (leading: {}):\n\n![singular values](singular_values.svg)",
        shown.join(", ")
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pulses_are_found_with_sign_and_steps_are_not_pulses() {
        let mut u = vec![0.5; 400];
        u[50..55].iter_mut().for_each(|v| *v = 0.6);
        u[100] = 0.45;
        u[200..].iter_mut().for_each(|v| *v = 0.7); // a step, never returns
        let p = find_pulses(&u, &SegmentRules::DEFAULT.at_rate(0.001));
        assert_eq!(p.len(), 2, "{p:?}");
        // At 10 Hz a run of five samples is half a second: a level, no pulse.
        assert_eq!(
            find_pulses(&u, &SegmentRules::DEFAULT.at_rate(0.1)).len(),
            1
        );
        assert_eq!(p[0].0, 50);
        assert!((p[0].1 - 0.1).abs() < 1e-12);
        assert_eq!(p[1].0, 100);
        assert!((p[1].1 + 0.05).abs() < 1e-12);
    }
}
