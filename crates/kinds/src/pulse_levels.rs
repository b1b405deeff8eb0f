//! The steady output at each operating point of a pulses run (its thrust curve): per-level
//! accumulators, sized once from the configured levels, fed sample by sample without
//! allocating.
//!
//! A sample counts for level `L` when its applied throttle is within [`crate::STEP_CHANGE`] of
//! `L` and the run has been at `L` for `settle_ms` (a visit starts when
//! `pulse_width_samples + 2` samples in a row are at a level other than the current one, so a
//! pulse that reaches a neighbouring level starts none). Pulse samples (off the level) are
//! left out; the response after each pulse is in (for pulses of `w` samples every `S`, its
//! share of the mean is about `amplitude·w/S` of the gain: 0.05 % for 0.05 × 2 ms / 200 ms).
//! Mean and spread by Welford's update (Welford 1962, *Technometrics* 4(3) 419–420).

use propid_numerics::static_map::Level;
use propid_wire::experiment::ExperimentConfig;

use crate::{Sample, STEP_CHANGE};

/// Welford's running mean and sum of squared deviations.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Running {
    n: usize,
    mean: f64,
    m2: f64,
}

impl Running {
    /// Adds `v` (a non-finite one is not measured: skipped).
    pub fn add(&mut self, v: f64) {
        if !v.is_finite() {
            return;
        }
        self.n += 1;
        let d = v - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (v - self.mean);
    }

    /// Samples added.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The level at `throttle` (sample standard deviation; 0 for one sample); `None` without
    /// a sample.
    pub fn level(&self, throttle: f64) -> Option<Level> {
        (self.n > 0).then(|| Level {
            throttle,
            mean: self.mean,
            std: if self.n > 1 {
                (self.m2 / (self.n - 1) as f64).sqrt()
            } else {
                0.0
            },
            samples: self.n,
        })
    }
}

/// The outputs accumulated: thrust, rpm, current.
pub const OUTPUTS: [(&str, &str); 3] = [("thrust", "N"), ("rpm", "rpm"), ("current", "A")];

/// The accumulators of a pulses run (module doc).
#[derive(Debug, Clone)]
pub struct PulseLevels {
    levels: Vec<f64>,
    acc: Vec<[Running; 3]>,
    current: Option<usize>,
    since_us: u64,
    candidate: Option<(usize, u32)>,
    settle_us: u64,
    switch_after: u32,
}

impl PulseLevels {
    /// Accumulators for `cfg`'s levels.
    pub fn new(cfg: &ExperimentConfig) -> PulseLevels {
        PulseLevels {
            levels: cfg.levels.clone(),
            acc: vec![[Running::default(); 3]; cfg.levels.len()],
            current: None,
            since_us: 0,
            candidate: None,
            settle_us: u64::from(cfg.settle_ms) * 1000,
            switch_after: cfg.pulse_width_samples.saturating_add(2),
        }
    }

    /// One sample.
    pub fn push(&mut self, s: &Sample) {
        let Some(k) = self
            .levels
            .iter()
            .position(|l| (s.throttle - l).abs() <= STEP_CHANGE)
        else {
            self.candidate = None;
            return;
        };
        if self.current != Some(k) {
            let seen = match self.candidate {
                Some((c, n)) if c == k => n + 1,
                _ => 1,
            };
            if seen < self.switch_after && self.current.is_some() {
                self.candidate = Some((k, seen));
                return;
            }
            self.current = Some(k);
            self.since_us = s.t_us;
        }
        self.candidate = None;
        if s.t_us.saturating_sub(self.since_us) >= self.settle_us {
            let a = &mut self.acc[k];
            a[0].add(s.thrust);
            a[1].add(s.rpm);
            a[2].add(s.current);
        }
    }

    /// The levels of output `o` (an index into [`OUTPUTS`]) by throttle, those measured.
    pub fn levels(&self, o: usize) -> Vec<Level> {
        let mut lv: Vec<Level> = self
            .levels
            .iter()
            .zip(&self.acc)
            .filter_map(|(&u, a)| a[o].level(u))
            .collect();
        lv.sort_by(|a, b| a.throttle.total_cmp(&b.throttle));
        lv
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_mean_and_spread() {
        let mut r = Running::default();
        for v in [1.0, 2.0, f64::NAN, 3.0, 4.0] {
            r.add(v);
        }
        let l = r.level(0.5).unwrap();
        assert_eq!((l.samples, l.mean), (4, 2.5));
        assert!((l.std - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!(Running::default().level(0.5).is_none());
    }

    #[test]
    fn pulses_and_the_settling_are_left_out() {
        let cfg = ExperimentConfig {
            levels: vec![0.3, 0.4],
            settle_ms: 100,
            pulse_width_samples: 1,
            ..ExperimentConfig::default()
        };
        let mut p = PulseLevels::new(&cfg);
        let mut k = 0u64;
        let mut feed = |p: &mut PulseLevels, u: f64, y: f64| {
            p.push(&Sample {
                index: k,
                t_us: k * 1000,
                throttle: u,
                thrust: y,
                rpm: f64::NAN,
                current: 1.0,
            });
            k += 1;
        };
        for i in 0..1000 {
            // settling: 100 samples reading 9; then 2.0, a pulse to 0.4 (the next level) of 50
            // every 100 samples
            match i {
                0..=99 => feed(&mut p, 0.3, 9.0),
                _ if i % 100 == 50 => feed(&mut p, 0.4, 50.0),
                _ => feed(&mut p, 0.3, 2.0),
            }
        }
        for _ in 0..300 {
            feed(&mut p, 0.4, 5.0);
        }
        let t = p.levels(0);
        assert_eq!(t.len(), 2, "{t:?}");
        assert_eq!((t[0].throttle, t[0].mean, t[0].std), (0.3, 2.0, 0.0));
        assert_eq!(t[0].samples, 900 - 9);
        assert_eq!((t[1].mean, t[1].samples), (5.0, 198));
        assert!(p.levels(1).is_empty(), "no rpm measured");
        assert_eq!(p.levels(2).len(), 2);
    }
}
