use super::*;
use crate::identify::{identify_okid, AnyInput};
use crate::okid::OkidOptions;
use crate::quality::judge_gain;
use crate::segment::{Command, SegmentRules};
use crate::stand::steady_levels;
use crate::static_map::level_slope;
use crate::workspace::IdentOptions;
use propid_testkit::{add_noise, Plant};

/// A staircase at 50 Hz, 300 samples per level, through the hardening static map
/// `T = 10·u³` and then a slow overdamped 2nd-order lag (`fn` Hz, ζ 2, unit gain), from steady
/// state, with white noise `sd` N (a Hammerstein plant: the shape of a propeller's thrust).
fn hardening_staircase(levels: &[f64], fn_hz: f64, sd: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let u: Vec<f64> = levels
        .iter()
        .flat_map(|&v| std::iter::repeat(v).take(300))
        .collect();
    let v: Vec<f64> = u.iter().map(|x| 10.0 * x.powi(3)).collect();
    let mut y = Plant::new(fn_hz, 2.0, 1.0, 0.02)
        .simulate(&v, 0.0)
        .remove(0);
    add_noise(&mut y, sd, seed);
    (u, y)
}

fn identify(u: &[f64], y: &[f64]) -> crate::identify::AnyModel {
    let (uu, yy) = ([u], [y]);
    let input = AnyInput {
        dt_s: 0.02,
        u: &uu,
        y: &yy,
        missing: &[],
        pulse_starts: None,
    };
    identify_okid(&input, &IdentOptions::default(), &OkidOptions::default()).unwrap()
}

/// The gain the staircase's own steady levels show (what `propid identify` judges against).
fn slope(u: &[f64], y: &[f64]) -> crate::static_map::LevelSlope {
    let lv = steady_levels(Command::new(u), &SegmentRules::DEFAULT, y);
    level_slope(&lv).unwrap()
}

#[test]
fn a_slow_hardening_staircase_gets_the_gain_of_its_levels_not_the_realisations_sign() {
    // Issue 11: the path before this rule realised these with poles near z = -1 and a DC gain
    // of the wrong sign (or ~0); the levels rise with the command in every one.
    let mut wrong_before = 0;
    for (levels, fn_hz, seed) in [
        (&[0.2, 0.35, 0.5, 0.65, 0.8][..], 0.1, 1),
        (&[0.2, 0.35, 0.5, 0.65, 0.8][..], 0.3, 2),
        (&[0.3, 0.5, 0.7, 0.9, 0.6, 0.4][..], 0.1, 3),
    ] {
        let (u, y) = hardening_staircase(levels, fn_hz, 0.2, seed);
        let m = identify(&u, &y);
        let s = slope(&u, &y);
        assert!(s.slope > 5.0, "{s:?}");
        let okid = m.okid.as_ref().unwrap();
        let g = m.report.dc_gain.get(0);
        assert!(
            judge_gain(&m.report, &s).is_none(),
            "gain {g} vs levels {s:?} ({okid:?})"
        );
        if okid.realised_dc_gain.is_some_and(|r| r <= 0.0) {
            wrong_before += 1;
            assert_eq!(okid.dc_gain_from, "markov_sum");
        }
        // the published matrices carry the published gain
        let (n, b, c, d) = (m.report.order, &m.report.b, &m.report.c, &m.report.d);
        let a = DMatrix::from_fn(n, n, |i, j| m.report.a[i][j]);
        let x = (DMatrix::<f64>::identity(n, n) - a)
            .lu()
            .solve(&DMatrix::from_fn(n, 1, |i, _| b[i][0]))
            .unwrap();
        let g_abcd = d[0][0] + (0..n).map(|i| c[0][i] * x[(i, 0)]).sum::<f64>();
        assert!((g_abcd - g).abs() < 1e-6 * g.abs(), "{g_abcd} vs {g}");
    }
    assert!(
        wrong_before >= 1,
        "the realisation's own gain had the wrong sign in none of the cases"
    );
}

#[test]
fn a_realisation_that_keeps_its_sequences_gain_is_left_alone() {
    // A fast plant, well excited: ERA's gain is Σ Y_k to a few percent.
    let (u, y) = hardening_staircase(&[0.2, 0.35, 0.5, 0.65, 0.8], 3.0, 0.01, 4);
    let m = identify(&u, &y);
    let okid = m.okid.as_ref().unwrap();
    assert_eq!(okid.dc_gain_from, "realisation", "{okid:?}");
    assert!(okid.realised_dc_gain.is_none());
    assert!(judge_gain(&m.report, &slope(&u, &y)).is_none());
}

#[test]
fn the_refit_holds_the_sequences_gain_with_the_realised_poles() {
    // A 2nd-order sequence whose realisation was given a feed-through of the wrong sign:
    // B, D are re-fitted so that the gain is Σ Y_k again, A and C untouched.
    let plant = Plant::new(2.0, 0.7, 3.0, 0.02);
    let markov = MarkovSeq::from_data(1, 1, plant.markov(400)).unwrap();
    let (a, b, c, _) = plant.matrices();
    let rows = |x: &DMatrix<f64>| -> Vec<Vec<f64>> {
        (0..x.nrows())
            .map(|i| x.row(i).iter().copied().collect())
            .collect()
    };
    let mut report: ModelReport = serde_json::from_value(serde_json::json!({
        "order": 2, "dt_s": 0.02, "fn_hz": 2.0, "zeta": 0.7, "dc_gain": -9.0,
        "time_constants_s": [], "poles_s": [], "poles_z": [],
        "a": rows(&a), "b": rows(&b), "c": rows(&c), "d": [[-12.0]],
        "singular_values": [], "indicators": [],
        "uncertainty": {"fn_hz": null, "zeta": null, "dc_gain": null},
        "pulses": 0, "pulses_skipped": 0, "noise_rms": 0.0,
        "mass_spring_damper": {"m": 0.0, "d": 0.0, "k": 0.0},
        "hankel_block_rows": 10, "hankel_block_cols": 10, "svd": "dense"
    }))
    .unwrap();
    let repair = impose_sequence_gain(&mut report, &markov).unwrap();
    assert!((repair.realised - (3.0 - 12.0)).abs() < 1e-6, "{repair:?}");
    assert!((repair.sequence - 3.0).abs() < 1e-6, "{repair:?}");
    assert!((report.dc_gain.get(0) - 3.0).abs() < 1e-6);
    // the exact B and D = 0 fit the sequence and hold its gain: the re-fit finds them
    assert!(report.d[0][0].abs() < 1e-6, "{:?}", report.d);
    for i in 0..2 {
        assert!((report.b[i][0] - b[(i, 0)]).abs() < 1e-6, "{:?}", report.b);
    }
    assert!((report.mass_spring_damper.k - 1.0 / 3.0).abs() < 1e-9);
    assert_eq!(report.a, rows(&a));
    // a second pass finds nothing to repair
    assert!(impose_sequence_gain(&mut report, &markov).is_none());
}
