//! The catalogue of effects (issue 5): one file per effect, each with its parameter struct
//! (see [`super::effect`] for what an effect provides), and the registry that lists them.
//!
//! Adding an effect: a new file here implementing [`Effect`] and [`super::effect::Term`], and
//! one line in [`REGISTRY`].

pub mod asymmetric_dynamics;
pub mod baseline_drift;
pub mod dead_time;
pub mod extra_mode;
pub mod periodic_disturbance;
pub mod saturation;
pub mod static_nonlinearity;
pub mod stiffness_nonlinearity;
pub mod supply_sag;

use super::effect::Effect;
use propid_numerics::EffectName;

/// Every effect, in catalogue order: the order the search tries them in (ties go to the
/// first), the order of their free parameters in a model, and the order of terms that act at
/// the same place on the signal path.
pub static REGISTRY: &[&dyn Effect] = &[
    &dead_time::DeadTime,
    &static_nonlinearity::StaticNonlinearity,
    &extra_mode::ExtraMode,
    &baseline_drift::BaselineDrift,
    &periodic_disturbance::PeriodicDisturbance,
    &supply_sag::SupplySag,
    &saturation::Saturation,
    &asymmetric_dynamics::AsymmetricDynamics,
    &stiffness_nonlinearity::StiffnessNonlinearity,
];

/// The names of the effects, in catalogue order.
pub fn names() -> impl Iterator<Item = EffectName> {
    REGISTRY.iter().map(|e| e.name())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_registry_lists_every_effect_in_catalogue_order() {
        let generic: Vec<EffectName> = EffectName::ALL
            .into_iter()
            .filter(|e| !e.stand_only())
            .collect();
        assert_eq!(names().collect::<Vec<_>>(), generic);
        let names: Vec<&str> = names().map(EffectName::as_str).collect();
        assert_eq!(
            names,
            [
                "dead_time",
                "static_nonlinearity",
                "extra_mode",
                "baseline_drift",
                "periodic_disturbance",
                "supply_sag",
                "saturation",
                "asymmetric_dynamics",
                "stiffness_nonlinearity",
            ]
        );
    }
}
