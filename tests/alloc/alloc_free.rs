//! The identification hot path makes zero heap allocations: a counting global allocator
//! counts allocations made by this thread while `identify` runs, repeatedly.

use propid_testkit as core_support;

use crate::counting_alloc;

use counting_alloc::allocations;

use core_support::{record_input, throttle, Plant};
use propid_numerics::{IdentOptions, Limits, MarkovSeq, PulseInput, Workspace};
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

#[test]
fn pulse_identification_allocates_nothing() {
    let plant = Plant::new(10.0, 0.25, 4.0, 0.005).with_output([0.2, 0.01], 0.05);
    let pulses: Vec<_> = (0..6)
        .map(|i| {
            (
                100 + 400 * i,
                1 + i % 2,
                if i % 2 == 0 { 0.1 } else { -0.05 },
            )
        })
        .collect();
    let u = throttle(2600, &[(0, 0.4)], &pulses);
    let mut y = plant.simulate(&u, 2.0);
    // A little seeded white noise so the noise floor and the jackknife are exercised.
    let mut rng = StdRng::seed_from_u64(7);
    let normal = Normal::new(0.0, 1e-4).unwrap();
    for ch in y.iter_mut() {
        for v in ch.iter_mut() {
            *v += normal.sample(&mut rng);
        }
    }
    let chans = [&y[0][..], &y[1][..]];
    let input = record_input(plant.dt, &u, &chans);
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let opts = IdentOptions::default();
    for round in 0..3 {
        let (n, order) = allocations(|| ws.identify(&input, &opts).map(|m| m.order()));
        assert_eq!(
            order,
            Ok(2),
            "{}",
            serde_json::to_string(&ws.to_report()).unwrap()
        );
        assert_eq!(n, 0, "round {round}: {n} allocations in identify");
        let fixed = IdentOptions {
            order: Some(3),
            ..opts
        };
        let (n, res) = allocations(|| ws.identify(&input, &fixed).map(|m| m.order()));
        assert_eq!(res, Ok(3));
        assert_eq!(n, 0, "round {round}: {n} allocations at order 3");
    }
    // The truncated (FFT + Lanczos) path, jackknife included.
    let trunc = IdentOptions {
        svd: propid_numerics::SvdChoice::Truncated,
        ..opts
    };
    for round in 0..2 {
        let (n, res) = allocations(|| ws.identify(&input, &trunc).map(|m| m.order()));
        assert_eq!(res, Ok(2));
        assert_eq!(n, 0, "round {round}: {n} allocations on the truncated path");
    }
    // Errors allocate nothing either.
    let flat = vec![0.4; 2600];
    let bad = PulseInput { u: &flat, ..input };
    let (n, res) = allocations(|| ws.identify(&bad, &opts).map(|m| m.order()));
    assert!(res.is_err());
    assert_eq!(n, 0);
    // Given Markov parameters.
    let markov = MarkovSeq::from_data(2, 1, plant.markov(400)).unwrap();
    let (n, res) = allocations(|| {
        ws.identify_markov(&markov, plant.dt, &opts)
            .map(|m| m.order())
    });
    assert_eq!(res, Ok(2), "{:?}", ws.to_report().singular_values);
    assert_eq!(n, 0, "{n} allocations in identify_markov");
}
