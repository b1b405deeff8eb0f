//! A channel's missing samples: marked NaN ([`mark_missing`]), or held across from the last
//! finite value ([`fill_gaps`]), as the engines take an output and an input.

/// NaN at every sample marked missing.
pub fn mark_missing(y: &mut [f64], missing: &[bool]) {
    for (v, m) in y.iter_mut().zip(missing) {
        if *m {
            *v = f64::NAN;
        }
    }
}

/// Holds the last finite value across gaps (leading gaps take the first finite value).
pub fn fill_gaps(mut x: Vec<f64>) -> Vec<f64> {
    let first = x
        .iter()
        .copied()
        .find(|v| v.is_finite())
        .unwrap_or(f64::NAN);
    let mut last = first;
    for v in x.iter_mut() {
        if v.is_finite() {
            last = *v;
        } else {
            *v = last;
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_are_held_from_the_last_finite_value_and_leading_gaps_from_the_first() {
        let x = fill_gaps(vec![f64::NAN, 2.0, f64::NAN, f64::INFINITY, 5.0, f64::NAN]);
        assert_eq!(x, [2.0, 2.0, 2.0, 2.0, 5.0, 5.0]);
        assert!(fill_gaps(vec![f64::NAN; 3]).iter().all(|v| v.is_nan()));
    }

    #[test]
    fn samples_marked_missing_become_nan_and_others_stay() {
        let mut y = vec![1.0, 2.0, 3.0];
        mark_missing(&mut y, &[false, true, false]);
        assert_eq!((y[0], y[2]), (1.0, 3.0));
        assert!(y[1].is_nan());
    }
}
