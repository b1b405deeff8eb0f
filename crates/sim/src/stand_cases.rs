//! Seeded simulated-stand cases for the acceptance harness of `diagnose` (issue 29 items 4 and
//! 6): the plants and hidden effects of [`crate::synth`] under three kinds of record (pulses
//! about operating points, steps, a Tyto-style staircase), and the truth a finding is held to.

use propid_numerics::EffectName;
use rand::rngs::StdRng;
use rand::SeedableRng;

use crate::plant::{PlantConfig, PlantError};
use crate::synth::{self, hide_effect, random_plant, Measured, DT_S};

/// The kind of record a case is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordKind {
    /// [`synth::throttle_plan`]: five operating points with short pulses (15 s).
    Pulse,
    /// Eight levels of 1.5 s, steps up and down of 0.10–0.42 (12 s).
    Step,
    /// Up from 0.30 to 0.72 in steps of 0.06, then down in two steps (0.51, 0.30), 1 s
    /// each (10 s): the shape of a stand's step test.
    Staircase,
}

impl RecordKind {
    /// Every kind, in table order.
    pub const ALL: [RecordKind; 3] = [RecordKind::Pulse, RecordKind::Step, RecordKind::Staircase];

    /// Name in tables.
    pub fn as_str(self) -> &'static str {
        match self {
            RecordKind::Pulse => "pulse",
            RecordKind::Step => "step",
            RecordKind::Staircase => "staircase",
        }
    }

    /// The throttle sequence, one value per sample of [`DT_S`].
    pub fn plan(self) -> Vec<f64> {
        let held = |levels: &[f64], s: f64| -> Vec<f64> {
            let per = (s / DT_S).round() as usize;
            levels
                .iter()
                .flat_map(|&l| std::iter::repeat(l).take(per))
                .collect()
        };
        match self {
            RecordKind::Pulse => synth::throttle_plan(),
            RecordKind::Step => held(&[0.35, 0.6, 0.4, 0.72, 0.45, 0.55, 0.3, 0.65], 1.5),
            RecordKind::Staircase => held(
                &[0.30, 0.36, 0.42, 0.48, 0.54, 0.60, 0.66, 0.72, 0.51, 0.30],
                1.0,
            ),
        }
    }
}

/// Case `i` of `kind` with effect `name` hidden (`None`: clean): a seeded random plant of
/// [`random_plant`] (overdamped for odd `i`), the effect's parameters drawn by
/// [`hide_effect`], run through [`RecordKind::plan`].
pub fn case(
    kind: RecordKind,
    name: Option<EffectName>,
    i: u64,
) -> Result<(PlantConfig, Measured), PlantError> {
    let len = name.map_or("clean", EffectName::as_str).len() as u64;
    let k = RecordKind::ALL.iter().position(|&x| x == kind).unwrap_or(0) as u64;
    let seed = 0x57a0_0000 + k * 1_000_003 + i * 7919 + len * 104_729;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut cfg = random_plant(&mut rng, i % 2 == 1);
    if let Some(name) = name {
        hide_effect(&mut cfg, name, &mut rng);
    }
    let m = synth::run(&cfg, &kind.plan(), seed ^ 0xabcdef)?;
    Ok((cfg, m))
}

/// The parameter a finding of an effect is held to: the key of the finding's parameters, the
/// true value, and the tolerance (absolute or relative).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Key in the finding's parameters.
    pub key: &'static str,
    /// The true value in the finding's terms.
    pub value: f64,
    /// Largest error accepted.
    pub tolerance: f64,
    /// Whether the error is relative to `value`.
    pub relative: bool,
}

impl Truth {
    /// The error of an estimate (relative or absolute as the truth says).
    pub fn error(&self, estimate: f64) -> f64 {
        let e = (estimate - self.value).abs();
        if self.relative {
            e / self.value.abs()
        } else {
            e
        }
    }

    /// Whether an estimate is within the tolerance.
    pub fn holds(&self, estimate: f64) -> bool {
        self.error(estimate) <= self.tolerance
    }
}

/// The truth of the main parameter of effect `name` hidden in `cfg` (the tolerances of
/// `docs/detection.md`); `v_mean` is the record's mean supply voltage (`diagnose` reports a
/// supply sag's gain at it: `g / (1 + g (V̄ − battery_v))`). `None` when `cfg` does not hide
/// `name`.
pub fn truth(name: EffectName, cfg: &PlantConfig, v_mean: f64) -> Option<Truth> {
    let e = &cfg.effects;
    let t = |key, value, tolerance, relative| Truth {
        key,
        value,
        tolerance,
        relative,
    };
    Some(match name {
        EffectName::DeadTime => t(
            "delay_samples",
            (e.dead_time.as_ref()?.delay_s / DT_S).round(),
            1.0,
            false,
        ),
        EffectName::StaticNonlinearity => t(
            "exponent",
            e.static_nonlinearity.as_ref()?.exponent,
            0.10,
            true,
        ),
        EffectName::ExtraMode => t("fn_hz", e.extra_mode.as_ref()?.fn_hz, 0.05, true),
        EffectName::BaselineDrift => t(
            "rate_per_s",
            e.baseline_drift.as_ref()?.rate_per_s,
            0.15,
            true,
        ),
        EffectName::PeriodicDisturbance => t(
            "amplitude",
            e.periodic_disturbance.as_ref()?.amplitude,
            0.15,
            true,
        ),
        EffectName::SupplySag => {
            let g = e.supply_sag.as_ref()?.gain_per_volt;
            t(
                "gain_per_volt",
                g / (1.0 + g * (v_mean - cfg.battery_v)),
                0.03,
                true,
            )
        }
        EffectName::Saturation => t("level", e.saturation.as_ref()?.level, 0.01, false),
        EffectName::AsymmetricDynamics => {
            let a = e.asymmetric_dynamics.as_ref()?;
            t("down_over_up", a.down_scale / a.up_scale, 0.10, true)
        }
        EffectName::StiffnessNonlinearity => t(
            "k3_per_k1",
            e.stiffness_nonlinearity.as_ref()?.k3_per_k1,
            0.15,
            true,
        ),
        // Effects of the stand baseline only: never hidden in this plant.
        EffectName::SensorLag | EffectName::SpeedDependentTau => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_numerics::segment::{levels, steps, Command, SegmentRules};

    #[test]
    fn every_kind_has_steps_and_levels_the_segmentation_sees() {
        for kind in RecordKind::ALL {
            let u = kind.plan();
            let rules = SegmentRules::for_record(DT_S, true);
            assert!(levels(Command::new(&u), &rules).len() >= 5, "{kind:?}");
            assert!(steps(Command::new(&u), &rules).len() >= 4, "{kind:?}");
            // a throttle saturation (0.6–0.7) is reached by every kind
            assert!(u.iter().any(|&x| x > 0.7), "{kind:?}");
        }
    }

    #[test]
    fn a_truth_is_held_to_its_tolerance() {
        let t = Truth {
            key: "x",
            value: 2.0,
            tolerance: 0.1,
            relative: true,
        };
        assert!(t.holds(2.19) && !t.holds(2.21) && !t.holds(-2.0));
        let (cfg, _) = case(RecordKind::Step, Some(EffectName::DeadTime), 0).unwrap();
        let d = truth(EffectName::DeadTime, &cfg, 16.0).unwrap();
        assert!(d.holds(d.value + 1.0) && !d.holds(d.value + 2.0));
        assert!(truth(EffectName::Saturation, &cfg, 16.0).is_none());
    }
}
