//! Accuracy indicators against known values: exact data gives MAC = EMAC = 1; modes forced
//! into noise get low indicators while the physical mode keeps high ones.

use propid_testkit as core_support;

use core_support::{add_noise, record_input, throttle, Plant};
use propid_numerics::{IdentOptions, Limits, MarkovSeq, Workspace};

#[test]
fn exact_data_gives_unit_coherence() {
    let plant = Plant::new(10.0, 0.2, 4.0, 0.005);
    let markov = MarkovSeq::from_data(1, 1, plant.markov(300)).unwrap();
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let m = ws
        .identify_markov(&markov, plant.dt, &IdentOptions::default())
        .unwrap();
    assert_eq!(m.order(), 2);
    for ind in m.indicators() {
        assert!((ind.mac - 1.0).abs() < 1e-6, "{ind:?}");
        assert!((ind.emac - 1.0).abs() < 1e-6, "{ind:?}");
        assert!((ind.mpc - 1.0).abs() < 1e-12, "single output: MPC = 1");
        assert!((ind.cmi - ind.emac * ind.mpc).abs() < 1e-15);
        assert!(ind.msv > 0.0);
    }
}

#[test]
fn noise_modes_have_low_indicators() {
    let plant = Plant::new(15.0, 0.5, 4.0, 0.001);
    let pulses: Vec<_> = (0..30)
        .map(|i| (200 + 250 * i, 1, if i % 2 == 0 { 0.2 } else { -0.2 }))
        .collect();
    let u = throttle(200 + 250 * 30 + 50, &[(0, 0.5)], &pulses);
    let mut y = plant.simulate(&u, 2.0).remove(0);
    add_noise(&mut y, 0.005, 11);
    let chans = [&y[..]];
    let input = record_input(plant.dt, &u, &chans);
    let mut ws = Workspace::new(&Limits {
        max_samples: 16384,
        ..Limits::default()
    })
    .unwrap();
    let opts = IdentOptions {
        order: Some(6),
        jackknife: false,
        ..IdentOptions::default()
    };
    let m = ws.identify(&input, &opts).unwrap();
    // The physical pair: poles closest to the truth.
    let wn = 2.0 * std::f64::consts::PI * 15.0;
    let truth = nalgebra::Complex::new(-0.5 * wn, wn * 0.75f64.sqrt());
    let dist = |k: usize| {
        (m.poles_s()[k] - truth)
            .norm()
            .min((m.poles_s()[k] - truth.conj()).norm())
    };
    let phys: Vec<usize> = (0..6).filter(|&k| dist(k) < 0.1 * wn).collect();
    assert_eq!(phys.len(), 2, "{:?}", m.poles_s());
    let ind = m.indicators();
    let worst_phys = phys
        .iter()
        .map(|&k| ind[k].emac.min(ind[k].mac))
        .fold(1.0, f64::min);
    assert!(worst_phys > 0.7, "physical mode: {:?}", &ind[phys[0]]);
    for k in (0..6).filter(|k| !phys.contains(k)) {
        assert!(
            ind[k].msv < 0.5 * ind[phys[0]].msv,
            "noise mode {k} MSV: {:?}",
            ind[k]
        );
        assert!(ind[k].cmi < worst_phys, "noise mode {k}: {:?}", ind[k]);
    }
    let best_noise = (0..6)
        .filter(|k| !phys.contains(k))
        .map(|k| ind[k].emac)
        .fold(0.0, f64::max);
    assert!(best_noise < 0.8, "noise modes EMAC up to {best_noise}");
}
