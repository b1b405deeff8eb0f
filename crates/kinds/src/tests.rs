use super::*;
use propid_wire::experiment::program::program;

/// The samples of `cfg`'s program at 1 kHz through a plant: the throttle the device would
/// apply (each set-point ramped to over its `ramp_ms`), `plant` stepping the thrust.
fn run(cfg: &ExperimentConfig, mut plant: impl FnMut(f64) -> f64) -> Vec<Sample> {
    let (prog, end_ms) = program(cfg);
    let mut out = Vec::new();
    let (mut from, mut to, mut t_set, mut ramp) = (0.0, 0.0, 0u64, 0u64);
    let mut next = 0;
    for ms in 0..end_ms + 500 {
        while next < prog.len() && prog[next].at_ms <= ms {
            from = if ramp == 0 || ms >= t_set + ramp {
                to
            } else {
                from + (to - from) * (ms - t_set) as f64 / ramp as f64
            };
            to = prog[next].level;
            t_set = ms;
            ramp = prog[next].ramp_ms as u64;
            next += 1;
        }
        let u = if ramp == 0 || ms >= t_set + ramp {
            to
        } else {
            from + (to - from) * (ms - t_set) as f64 / ramp as f64
        };
        let u = (u * 10_000.0).round() / 10_000.0;
        out.push(Sample {
            index: ms,
            t_us: ms * 1000,
            throttle: u,
            thrust: plant(u),
            rpm: f64::NAN,
            current: f64::NAN,
        });
    }
    out
}

/// Static thrust of the test stand: 12 N·u².
fn steady(u: f64) -> f64 {
    12.0 * u * u
}

/// A first-order lag of `tau` s at 1 kHz towards `steady`, with deterministic noise.
fn first_order(tau: f64, noise: f64) -> impl FnMut(f64) -> f64 {
    let (mut y, mut k) = (0.0, 0u64);
    move |u| {
        y += (steady(u) - y) * (1e-3 / tau);
        k += 1;
        // a zero-mean pseudo-random ±noise (a fixed sequence)
        let r = ((k.wrapping_mul(2654435761) % 1000) as f64 / 999.0 - 0.5) * 2.0;
        y + noise * r
    }
}

#[test]
fn a_staircase_publishes_each_step_as_it_comes_and_the_static_map_at_the_end() {
    let cfg = ExperimentConfig {
        kind: Kind::Staircase,
        levels: vec![0.3, 0.45, 0.6],
        hold_ms: 1500,
        ..ExperimentConfig::default()
    };
    let mut a = Analysis::new(&cfg);
    let mut steps = Vec::new();
    let samples = run(&cfg, first_order(0.05, 0.02));
    for s in samples {
        for p in a.push(s) {
            match p {
                Published::Step(st) => steps.push((s.index, st)),
                other => panic!("{other:?} before the end"),
            }
        }
    }
    // the record starts at the first level: steps 0.3→0.45→0.6→0.45→0.3, the first three
    // each published as the next one starts
    assert_eq!(steps.len(), 3, "{steps:?}");
    for (k, (at, _)) in steps.iter().enumerate() {
        assert_eq!(*at, 1500 * (k as u64 + 2), "step {k}");
    }
    let fin = a.finish();
    let last_steps = fin
        .iter()
        .filter(|p| matches!(p, Published::Step(_)))
        .count();
    assert_eq!(last_steps, 1);
    let map = fin
        .iter()
        .find_map(|p| match p {
            Published::StaticMap(m) if m.output == "thrust" => Some(m),
            _ => None,
        })
        .unwrap();
    assert_eq!(map.map.levels.len(), 5);
    for l in &map.map.levels {
        let want = steady(l.throttle);
        assert!((l.mean - want).abs() < 0.01 * want, "{l:?} for {want}");
    }
    // τ per step within 10 % of 50 ms, both directions
    let taus: Vec<f64> = steps
        .iter()
        .filter_map(|(_, s)| s.figures.time_constant_s)
        .collect();
    assert!(taus.len() >= 3, "{steps:?}");
    assert!(taus.iter().all(|t| (t - 0.05).abs() < 0.005), "{taus:?}");
    assert!(map.directions.contains_key("up") && map.directions.contains_key("down"));
    assert_eq!(a.published().len(), 4 + 1);
}

