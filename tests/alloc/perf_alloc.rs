//! The core calls behind the daemon's jackknife helper thread (`daemon::identify`) allocate
//! nothing: `Workspace::identify_model`, `Workspace::jackknife_only` (what the helper runs on
//! its twin workspace) and `Workspace::set_uncertainty`, counted per thread by the counting
//! allocator; and together they give `Workspace::identify`'s model exactly.

use crate::counting_alloc;

use counting_alloc::allocations;
use propid_numerics::pulses::PulseInput;
use propid_numerics::svd::SvdChoice;
use propid_numerics::workspace::{IdentOptions, Limits, Workspace};

/// Four ±pulses on a noisy 2nd-order response (fn 12 Hz, ζ 0.6) at 1 kHz.
fn record() -> (Vec<f64>, Vec<f64>, Vec<usize>) {
    let n = 1300;
    let dt = 1e-3;
    let (w, z) = (2.0 * std::f64::consts::PI * 12.0, 0.6f64);
    let wd = w * dt * (1.0 - z * z).sqrt();
    let (a1, a2) = (
        2.0 * (-z * w * dt).exp() * wd.cos(),
        -(-2.0 * z * w * dt).exp(),
    );
    let starts = vec![100, 400, 700, 1000];
    let mut u = vec![0.3; n];
    for (k, &s) in starts.iter().enumerate() {
        u[s] += if k % 2 == 0 { 0.1 } else { -0.1 };
    }
    let (mut y, mut state) = (vec![0.0; n], 0x2545_F491_4F6C_DD1Du64);
    let (mut y1, mut y2) = (0.0, 0.0);
    for k in 0..n {
        let x = if k > 0 { u[k - 1] - 0.3 } else { 0.0 };
        let v = a1 * y1 + a2 * y2 + 0.5 * x;
        (y2, y1) = (y1, v);
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        y[k] = 3.0 + v + 1e-3 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
    }
    (u, y, starts)
}

#[test]
fn model_and_jackknife_beside_it_allocate_nothing_and_equal_identify() {
    let (u, y, starts) = record();
    let limits = Limits {
        max_samples: 4096,
        max_outputs: 1,
        max_order: 8,
        max_pulses: 6,
        ..Limits::default()
    };
    let opts = IdentOptions {
        order: Some(2),
        svd: SvdChoice::Truncated,
        ..IdentOptions::default()
    };
    let (mut main, mut twin, mut reference) = (
        Workspace::new(&limits).unwrap(),
        Workspace::new(&limits).unwrap(),
        Workspace::new(&limits).unwrap(),
    );
    let yy = [&y[..]];
    let input = PulseInput {
        dt_s: 1e-3,
        u: &u,
        y: &yy,
        missing: &[],
        pulse_starts: Some(&starts),
    };
    for round in 0..3 {
        let (n, applied) = allocations(|| {
            main.identify_model(&input, &opts).unwrap();
            let applied = twin.jackknife_only(&input, &opts).unwrap();
            let (f, z, d) = twin.model().uncertainty(0);
            main.set_uncertainty(f, z, &[d]);
            applied
        });
        assert!(applied, "order 2 on the truncated path");
        if round > 0 {
            assert_eq!(n, 0, "round {round}: {n} allocations");
        }
        reference.identify(&input, &opts).unwrap();
        let (a, b) = (main.to_report(), reference.to_report());
        assert_eq!(
            serde_json::to_string(&a).unwrap(),
            serde_json::to_string(&b).unwrap()
        );
        assert!(a.uncertainty.fn_hz > 0.0);
    }
    // Automatic order: not for the twin (the jackknife then runs after the model).
    let auto = IdentOptions {
        order: None,
        ..opts
    };
    assert!(!twin.jackknife_only(&input, &auto).unwrap());
}
