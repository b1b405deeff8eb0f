//! The run report of an experiment kind other than pulses (`propid run`/`replay --report
//! DIR`): the Markdown of `propid_kinds::report` and its figures (thrust curve, τ against
//! throttle, Bode plot), drawn with [`crate::plot::xy`]; the CLI writes the files.

use std::io;

use propid_kinds::report::{self, BODE_SVG, MARKDOWN, TAU_SVG, THRUST_SVG};
use propid_kinds::Published;

use crate::plot::xy::{svg, Panel, Series};

/// The report of a run of `kind` that published `published`: (file name, text) pairs, the
/// Markdown first, then each figure the run's lines can draw.
pub fn render(kind: &str, published: &[Published]) -> io::Result<Vec<(&'static str, String)>> {
    let mut files = vec![(MARKDOWN, report::markdown(kind, published))];
    let figs = report::figures(published);
    if figs.thrust {
        files.push((THRUST_SVG, thrust(published)?));
    }
    if figs.tau {
        files.push((TAU_SVG, tau(published)?));
    }
    if figs.bode {
        if let Some(text) = bode(published)? {
            files.push((BODE_SVG, text));
        }
    }
    Ok(files)
}

fn thrust(published: &[Published]) -> io::Result<String> {
    let mut series = Vec::new();
    for p in published {
        let Published::StaticMap(m) = p else { continue };
        if m.output != "thrust" {
            continue;
        }
        let label = m.leg.unwrap_or("levels");
        series.push(Series {
            label,
            points: m.map.levels.iter().map(|l| (l.throttle, l.mean)).collect(),
            line: false,
        });
        if let (Some(pw), None | Some("up")) = (&m.map.power, m.leg) {
            let offset = m.map.zero_offset.map_or(0.0, |z| z.value);
            let pts = (0..=100)
                .map(|k| k as f64 / 100.0)
                .filter(|&u| u >= pw.u0)
                .map(|u| (u, pw.predict(u) + offset))
                .collect();
            series.push(Series {
                label: "power law",
                points: pts,
                line: true,
            });
        }
    }
    let panel = Panel {
        title: "thrust against throttle",
        x_desc: "throttle",
        y_desc: "thrust (N)",
        log_x: false,
        series,
    };
    svg(&[panel])
}

fn tau(published: &[Published]) -> io::Result<String> {
    let pts = |dir: propid_numerics::step_response::Direction| {
        published
            .iter()
            .filter_map(|p| match p {
                Published::Step(s) if s.figures.direction == dir => {
                    s.figures.time_constant_s.map(|t| (s.figures.to, t * 1e3))
                }
                _ => None,
            })
            .collect()
    };
    use propid_numerics::step_response::Direction;
    let panel = Panel {
        title: "time constant against throttle (the step's end level)",
        x_desc: "throttle",
        y_desc: "τ (ms)",
        log_x: false,
        series: vec![
            Series {
                label: "steps up",
                points: pts(Direction::Up),
                line: false,
            },
            Series {
                label: "steps down",
                points: pts(Direction::Down),
                line: false,
            },
        ],
    };
    svg(&[panel])
}

fn bode(published: &[Published]) -> io::Result<Option<String>> {
    let Some(fr) = published.iter().find_map(|p| match p {
        Published::FrequencyResponse(f) => Some(f),
        _ => None,
    }) else {
        return Ok(None);
    };
    let r = &fr.response;
    let db = |g: f64| 20.0 * g.max(1e-300).log10();
    let bins = &r.bins;
    let mut gain = vec![Series {
        label: "H1",
        points: bins.iter().map(|b| (b.f_hz, db(b.gain))).collect(),
        line: true,
    }];
    let mut phase = vec![Series {
        label: "H1",
        points: bins.iter().map(|b| (b.f_hz, b.phase_deg)).collect(),
        line: true,
    }];
    if let Some(m) = &r.model {
        gain.push(Series {
            label: "fitted model",
            points: bins
                .iter()
                .map(|b| (b.f_hz, db(m.at(b.f_hz).norm())))
                .collect(),
            line: true,
        });
        // the model's phase unwrapped like the measurement's: continued bin to bin
        let mut last: Option<f64> = None;
        let pts = bins
            .iter()
            .map(|b| {
                let mut ph = m.at(b.f_hz).arg().to_degrees();
                if let Some(prev) = last {
                    ph += 360.0 * ((prev - ph) / 360.0).round();
                }
                last = Some(ph);
                (b.f_hz, ph)
            })
            .collect();
        phase.push(Series {
            label: "fitted model",
            points: pts,
            line: true,
        });
    }
    let coherence = vec![Series {
        label: "coherence",
        points: bins.iter().map(|b| (b.f_hz, b.coherence)).collect(),
        line: true,
    }];
    let panels = [
        Panel {
            title: "gain",
            x_desc: "frequency (Hz)",
            y_desc: "dB (N per unit throttle)",
            log_x: true,
            series: gain,
        },
        Panel {
            title: "phase",
            x_desc: "frequency (Hz)",
            y_desc: "degrees",
            log_x: true,
            series: phase,
        },
        Panel {
            title: "coherence",
            x_desc: "frequency (Hz)",
            y_desc: "γ²",
            log_x: true,
            series: coherence,
        },
    ];
    svg(&panels).map(Some)
}