#[test]
fn a_ramp_reports_each_leg_and_their_hysteresis() {
    let cfg = ExperimentConfig {
        kind: Kind::Ramp,
        levels: vec![0.2, 0.7],
        ramp_rate_per_s: 0.05,
        hold_ms: 1000,
        ..ExperimentConfig::default()
    };
    let mut a = Analysis::new(&cfg);
    // a stand whose thrust reads 0.1 N less once it has been to the top (a creeping cell)
    let mut been_top = false;
    let mut lag = first_order(0.02, 0.0);
    for s in run(&cfg, |u| {
        been_top |= u >= 0.7;
        lag(u) - if been_top { 0.1 } else { 0.0 }
    }) {
        assert!(a.push(s).is_empty());
    }
    let fin = a.finish();
    let legs: Vec<&StaticMapLine> = fin
        .iter()
        .filter_map(|p| match p {
            Published::StaticMap(m) => Some(m),
            _ => None,
        })
        .collect();
    assert_eq!(legs.len(), 2);
    assert_eq!((legs[0].leg, legs[1].leg), (Some("up"), Some("down")));
    assert!(legs[0].map.levels.len() >= 3, "{:?}", legs[0].map.levels);
    let h = legs[1].hysteresis.unwrap();
    assert!((h.mean + 0.1).abs() < 0.03, "{h:?}");
}

#[test]
fn a_chirp_through_a_resonant_stand_finds_its_peak_within_ten_per_cent() {
    let cfg = ExperimentConfig {
        kind: Kind::Chirp,
        levels: vec![0.5],
        chirp_f0_hz: 1.0,
        chirp_f1_hz: 20.0,
        chirp_amplitude: 0.05,
        chirp_s: 20.0,
        ..ExperimentConfig::default()
    };
    let mut a = Analysis::new(&cfg);
    let (fn_hz, zeta, k) = (8.0, 0.15, 12.0);
    let wn = std::f64::consts::TAU * fn_hz;
    let (mut x, mut v) = (k * 0.0, 0.0);
    for s in run(&cfg, |u| {
        for _ in 0..10 {
            let h = 1e-4;
            v += h * (wn * wn * (k * u - x) - 2.0 * zeta * wn * v);
            x += h * v;
        }
        x
    }) {
        a.push(s);
    }
    let fin = a.finish();
    let Some(Published::FrequencyResponse(fr)) = fin.first() else {
        panic!("{fin:?}")
    };
    let want = fn_hz * (1.0 - 2.0 * zeta * zeta).sqrt();
    let peak = fr.response.peak_hz.unwrap();
    assert!((peak - want).abs() < 0.1 * want, "peak {peak} for {want}");
    let m = fr.response.model.unwrap();
    assert!((m.natural_hz - fn_hz).abs() < 0.1 * fn_hz, "{m:?}");
    // the fitted model is published as a model line of its own, the pulse model's fields
    let Some(Published::Model(ml)) = fin.get(1) else {
        panic!("{fin:?}")
    };
    assert_eq!(
        (ml.path, ml.reason, ml.output),
        ("frequency_response", "end", "thrust")
    );
    assert_eq!((ml.report.fn_hz, ml.report.zeta), (m.natural_hz, m.damping));
    assert_eq!(ml.report.dt_s, fr.dt_s);
    assert_eq!(ml.operating_point, fr.level);
    assert!(
        ml.samples > 1000 && ml.t_s > 0.0,
        "{} {}",
        ml.samples,
        ml.t_s
    );
    let v = serde_json::to_value(ml).unwrap();
    for key in [
        "operating_point",
        "level",
        "t_s",
        "fn_hz",
        "zeta",
        "dc_gain",
        "a",
        "poles_s",
    ] {
        assert!(v.get(key).is_some(), "{key} in {v}");
    }
}

