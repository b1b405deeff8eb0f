//! Where the stand simulation departs from one measured channel: its held-out residual
//! (each fold predicted by the model fitted without it) by command level, by step direction
//! and by frequency band.
//!
//! - **By level**: over each hold of the command (the one segmentation,
//!   `propid_numerics::segment::holds`), the residual's mean (a bias: the static map wrong
//!   there) and RMS at the channel's readings.
//! - **By direction**: over the first half of the hold after each step (the transient), the
//!   residual's mean and RMS after the steps up and after the steps down (a rotor or a sensor
//!   timed wrong in one direction).
//! - **By band**: the residual's power (Hann periodogram of its finite samples,
//!   [`crate::spectrum::periodogram`]) in octave-wide bands of four octaves each below half
//!   the row rate, as an RMS and a share of the whole.

use propid_numerics::segment::{holds, steps, Command, SegmentRules};
use serde::Serialize;

use crate::spectrum::periodogram;

/// The residual over one hold.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LevelDeparture {
    /// The command held.
    pub command: f64,
    /// Its samples, `[first, end)`.
    pub samples: [usize; 2],
    /// Mean of the residual (measured − simulated), the channel's unit.
    pub bias: f64,
    /// RMS of the residual.
    pub rms: f64,
}

/// The residual over the transients after the steps of one direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DirectionDeparture {
    /// Steps.
    pub steps: usize,
    /// Mean of the residual.
    pub bias: f64,
    /// RMS of the residual.
    pub rms: f64,
}

/// The residual in one frequency band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BandDeparture {
    /// The band, Hz.
    pub band_hz: [f64; 2],
    /// RMS of the residual in the band.
    pub rms: f64,
    /// Its share of the residual's power.
    pub share: f64,
}

/// Where the simulation departs from a channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Departures {
    /// RMS of the held-out residual at the channel's readings.
    pub rms: f64,
    /// Per hold of the command.
    pub by_level: Vec<LevelDeparture>,
    /// After the steps up (null without one).
    pub steps_up: Option<DirectionDeparture>,
    /// After the steps down (null without one).
    pub steps_down: Option<DirectionDeparture>,
    /// Per frequency band, lowest first.
    pub by_band: Vec<BandDeparture>,
}

impl Departures {
    /// One line for the summary: the worst level, the directions, the band holding most of
    /// the residual.
    pub fn line(&self) -> String {
        let mut parts = vec![format!("residual RMS {:.4}", self.rms)];
        if let Some(l) = self.by_level.iter().max_by(|a, b| a.rms.total_cmp(&b.rms)) {
            parts.push(format!(
                "worst at command {:.3} (bias {:+.4}, RMS {:.4})",
                l.command, l.bias, l.rms
            ));
        }
        let dir = |d: &Option<DirectionDeparture>| {
            d.map_or("none".to_string(), |d| {
                format!("RMS {:.4} bias {:+.4}", d.rms, d.bias)
            })
        };
        parts.push(format!(
            "after steps up {}, down {}",
            dir(&self.steps_up),
            dir(&self.steps_down)
        ));
        if let Some(b) = self
            .by_band
            .iter()
            .max_by(|a, b| a.share.total_cmp(&b.share))
        {
            parts.push(format!(
                "{:.0} % of its power at {:.2}–{:.2} Hz",
                100.0 * b.share,
                b.band_hz[0],
                b.band_hz[1]
            ));
        }
        parts.join("; ")
    }
}

