//! How far a ramp's down leg lies from its up leg: the output of the down leg minus the up
//! leg's at the same throttle (the up leg's levels interpolated linearly at each down-leg
//! throttle within both legs' range). A motor warmed by the run, a supply sagging, a load cell
//! creeping show here rather than as curvature of one map.

use propid_numerics::static_map::Level;
use serde::Serialize;

/// The down leg against the up leg.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Hysteresis {
    /// Largest `|down − up|`, the output's unit.
    pub max_abs: f64,
    /// The throttle it is at.
    pub at_throttle: f64,
    /// Mean `down − up` (signed: negative when the down leg reads less).
    pub mean: f64,
    /// `max_abs` as a percentage of the largest output of the up leg.
    pub max_pct: f64,
    /// Throttles compared.
    pub points: usize,
}

/// The hysteresis of `down` against `up` (levels of one output over a ramp's windows); `None`
/// with fewer than two levels in either or no overlap.
pub fn hysteresis(up: &[Level], down: &[Level]) -> Option<Hysteresis> {
    let mut up: Vec<&Level> = up.iter().filter(|l| l.mean.is_finite()).collect();
    up.sort_by(|a, b| a.throttle.total_cmp(&b.throttle));
    if up.len() < 2 || down.len() < 2 {
        return None;
    }
    let at = |x: f64| -> Option<f64> {
        let j = up.iter().position(|l| l.throttle >= x)?;
        if j == 0 {
            return (up[0].throttle == x).then_some(up[0].mean);
        }
        let (a, b) = (up[j - 1], up[j]);
        let t = (x - a.throttle) / (b.throttle - a.throttle);
        Some(a.mean + t * (b.mean - a.mean))
    };
    let (mut max_abs, mut at_throttle, mut sum, mut points) = (0.0f64, 0.0, 0.0, 0usize);
    for l in down.iter().filter(|l| l.mean.is_finite()) {
        let Some(u) = at(l.throttle) else { continue };
        let d = l.mean - u;
        if d.abs() > max_abs {
            max_abs = d.abs();
            at_throttle = l.throttle;
        }
        sum += d;
        points += 1;
    }
    if points == 0 {
        return None;
    }
    let full = up.iter().map(|l| l.mean.abs()).fold(0.0, f64::max);
    Some(Hysteresis {
        max_abs,
        at_throttle,
        mean: sum / points as f64,
        max_pct: if full > 0.0 {
            100.0 * max_abs / full
        } else {
            0.0
        },
        points,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lv(throttle: f64, mean: f64) -> Level {
        Level {
            throttle,
            mean,
            std: 0.0,
            samples: 10,
        }
    }

    #[test]
    fn the_down_leg_is_read_against_the_up_leg_interpolated() {
        let up = [lv(0.2, 1.0), lv(0.4, 3.0), lv(0.6, 5.0)];
        let down = [lv(0.5, 3.5), lv(0.3, 1.8), lv(0.7, 9.0)];
        let h = hysteresis(&up, &down).unwrap();
        // at 0.5 the up leg reads 4.0 (−0.5), at 0.3 2.0 (−0.2); 0.7 is outside the up leg
        assert_eq!(h.points, 2);
        assert!((h.max_abs - 0.5).abs() < 1e-12 && h.at_throttle == 0.5);
        assert!((h.mean + 0.35).abs() < 1e-12);
        assert!((h.max_pct - 10.0).abs() < 1e-9);
    }
}
