//! A slow sensor that the stand software (or a script before it) already interpolated onto every
//! row: the third way a sensor's rows can hold values that are not its readings, beside empty
//! cells ([`super::resample`]) and a repeated last reading ([`super::held`]).
//!
//! Method and reasoning: `docs/engine-notes.md`, `crates/ingest/src/interpolated.rs`.

/// Relative size under which a sloped second difference is taken for a line (module doc).
pub const COLLINEAR: f64 = 1e-9;
/// Share of a channel's values on sloped lines through their neighbours from which it is
/// taken as interpolated (a channel read on every second row has half of them so, every fourth
/// three quarters; chance in a quantised sensor, a few per cent).
pub const INTERPOLATED_SHARE: f64 = 1.0 / 3.0;

/// True when `y[k]` lies on the sloped straight line through its neighbours (module doc).
fn on_line(y: &[f64], k: usize) -> bool {
    let (Some(&a), Some(&b), Some(&c)) = (
        k.checked_sub(1).and_then(|j| y.get(j)),
        y.get(k),
        y.get(k + 1),
    ) else {
        return false;
    };
    let tol = COLLINEAR * a.abs().max(b.abs()).max(c.abs()).max(f64::MIN_POSITIVE);
    (c - a).abs() > tol && (c - 2.0 * b + a).abs() <= tol
}

/// The mark of a channel's values that lie on lines (true there) when the channel is
/// interpolated by the rule of the module doc; `None` when it is not.
pub fn exporter_interpolated(y: &[f64]) -> Option<Vec<bool>> {
    let mark: Vec<bool> = (0..y.len()).map(|k| on_line(y, k)).collect();
    let with_neighbours = (1..y.len().saturating_sub(1))
        .filter(|&k| y[k - 1].is_finite() && y[k].is_finite() && y[k + 1].is_finite())
        .count();
    let lines = mark.iter().filter(|m| **m).count();
    (with_neighbours > 0 && lines as f64 >= INTERPOLATED_SHARE * with_neighbours as f64)
        .then_some(mark)
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_testkit::gaussian as noise;

    #[test]
    fn readings_interpolated_onto_every_row_are_marked_between_the_readings() {
        // Readings every 10 rows, the rows between on the line joining them.
        let r = noise(41, 1.0, 1);
        let y: Vec<f64> = (0..400)
            .map(|k| {
                let (j, f) = (k / 10, (k % 10) as f64 / 10.0);
                r[j] + f * (r[j + 1] - r[j])
            })
            .collect();
        let mark = exporter_interpolated(&y).expect("interpolated");
        for (k, m) in mark.iter().enumerate().take(399).skip(1) {
            assert_eq!(*m, k % 10 != 0, "{k}");
        }
    }

    #[test]
    fn a_noisy_or_quantised_or_resting_sensor_is_read_as_it_is() {
        let white = noise(3000, 0.02, 2);
        assert!(exporter_interpolated(&white).is_none());
        // Codes of 0.01 under noise of 0.02: three codes in a row by chance, a few per cent.
        let coded: Vec<f64> = white.iter().map(|e| (e / 0.01).round() * 0.01).collect();
        let by_chance = (1..2999).filter(|&k| on_line(&coded, k)).count();
        assert!(by_chance > 30, "{by_chance}");
        assert!(exporter_interpolated(&coded).is_none());
        // A sensor at rest between steps repeats: levels are not lines.
        let levels: Vec<f64> = (0..300).map(|k| (k / 50) as f64).collect();
        assert!(exporter_interpolated(&levels).is_none());
    }

    #[test]
    fn missing_and_short_channels_are_not_marked() {
        assert!(exporter_interpolated(&[]).is_none());
        assert!(exporter_interpolated(&[1.0, 2.0]).is_none());
        let gaps = vec![f64::NAN; 100];
        assert!(exporter_interpolated(&gaps).is_none());
    }
}
