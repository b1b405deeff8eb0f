//! The daemon at 20 kHz (issue 12 item 6): the default windows held 3.3 pulse spacings, so
//! every window filled before its K pulses and was discarded (`window_full`), and the Hankel
//! matrix spanned 12.8 ms of a 100 ms response. Windows are now sized from the plan at the
//! fastest rate and the Hankel spans the whole response: the same 1 ms pulses identify the
//! plant at 20 kHz at least as well as at 1 kHz.

use propid_sim::SimConfig;
use serde_json::Value;
use std::process::Command;

use crate::daemon_proc::{of_type, stats, BIN};

/// The lines `propid replay` publishes for the simulated stand's recording of `cfg`.
fn replay(cfg: &SimConfig) -> Vec<Value> {
    let mut bytes = Vec::new();
    let sum = propid_sim::record::record(cfg, 30.0, &mut bytes).unwrap();
    assert!(sum.finished, "{sum:?}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.tsp");
    std::fs::write(&path, bytes).unwrap();
    let out = Command::new(BIN).arg("replay").arg(&path).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The default stand and plan at `rate` Hz with pulses `width` samples wide, two levels of 8
/// pulses (4 models at K = 4).
fn stand(rate: u32, width: u32, seed: u64) -> SimConfig {
    let mut cfg = SimConfig::default();
    cfg.stand.sample_rate_hz = rate;
    cfg.stand.seed = seed;
    cfg.experiment.levels = vec![0.35, 0.55];
    cfg.experiment.pulses_per_level = 8;
    cfg.experiment.pulse_width_samples = width;
    cfg
}

fn window_full(lines: &[Value]) -> usize {
    lines.iter().filter(|l| l["kind"] == "window_full").count()
}

#[test]
fn one_ms_pulses_at_20_khz_identify_as_well_as_at_1_khz() {
    let keys = ["fn_hz", "zeta", "dc_gain"];
    // sum of squared relative errors per key, and models, at 1 kHz and 20 kHz
    let mut sq = [[0.0; 3]; 2];
    let mut count = [0usize; 2];
    for seed in 1..=3 {
        for (i, (rate, width)) in [(1_000, 1), (20_000, 20)].into_iter().enumerate() {
            let cfg = stand(rate, width, seed);
            let lines = replay(&cfg);
            assert_eq!(window_full(&lines), 0, "{rate} Hz");
            let models = of_type(&lines, "model");
            assert_eq!(models.len(), 4, "{rate} Hz seed {seed}: {lines:#?}");
            assert_eq!(stats(&lines)["models"], 4);
            let p = &cfg.plant;
            for m in &models {
                for (k, (key, truth)) in keys
                    .into_iter()
                    .zip([p.fn_hz, p.zeta, p.gain_n_per_throttle])
                    .enumerate()
                {
                    let est = m[key].as_f64().unwrap();
                    let sd = m["uncertainty"][key].as_f64().unwrap();
                    // at 20 kHz each model also knows its own error (at 1 kHz the jackknife of
                    // 4 one-sample pulses can be overconfident: fn 13.8 ± 0.3 Hz for 12 Hz)
                    assert!(
                        rate == 1_000 || (est - truth).abs() < 4.0 * sd + 0.02 * truth,
                        "{rate} Hz: {key} {est} ± {sd} vs {truth}"
                    );
                    sq[i][k] += ((est - truth) / truth).powi(2);
                }
            }
            count[i] += models.len();
        }
    }
    for (k, key) in keys.iter().enumerate() {
        let rms = |i: usize| (sq[i][k] / count[i] as f64).sqrt();
        eprintln!(
            "{key}: rms relative error 1 kHz {:.4}, 20 kHz {:.4}",
            rms(0),
            rms(1)
        );
        assert!(
            rms(1) <= 1.25 * rms(0) + 0.005,
            "{key}: {} vs {}",
            rms(1),
            rms(0)
        );
    }
}

#[test]
fn one_sample_pulses_at_20_khz_fill_no_window() {
    // the plan's defaults at 20 kHz: 50 µs pulses carry a twentieth of the energy of 1 kHz
    // ones. Every window is identified or refused on its data (never discarded as full), and
    // nothing unstable is published as a model.
    let lines = replay(&stand(20_000, 1, 1));
    assert_eq!(window_full(&lines), 0);
    let s = stats(&lines);
    let judged = s["models"].as_u64().unwrap()
        + s["models_unreliable"].as_u64().unwrap()
        + lines
            .iter()
            .filter(|l| l["kind"] == "identification_failed")
            .count() as u64;
    assert_eq!(judged, 4, "{lines:#?}");
    for m in of_type(&lines, "model") {
        for p in m["poles_s"].as_array().unwrap() {
            assert!(p[0].as_f64().unwrap() < 0.0, "{m}");
        }
    }
}