#[test]
fn pulses_publish_nothing_here_and_keep_their_thrust_curve_for_the_report() {
    let cfg = ExperimentConfig {
        levels: vec![0.3, 0.5, 0.7],
        settle_ms: 50,
        ..ExperimentConfig::default()
    };
    let mut a = Analysis::new(&cfg);
    let mut k = 0u64;
    for &u in &cfg.levels {
        for _ in 0..500 {
            let s = Sample {
                index: k,
                t_us: k * 1000,
                throttle: u,
                thrust: steady(u),
                rpm: f64::NAN,
                current: f64::NAN,
            };
            assert!(a.push(s).is_empty());
            k += 1;
        }
    }
    assert!(a.finish().is_empty(), "a pulses run publishes no map");
    let m = a.into_material();
    let [Published::StaticMap(map)] = &m.published[..] else {
        panic!("{:?}", m.published)
    };
    assert_eq!(
        (map.kind, map.output, map.map.levels.len()),
        (Kind::Pulses, "thrust", 3)
    );
    assert!((map.map.levels[1].mean - steady(0.5)).abs() < 1e-12);
    // 500 samples, less 50 ms settling, less the 2 samples before a new level counts as
    // reached (pulse_width_samples + 2 in a row)
    assert_eq!(map.map.levels[1].samples, 448);
}

/// The staircase's step lines as the whole record gives them: at each new step, the figures
/// of every step of the record so far ([`stand_figures`]), those not yet published; at the end
/// the last one.
fn whole_record_steps(samples: &[Sample]) -> Vec<StepFigures> {
    let (mut u, mut y, mut out) = (Vec::new(), Vec::new(), Vec::new());
    let publish = |u: &[f64], y: &[f64], last_t: u64, out: &mut Vec<StepFigures>| {
        let dt = (last_t - samples[0].t_us) as f64 * 1e-6 / (u.len() - 1) as f64;
        let rules = SegmentRules::for_record(dt, true);
        let figs = stand_figures(Command::new(u), dt, &rules, y, &[]);
        let new: Vec<StepFigures> = figs.steps.into_iter().skip(out.len()).collect();
        out.extend(new);
    };
    for s in samples {
        // the period as the analysis measures it: the new sample's time over the samples
        // before it
        if u.last()
            .is_some_and(|p: &f64| (s.throttle - p).abs() > STEP_CHANGE)
        {
            publish(&u, &y, s.t_us, &mut out);
        }
        u.push(s.throttle);
        y.push(s.thrust);
    }
    publish(&u, &y, samples[samples.len() - 1].t_us, &mut out);
    out
}

#[test]
fn the_steps_looked_for_from_the_last_one_are_the_whole_records() {
    let cfg = ExperimentConfig {
        kind: Kind::Staircase,
        levels: vec![0.2, 0.35, 0.5, 0.65, 0.8],
        hold_ms: 700,
        ..ExperimentConfig::default()
    };
    let mut samples = run(&cfg, first_order(0.03, 0.05));
    // a device clock with jitter: the period the analysis measures moves as the record grows
    for s in &mut samples {
        s.t_us += s.index * 7919 % 300;
    }
    let want = whole_record_steps(&samples);
    assert_eq!(want.len(), 8, "{want:?}");
    let mut a = Analysis::new(&cfg);
    let mut got = Vec::new();
    for &s in &samples {
        got.extend(a.push(s));
    }
    got.extend(a.finish());
    let got: Vec<StepFigures> = got
        .into_iter()
        .filter_map(|p| match p {
            Published::Step(s) => Some(s.figures),
            _ => None,
        })
        .collect();
    assert_eq!(got, want);
}
