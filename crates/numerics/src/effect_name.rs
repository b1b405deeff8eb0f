//! The names of the effects the discrepancy engine knows (`propid-diagnose`): one enum, used by
//! the engine, the simulated stand's effects, the test kit's injections and the examples.

use serde::{Deserialize, Serialize};

/// One physical effect a 2nd-order model may be missing. Declared in catalogue order (the
/// order the search tries them in, ties to the first): `Ord` follows it. The published names
/// (`as_str`, serde) are a public interface, never renamed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectName {
    /// A pure delay of the input.
    DeadTime,
    /// A power law of the throttle.
    StaticNonlinearity,
    /// A second resonance in the load-cell path.
    ExtraMode,
    /// A linear drift of the output.
    BaselineDrift,
    /// A sinusoid added to the output.
    PeriodicDisturbance,
    /// A gain following the supply voltage.
    SupplySag,
    /// A clipped input or output.
    Saturation,
    /// Spin-up and spin-down on different time scales.
    AsymmetricDynamics,
    /// A cubic stiffness in the core.
    StiffnessNonlinearity,
    /// One channel's sensor reads late and through a lag of its own (a load cell's filter),
    /// relative to the others (stand baseline only).
    SensorLag,
    /// The rotor's time constant changes with its speed (stand baseline only).
    SpeedDependentTau,
}

impl EffectName {
    /// Every effect, in catalogue order.
    pub const ALL: [EffectName; 11] = [
        EffectName::DeadTime,
        EffectName::StaticNonlinearity,
        EffectName::ExtraMode,
        EffectName::BaselineDrift,
        EffectName::PeriodicDisturbance,
        EffectName::SupplySag,
        EffectName::Saturation,
        EffectName::AsymmetricDynamics,
        EffectName::StiffnessNonlinearity,
        EffectName::SensorLag,
        EffectName::SpeedDependentTau,
    ];

    /// The published name (`"dead_time"`, ...).
    pub const fn as_str(self) -> &'static str {
        match self {
            EffectName::DeadTime => "dead_time",
            EffectName::StaticNonlinearity => "static_nonlinearity",
            EffectName::ExtraMode => "extra_mode",
            EffectName::BaselineDrift => "baseline_drift",
            EffectName::PeriodicDisturbance => "periodic_disturbance",
            EffectName::SupplySag => "supply_sag",
            EffectName::Saturation => "saturation",
            EffectName::AsymmetricDynamics => "asymmetric_dynamics",
            EffectName::StiffnessNonlinearity => "stiffness_nonlinearity",
            EffectName::SensorLag => "sensor_lag",
            EffectName::SpeedDependentTau => "speed_dependent_tau",
        }
    }

    /// Whether the effect extends only a stand baseline (`propid diagnose` on a motor stand's
    /// channels), never the generic 2nd-order model.
    pub const fn stand_only(self) -> bool {
        matches!(self, EffectName::SensorLag | EffectName::SpeedDependentTau)
    }

    /// The effect published as `name`; `None` for a name no effect has.
    pub fn from_name(name: &str) -> Option<EffectName> {
        EffectName::ALL.into_iter().find(|e| e.as_str() == name)
    }
}

impl std::fmt::Display for EffectName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serde_names_are_the_published_names_in_catalogue_order() {
        for (i, e) in EffectName::ALL.into_iter().enumerate() {
            let json = serde_json::to_string(&e).unwrap();
            assert_eq!(json, format!("\"{}\"", e.as_str()));
            assert_eq!(serde_json::from_str::<EffectName>(&json).unwrap(), e);
            assert_eq!(EffectName::from_name(e.as_str()), Some(e));
            if i > 0 {
                assert!(EffectName::ALL[i - 1] < e);
            }
        }
        assert_eq!(EffectName::from_name("clean"), None);
    }
}
