//! The run report of an experiment kind (`propid run`/`replay --report DIR`): the Markdown
//! of `propid_kinds::report`, the flight controllers' numbers from the thrust map
//! ([`propid_model::params::params`], the conversions `propid params` prints) and the figures
//! (thrust curve, τ against throttle, Bode plot, fn/ζ/τ of the models against the operating
//! point), drawn with [`crate::plot::xy`]; the CLI writes the files.

use std::fmt::Write as _;
use std::io;

use propid_kinds::report::{self, BODE_SVG, MARKDOWN, MODELS_SVG, TAU_SVG, THRUST_SVG};
use propid_kinds::{Material, Published};
use propid_model::params::{params, Options, Record, Target};

use crate::plot::xy::{svg, Panel, Series};

/// The targets whose thrust-curve numbers the report gives.
const TARGETS: [Target; 3] = [Target::Ardupilot, Target::Px4, Target::Betaflight];

/// The report of a run (`m`): (file name, text) pairs, the Markdown first, then each figure
/// the run's lines can draw.
pub fn render(m: &Material) -> io::Result<Vec<(&'static str, String)>> {
    let published = &m.published[..];
    let fc = flight_controller(published);
    let mut files = vec![(MARKDOWN, report::markdown(m, fc.as_deref()))];
    let figs = report::figures(m);
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
    if figs.models {
        files.push((MODELS_SVG, models(m)?));
    }
    Ok(files)
}

/// The flight controllers' thrust-curve numbers from the run's thrust map (a ramp's up leg:
/// the down leg carries the run's warming), as a Markdown section; `None` without a thrust
/// map.
pub fn flight_controller(published: &[Published]) -> Option<String> {
    let mut maps = serde_json::Map::new();
    let mut leg = "";
    for p in published {
        let Published::StaticMap(m) = p else { continue };
        if m.leg == Some("down") {
            continue;
        }
        if m.leg == Some("up") {
            leg = " (the ramp's up leg)";
        }
        maps.insert(m.output.into(), serde_json::to_value(&m.map).ok()?);
    }
    maps.get("thrust")?;
    let static_map = serde_json::Value::Object(maps);
    let rec = Record {
        stand: None,
        static_map: &static_map,
        supply: None,
    };
    let opts = Options::default();
    let mut out = String::from("\n### Flight-controller numbers\n\n");
    let _ = writeln!(
        out,
        "From the thrust map{leg}, by the conversions `propid params` prints (docs/params.md). \
         Normalisation: the stand's throttle 0..1 is the pulse {:.0}–{:.0} µs and the \
         controller's output range {:.0}–{:.0} µs (`propid params` on a saved model takes \
         `--pwm-min`, `--pwm-max`); each value's own normalisation is beside it.\n",
        opts.record_us[0], opts.record_us[1], opts.pwm[0], opts.pwm[1]
    );
    out.push_str("| target | parameter | value | normalisation |\n|---|---|---:|---|\n");
    for t in TARGETS {
        for p in params(t, &rec, &opts) {
            let value = p.value.map_or("refused".into(), |v| format!("{v:.4}"));
            let _ = writeln!(
                out,
                "| {} | `{}` | {} | {} |",
                t.as_str(),
                p.name,
                value,
                p.note.replace('|', "\\|")
            );
        }
    }
    Some(out)
}

/// fn, ζ and τ of the models against their operating points.
fn models(m: &Material) -> io::Result<String> {
    let pts = |f: &dyn Fn(&propid_kinds::ModelRow) -> Option<f64>| -> Vec<(f64, f64)> {
        m.models
            .iter()
            .filter_map(|r| {
                f(r).filter(|v| v.is_finite())
                    .map(|v| (r.operating_point, v))
            })
            .collect()
    };
    let panel = |title, y_desc, points| Panel {
        title,
        x_desc: "operating point (throttle)",
        y_desc,
        log_x: false,
        series: vec![Series {
            label: "models",
            points,
            line: false,
        }],
    };
    svg(&[
        panel("natural frequency", "fn (Hz)", pts(&|r| Some(r.fn_hz))),
        panel("damping ratio", "ζ", pts(&|r| Some(r.zeta))),
        panel(
            "time constant (longest real pole)",
            "τ (ms)",
            pts(&|r| r.tau_s.map(|t| t * 1e3)),
        ),
    ])
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