/// The departures of the residual `r` (NaN: no reading, or no prediction) under command `u`
/// every `dt_s`.
pub fn departures(u: &[f64], r: &[f64], dt_s: f64, rules: &SegmentRules) -> Departures {
    let stats = |ks: &mut dyn Iterator<Item = usize>| {
        let (mut s, mut s2, mut n) = (0.0, 0.0, 0usize);
        for k in ks {
            if let Some(&x) = r.get(k).filter(|x| x.is_finite()) {
                s += x;
                s2 += x * x;
                n += 1;
            }
        }
        (n > 0).then(|| (s / n as f64, (s2 / n as f64).sqrt(), n))
    };
    let rms = stats(&mut (0..r.len())).map_or(f64::NAN, |s| s.1);
    let cmd = Command::new(u);
    let by_level = holds(cmd, rules)
        .filter_map(|h| {
            let (bias, rms, _) = stats(&mut (h.start..h.end))?;
            Some(LevelDeparture {
                command: h.value,
                samples: [h.start, h.end],
                bias,
                rms,
            })
        })
        .collect();
    let st = steps(cmd, rules);
    let direction = |up: bool| {
        let mut it = st
            .iter()
            .filter(|s| (s.to > s.from) == up)
            .flat_map(|s| s.at..s.at + (s.after_end - s.at).div_ceil(2));
        let count = st.iter().filter(|s| (s.to > s.from) == up).count();
        stats(&mut it).map(|(bias, rms, _)| DirectionDeparture {
            steps: count,
            bias,
            rms,
        })
    };
    Departures {
        rms,
        by_level,
        steps_up: direction(true),
        steps_down: direction(false),
        by_band: bands(r, dt_s),
    }
}

/// The residual's power in bands of four octaves... each an octave pair below Nyquist
/// (module doc): `[f/4, f]` for `f` = Nyquist, Nyquist/4, ..., the lowest from 0.
fn bands(r: &[f64], dt_s: f64) -> Vec<BandDeparture> {
    let x: Vec<f64> = r.iter().copied().filter(|v| v.is_finite()).collect();
    let (f, p) = periodogram(&x, dt_s);
    if f.len() < 4 {
        return Vec::new();
    }
    let total: f64 = p.iter().skip(1).sum::<f64>().max(1e-300);
    let nyquist = 0.5 / dt_s;
    let lowest = f[1];
    let mut edges = vec![nyquist];
    while *edges.last().unwrap_or(&0.0) / 4.0 > 4.0 * lowest && edges.len() < 5 {
        let next = edges.last().copied().unwrap_or(nyquist) / 4.0;
        edges.push(next);
    }
    edges.push(0.0);
    edges.reverse();
    let n = x.len() as f64;
    edges
        .windows(2)
        .map(|w| {
            let pw: f64 = f
                .iter()
                .zip(&p)
                .skip(1)
                .filter(|(fj, _)| **fj >= w[0] && (**fj < w[1] || w[1] == nyquist))
                .map(|(_, pj)| pj)
                .sum();
            BandDeparture {
                band_hz: [w[0], w[1]],
                // Parseval for the one-sided Hann periodogram: Σ P ≈ Σ x² / 2 per ... scaled
                // to the residual's own mean square through the share.
                rms: (pw / total * x.iter().map(|v| v * v).sum::<f64>() / n.max(1.0)).sqrt(),
                share: pw / total,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bias_at_one_level_and_a_misfit_after_steps_up_are_placed_where_they_are() {
        let dt = 0.01;
        let u: Vec<f64> = (0..1200)
            .map(|k| [0.2, 0.6, 0.4, 0.8][(k / 300) % 4])
            .collect();
        let mut r = vec![0.0; 1200];
        for x in &mut r[300..600] {
            *x = 0.5; // a bias over the second hold
        }
        for k in [900, 901, 902, 903] {
            r[k] = 2.0; // a transient after the step up at 900
        }
        let d = departures(&u, &r, dt, &SegmentRules::for_record(dt, true));
        let worst = d
            .by_level
            .iter()
            .max_by(|a, b| a.rms.total_cmp(&b.rms))
            .unwrap();
        assert!((worst.command - 0.6).abs() < 1e-12, "{d:?}");
        assert!((worst.bias - 0.5).abs() < 1e-12);
        let (up, down) = (d.steps_up.unwrap(), d.steps_down.unwrap());
        assert!(up.rms > down.rms, "{d:?}");
        let shares: f64 = d.by_band.iter().map(|b| b.share).sum();
        assert!((shares - 1.0).abs() < 1e-9, "{shares}");
    }
}
