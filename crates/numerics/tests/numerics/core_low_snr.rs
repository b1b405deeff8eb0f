//! Low signal-to-noise pulse records like the simulated stand's default plant at 1 kHz
//! (fn = 12 Hz, ζ = 0.7, 12 N/throttle, 10 mN noise, four pulses of ±0.05/±0.1 throttle,
//! order 2): the single-pulse peak is only 2–4 × the noise. Numbers in docs/core.md.

use propid_testkit as core_support;

use core_support::{add_noise, record_input, throttle, Plant};
use propid_numerics::{IdentOptions, Limits, Workspace};

/// RMS relative error of (fn, ζ) over `seeds` records at 1 kHz.
fn rms_errors(seeds: u64) -> (f64, f64) {
    let plant = Plant::new(12.0, 0.7, 12.0, 0.001);
    let amps = [0.05, -0.05, 0.1, -0.1];
    let pulses: Vec<_> = (0..4).map(|i| (100 + 250 * i, 1, amps[i])).collect();
    let u = throttle(100 + 250 * 4, &[(0, 0.45)], &pulses);
    let mut ws = Workspace::new(&Limits::default()).unwrap();
    let opts = IdentOptions {
        order: Some(2),
        jackknife: false,
        ..IdentOptions::default()
    };
    let (mut ef, mut ez) = (0.0, 0.0);
    for seed in 0..seeds {
        // The stand measures at the end of the period (Y_0 = C B): shift by one sample.
        let mut y = plant.simulate(&u, 5.4).remove(0);
        y.remove(0);
        y.push(y[y.len() - 1]);
        add_noise(&mut y, 0.01, seed);
        let chans = [&y[..]];
        let input = record_input(plant.dt, &u, &chans);
        let m = ws.identify(&input, &opts).unwrap();
        ef += (m.fn_hz() / 12.0 - 1.0).powi(2);
        ez += (m.zeta() / 0.7 - 1.0).powi(2);
    }
    let n = seeds as f64;
    ((ef / n).sqrt(), (ez / n).sqrt())
}

/// The Hankel matrix used to stop 8 samples after the averaged response's moving RMS fell
/// below 2σ: at this SNR that is ~50 of the ~100 samples the response lasts, and ζ came out
/// +12 % biased with 28 % scatter (fn +2.5 %, 7.9 %) over 200 seeds. Spanning twice the
/// above-noise length gives ζ +2 % / 11 %, fn +1.5 % / 5.7 %.
#[test]
fn hankel_cut_at_the_2_sigma_crossing_biases_low_snr_damping() {
    let (rf, rz) = rms_errors(60);
    assert!(rf < 0.075, "fn RMS error {rf}");
    assert!(rz < 0.17, "zeta RMS error {rz}");
}
