//! Levels over holds, and each fit (power law, expo, thrust coefficient) on known maps.

use super::*;

fn lv(throttle: f64, mean: f64) -> Level {
    Level {
        throttle,
        mean,
        std: 0.0,
        samples: 100,
    }
}

#[test]
fn levels_take_the_steady_half_and_skip_missing_cells() {
    let mut y = vec![0.0; 100];
    y[50..100].iter_mut().for_each(|v| *v = 2.0);
    y[60] = f64::NAN;
    y[0..25].iter_mut().for_each(|v| *v = 9.0); // transient, left out
    let l = levels(
        &y,
        &[Run {
            lead: 0,
            start: 0,
            end: 100,
            value: 0.5,
        }],
    );
    assert_eq!(l.len(), 1);
    assert_eq!((l[0].mean, l[0].std, l[0].samples), (2.0, 0.0, 49));
    let run = Run {
        lead: 0,
        start: 0,
        end: 4,
        value: 0.1,
    };
    assert!(levels(&[f64::NAN; 4], &[run]).is_empty());
}

#[test]
fn an_exact_power_law_is_recovered_with_its_dead_band() {
    let truth = PowerLaw {
        k: 12.0,
        u0: 0.08,
        exponent: 1.9,
        uncertainty: None,
    };
    let l: Vec<Level> = [0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
        .iter()
        .map(|&u| lv(u, truth.predict(u)))
        .collect();
    let p = fit_power_law(&l).unwrap();
    assert!((p.k - 12.0).abs() < 1e-4, "{p:?}");
    assert!((p.u0 - 0.08).abs() < 1e-5, "{p:?}");
    assert!((p.exponent - 1.9).abs() < 1e-5, "{p:?}");
    let sd = p.uncertainty.unwrap();
    assert!(sd.k < 1e-4 && sd.exponent < 1e-4);
}

#[test]
fn a_noisy_power_law_has_an_uncertainty_that_covers_the_error() {
    let truth = |u: f64| 8.0 * (u - 0.05f64).max(0.0).powf(2.0);
    let noise = [0.02, -0.03, 0.01, 0.025, -0.02, 0.015, -0.01, 0.03];
    let l: Vec<Level> = (0..8)
        .map(|i| {
            let u = 0.2 + 0.1 * i as f64;
            lv(u, truth(u) + noise[i])
        })
        .collect();
    let p = fit_power_law(&l).unwrap();
    let sd = p.uncertainty.unwrap();
    assert!((p.exponent - 2.0).abs() < 4.0 * sd.exponent + 1e-9, "{p:?}");
    assert!(sd.exponent > 0.0);
}

#[test]
fn too_few_levels_give_no_power_law() {
    assert!(fit_power_law(&[lv(0.3, 1.0), lv(0.5, 2.0)]).is_none());
    // No level above zero, rising or falling: nothing to fit.
    assert!(fit_power_law(&[lv(0.3, 0.0), lv(0.5, 0.0), lv(0.6, 0.0)]).is_none());
    let three = fit_power_law(&[lv(0.3, 1.0), lv(0.5, 2.5), lv(0.7, 5.0)]).unwrap();
    assert!(three.uncertainty.is_none());
}

#[test]
fn an_output_that_falls_with_the_command_is_fitted_by_its_magnitude() {
    // A load cell mounted reversed: the same map, negated (and a tare a little below zero).
    let truth = |u: f64| 12.0 * (u - 0.08f64).max(0.0).powf(1.9);
    let up: Vec<Level> = [0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
        .iter()
        .map(|&u| lv(u, truth(u)))
        .collect();
    let down: Vec<Level> = up.iter().map(|l| lv(l.throttle, -l.mean)).collect();
    assert!(!falls_with_command(&up));
    assert!(falls_with_command(&down));
    let (p, q) = (fit_power_law(&up).unwrap(), fit_power_law(&down).unwrap());
    assert!((q.k + 12.0).abs() < 1e-4, "{q:?}");
    assert_eq!((q.u0, q.exponent), (p.u0, p.exponent));
    assert!((q.predict(0.5) - down[4].mean).abs() < 1e-6);
    let (e, f) = (fit_expo(&up).unwrap(), fit_expo(&down).unwrap());
    assert_eq!((f.a, f.t_max), (e.a, -e.t_max));
    assert!(f.t_max < 0.0 && (f.predict(0.9) - down[8].mean).abs() < 0.5);
}

#[test]
fn expo_recovers_the_blend() {
    let (a, t_max) = (0.65, 14.0);
    let l: Vec<Level> = [0.1, 0.3, 0.5, 0.7, 0.9]
        .iter()
        .map(|&x| lv(x, t_max * ((1.0 - a) * x + a * x * x)))
        .collect();
    let e = fit_expo(&l).unwrap();
    assert!(
        (e.a - a).abs() < 1e-12 && (e.t_max - t_max).abs() < 1e-10,
        "{e:?}"
    );
    assert!(e.uncertainty.unwrap().a < 1e-9);
    assert!((e.predict(0.5) - l[2].mean).abs() < 1e-10);
}

#[test]
fn thrust_coefficient_through_the_origin() {
    let w = [100.0, 200.0, 300.0];
    let t: Vec<Level> = w.iter().map(|w| lv(0.0, 2e-5 * w * w)).collect();
    let o: Vec<Level> = w.iter().map(|&w| lv(0.0, w)).collect();
    let c = fit_thrust_coefficient(&t, &o).unwrap();
    assert!((c.k_t - 2e-5).abs() < 1e-15);
    assert!(c.k_t_sd.unwrap() < 1e-15);
    assert!(fit_thrust_coefficient(&[], &[]).is_none());
}
