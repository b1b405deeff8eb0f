//! The gain the steady levels themselves show: the least-squares line through the levels.
//!
//! For levels `(uᵢ, yᵢ)` (the steady mean `yᵢ` at command `uᵢ`, [`super::levels`]):
//!
//! ```text
//! slope = Σ (uᵢ − ū)(yᵢ − ȳ) / Σ (uᵢ − ū)²,   sd = √( Σ rᵢ² / (n − 2) / Σ (uᵢ − ū)² )
//! ```
//!
//! with `rᵢ` the residuals about the line (`sd` is `None` with two levels: no spare degree of
//! freedom). This is the DC gain of the best *static linear* map through the record's own
//! steady states: a linear dynamic model fitted across the same levels settles on them, so its
//! DC gain has the slope's sign and its order of magnitude (a curved map, a propeller's
//! hardening one, puts the local slopes on either side of it). [`crate::quality`] judges a
//! model's DC gain against it.

use serde::Serialize;

use super::{finite, Level};

/// The least-squares slope of the steady levels (output unit per command unit).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LevelSlope {
    /// The slope.
    pub slope: f64,
    /// Its standard error (`None` with two levels).
    pub sd: Option<f64>,
    /// Levels used.
    pub levels: usize,
}

/// The slope of `levels` (see the module doc); `None` with fewer than two levels at distinct
/// commands.
pub fn level_slope(levels: &[Level]) -> Option<LevelSlope> {
    let pts: Vec<(f64, f64)> = finite(levels).map(|l| (l.throttle, l.mean)).collect();
    let n = pts.len();
    if n < 2 {
        return None;
    }
    let mu = pts.iter().map(|p| p.0).sum::<f64>() / n as f64;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n as f64;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mu).powi(2)).sum();
    let spread = pts.iter().map(|p| p.0.abs()).fold(0.0, f64::max);
    if sxx.is_nan() || sxx <= (1e-12 * spread).powi(2) * n as f64 {
        return None;
    }
    let slope = pts.iter().map(|p| (p.0 - mu) * (p.1 - my)).sum::<f64>() / sxx;
    let sd = (n > 2).then(|| {
        let sse: f64 = pts
            .iter()
            .map(|p| (p.1 - my - slope * (p.0 - mu)).powi(2))
            .sum();
        (sse / (n - 2) as f64 / sxx).sqrt()
    });
    slope.is_finite().then_some(LevelSlope {
        slope,
        sd,
        levels: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lv(u: f64, y: f64) -> Level {
        Level {
            throttle: u,
            mean: y,
            std: 0.0,
            samples: 100,
        }
    }

    #[test]
    fn a_line_gives_its_slope_exactly_and_a_curve_its_least_squares_line() {
        let s = level_slope(&[lv(0.2, 1.0), lv(0.4, 2.0), lv(0.6, 3.0)]).unwrap();
        assert!(
            (s.slope - 5.0).abs() < 1e-12 && s.sd.unwrap() < 1e-12,
            "{s:?}"
        );
        // y = 10 u²: the least-squares line through 0.2 .. 0.8 has slope 10 (0.2 + 0.8)
        let q: Vec<Level> = [0.2, 0.4, 0.6, 0.8]
            .iter()
            .map(|&u| lv(u, 10.0 * u * u))
            .collect();
        let s = level_slope(&q).unwrap();
        assert!((s.slope - 10.0).abs() < 1e-9, "{s:?}");
        assert!(s.sd.unwrap() > 0.0);
        // two levels: the secant, no spread
        let s = level_slope(&[lv(0.2, 1.0), lv(0.5, 0.4)]).unwrap();
        assert!((s.slope + 2.0).abs() < 1e-12 && s.sd.is_none());
    }

    #[test]
    fn one_command_or_one_level_gives_no_slope() {
        assert!(level_slope(&[lv(0.3, 1.0)]).is_none());
        assert!(level_slope(&[lv(0.3, 1.0), lv(0.3, 2.0)]).is_none());
        assert!(level_slope(&[]).is_none());
    }
}
