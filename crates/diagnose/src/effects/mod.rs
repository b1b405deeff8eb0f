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

/// The published names of the effects, in catalogue order.
pub fn names() -> impl Iterator<Item = &'static str> {
    REGISTRY.iter().map(|e| e.name())
}

/// Position of effect `name` in the registry (past the end for a name it does not list).
pub fn position(name: &str) -> usize {
    names().position(|n| n == name).unwrap_or(REGISTRY.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_published_names_are_kept_in_catalogue_order() {
        let names: Vec<&str> = names().collect();
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
        assert_eq!(position("extra_mode"), 2);
        assert_eq!(position("no_such_effect"), REGISTRY.len());
    }
}
