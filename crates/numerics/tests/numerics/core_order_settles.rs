//! The automatic order steps down past a realisation whose poles do not all settle
//! (`model_order::settled_order`); a given order is kept as given.

use propid_numerics::{IdentOptions, Limits, MarkovSeq, Workspace};

/// A settling first-order mode (`z = 0.8`) plus a weak pole pair just outside the unit circle
/// near Nyquist (`|z| = 1.01`, 2.8 rad a sample): what noise let in looks like.
fn markov() -> MarkovSeq {
    let y: Vec<f64> = (0..200)
        .map(|k| match k {
            0 => 0.0,
            k => {
                let j = f64::from(k - 1);
                0.8f64.powf(j) + 0.05 * 1.01f64.powf(j) * (2.8 * j).cos()
            }
        })
        .collect();
    MarkovSeq::from_data(1, 1, y).unwrap()
}

fn settles(poles_s: &[[f64; 2]]) -> bool {
    poles_s.iter().all(|p| p[0].is_finite() && p[0] < 0.0)
}

#[test]
fn a_ceiling_order_steps_down_to_the_largest_that_settles_and_a_given_one_stays() {
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let dt = 0.01;
    let given = IdentOptions {
        order: Some(3),
        ..IdentOptions::default()
    };
    let kept = ws
        .identify_markov(&markov(), dt, &given)
        .unwrap()
        .to_report();
    assert_eq!(kept.order, 3);
    assert!(!settles(&kept.poles_s), "{:?}", kept.poles_s);
    assert_eq!(kept.order_stepped_down_from, None);

    let ceiling = IdentOptions {
        order_is_a_ceiling: true,
        ..given
    };
    let m = ws
        .identify_markov(&markov(), dt, &ceiling)
        .unwrap()
        .to_report();
    assert!(m.order < 3, "order {}", m.order);
    assert!(settles(&m.poles_s), "{:?}", m.poles_s);
    assert_eq!(m.order_stepped_down_from, Some(3));
    // The settling mode is the one kept: its pole within 1 % of 0.8.
    assert!(
        m.poles_z
            .iter()
            .any(|z| (z[0] - 0.8).abs() < 0.008 && z[1].abs() < 1e-9),
        "{:?}",
        m.poles_z
    );
    let json = serde_json::to_value(&m).unwrap();
    assert_eq!(json["order_stepped_down_from"], 3);
    assert!(serde_json::to_value(&kept)
        .unwrap()
        .get("order_stepped_down_from")
        .is_none());
}
