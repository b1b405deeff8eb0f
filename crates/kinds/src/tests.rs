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
    let mut a = Analysis::new(&cfg).unwrap();
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
    let mut a = Analysis::new(&cfg).unwrap();
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
    let mut a = Analysis::new(&cfg).unwrap();
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
}

#[test]
fn pulses_have_no_analysis_here() {
    assert!(Analysis::new(&ExperimentConfig::default()).is_none());
}
