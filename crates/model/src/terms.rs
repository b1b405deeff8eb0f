//! The extended model as data ([`Extended`]: its core and its terms, [`TermSpec`]): every
//! parameter of each effect's parameter struct in `propid_diagnose::effects`, so that the model
//! the file holds simulates exactly as the one `diagnose` fitted. [`to_specs`] reads a fitted
//! model's terms, [`TermSpec::to_term`] rebuilds one; [`model`] the whole
//! `propid_diagnose::model::Model`.

use propid_diagnose::effects::asymmetric_dynamics::AsymmetricDynamicsParams;
use propid_diagnose::effects::baseline_drift::BaselineDriftParams;
use propid_diagnose::effects::dead_time::DeadTimeParams;
use propid_diagnose::effects::extra_mode::ExtraModeParams;
use propid_diagnose::effects::periodic_disturbance::PeriodicDisturbanceParams;
use propid_diagnose::effects::saturation::{Clipped, SaturationParams};
use propid_diagnose::effects::static_nonlinearity::StaticNonlinearityParams;
use propid_diagnose::effects::stiffness_nonlinearity::StiffnessNonlinearityParams;
use propid_diagnose::effects::supply_sag::{Scaled, SupplySagParams};
use propid_diagnose::model::Model;
use propid_diagnose::signals::Core;
use propid_diagnose::term::{AsAny, Term};
use serde::{Deserialize, Serialize};

use crate::schema::ModelError;

/// `diagnose`'s model: its 2nd-order core and the terms of the effects found (none: the
/// baseline), enough to simulate it exactly (`propid_diagnose::model`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Extended {
    /// The core `T'' + 2ζωn T' + ωn² T = ωn² K v` and the output offset.
    pub core: CoreSpec,
    /// The terms, in the catalogue's order.
    pub terms: Vec<TermSpec>,
    /// The reference throttle of the static map `u_r`.
    pub u_ref: f64,
    /// The reference voltage of the supply term `V_r`, V (0 without a voltage).
    pub v_ref: f64,
}

/// The core of [`Extended`] (`propid_diagnose::signals::Core`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoreSpec {
    /// Natural frequency, Hz.
    pub fn_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Static gain `K`, output units per input unit.
    pub gain: f64,
    /// Output offset, output units.
    pub offset: f64,
    /// The input's lead, a share of a sample (0..1).
    pub lead: f64,
}

/// One term, tagged by its effect's published name (`"effect": "dead_time"`); the fields are
/// the parameter struct's (names and units in docs/model_file.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "effect", rename_all = "snake_case")]
pub enum TermSpec {
    /// A delay of whole samples, `sensor_samples` of them on the output's side.
    DeadTime {
        /// Samples.
        delay_samples: usize,
        /// Samples on the output's side.
        sensor_samples: usize,
    },
    /// `v = u_r (max(v, 0)/u_r)^p`.
    StaticNonlinearity {
        /// `p`.
        exponent: f64,
    },
    /// A 2nd-order mode in series.
    ExtraMode {
        /// Hz.
        fn_hz: f64,
        /// Damping ratio.
        zeta: f64,
        /// Share of the output through the mode.
        gain: f64,
    },
    /// `+ r t`.
    BaselineDrift {
        /// Output units per second.
        rate_per_s: f64,
    },
    /// `+ a sin ωt + b cos ωt`.
    PeriodicDisturbance {
        /// Hz.
        freq_hz: f64,
        /// `a`, output units.
        sin_coef: f64,
        /// `b`, output units.
        cos_coef: f64,
    },
    /// The supply voltage scales the drive and/or the output.
    SupplySag {
        /// 1/V.
        gain_per_volt: f64,
        /// `"drive"`, `"output"` or `"drive_and_output"`.
        scales: String,
        /// Share on the output, 0..1.
        output_share: f64,
    },
    /// A clip of the throttle or of the sensor.
    Saturation {
        /// Clip level (throttle, or output units).
        level: f64,
        /// `"throttle"` or `"sensor"`.
        clipped: String,
        /// A sensor clip: estimation samples that read the level (0 for a throttle clip).
        sensor_samples: usize,
    },
    /// A time scale per direction.
    AsymmetricDynamics {
        /// `ln(down/up)`.
        log_ratio: f64,
    },
    /// A cubic spring.
    StiffnessNonlinearity {
        /// `ε`, per output unit squared.
        k3_per_k1: f64,
        /// `Y²`, output units squared.
        scale_sq: f64,
    },
}

impl TermSpec {
    /// Of a fitted term (`None` for a term this schema does not know: a new effect needs its
    /// line here, and a test fails until it has one).
    pub fn of(t: &dyn Term) -> Option<TermSpec> {
        let any = <dyn Term as AsAny>::as_any(t);
        if let Some(p) = any.downcast_ref::<DeadTimeParams>() {
            return Some(TermSpec::DeadTime {
                delay_samples: p.delay_samples,
                sensor_samples: p.sensor_samples,
            });
        }
        if let Some(p) = any.downcast_ref::<StaticNonlinearityParams>() {
            return Some(TermSpec::StaticNonlinearity {
                exponent: p.exponent,
            });
        }
        if let Some(p) = any.downcast_ref::<ExtraModeParams>() {
            return Some(TermSpec::ExtraMode {
                fn_hz: p.fn_hz,
                zeta: p.zeta,
                gain: p.gain,
            });
        }
        if let Some(p) = any.downcast_ref::<BaselineDriftParams>() {
            return Some(TermSpec::BaselineDrift {
                rate_per_s: p.rate_per_s,
            });
        }
        if let Some(p) = any.downcast_ref::<PeriodicDisturbanceParams>() {
            return Some(TermSpec::PeriodicDisturbance {
                freq_hz: p.freq_hz,
                sin_coef: p.sin_coef,
                cos_coef: p.cos_coef,
            });
        }
        if let Some(p) = any.downcast_ref::<SupplySagParams>() {
            return Some(TermSpec::SupplySag {
                gain_per_volt: p.gain_per_volt,
                scales: p.scales.word().to_string(),
                output_share: p.output_share,
            });
        }
        if let Some(p) = any.downcast_ref::<SaturationParams>() {
            let (clipped, sensor_samples) = match p.clipped {
                Clipped::Throttle => ("throttle", 0),
                Clipped::Sensor { samples } => ("sensor", samples),
            };
            return Some(TermSpec::Saturation {
                level: p.level,
                clipped: clipped.to_string(),
                sensor_samples,
            });
        }
        if let Some(p) = any.downcast_ref::<AsymmetricDynamicsParams>() {
            return Some(TermSpec::AsymmetricDynamics {
                log_ratio: p.log_ratio,
            });
        }
        if let Some(p) = any.downcast_ref::<StiffnessNonlinearityParams>() {
            return Some(TermSpec::StiffnessNonlinearity {
                k3_per_k1: p.k3_per_k1,
                scale_sq: p.scale_sq,
            });
        }
        None
    }

    /// The term it describes.
    pub fn to_term(&self) -> Result<Box<dyn Term>, ModelError> {
        let bad = |s: String| Err(ModelError::Invalid(s));
        Ok(match self {
            TermSpec::DeadTime {
                delay_samples,
                sensor_samples,
            } => {
                if sensor_samples > delay_samples {
                    return bad("dead_time: sensor_samples above delay_samples".into());
                }
                Box::new(DeadTimeParams {
                    delay_samples: *delay_samples,
                    sensor_samples: *sensor_samples,
                })
            }
            TermSpec::StaticNonlinearity { exponent } => Box::new(StaticNonlinearityParams {
                exponent: *exponent,
            }),
            TermSpec::ExtraMode { fn_hz, zeta, gain } => Box::new(ExtraModeParams {
                fn_hz: *fn_hz,
                zeta: *zeta,
                gain: *gain,
            }),
            TermSpec::BaselineDrift { rate_per_s } => Box::new(BaselineDriftParams {
                rate_per_s: *rate_per_s,
            }),
            TermSpec::PeriodicDisturbance {
                freq_hz,
                sin_coef,
                cos_coef,
            } => Box::new(PeriodicDisturbanceParams {
                freq_hz: *freq_hz,
                sin_coef: *sin_coef,
                cos_coef: *cos_coef,
            }),
            TermSpec::SupplySag {
                gain_per_volt,
                scales,
                output_share,
            } => {
                let scales = match scales.as_str() {
                    "drive" => Scaled::Drive,
                    "output" => Scaled::Output,
                    "drive_and_output" => Scaled::Both,
                    other => return bad(format!("supply_sag: scales {other:?}")),
                };
                Box::new(SupplySagParams {
                    gain_per_volt: *gain_per_volt,
                    scales,
                    output_share: *output_share,
                })
            }
            TermSpec::Saturation {
                level,
                clipped,
                sensor_samples,
            } => {
                let clipped = match clipped.as_str() {
                    "throttle" => Clipped::Throttle,
                    "sensor" => Clipped::Sensor {
                        samples: *sensor_samples,
                    },
                    other => return bad(format!("saturation: clipped {other:?}")),
                };
                Box::new(SaturationParams {
                    level: *level,
                    clipped,
                })
            }
            TermSpec::AsymmetricDynamics { log_ratio } => Box::new(AsymmetricDynamicsParams {
                log_ratio: *log_ratio,
            }),
            TermSpec::StiffnessNonlinearity {
                k3_per_k1,
                scale_sq,
            } => Box::new(StiffnessNonlinearityParams {
                k3_per_k1: *k3_per_k1,
                scale_sq: *scale_sq,
            }),
        })
    }

    /// Whether the term reads the supply voltage.
    pub fn reads_voltage(&self) -> bool {
        matches!(self, TermSpec::SupplySag { .. })
    }
}

/// The terms of a fitted model, in its order (`Err` naming a term the schema does not know).
pub fn to_specs(m: &Model) -> Result<Vec<TermSpec>, ModelError> {
    m.terms()
        .map(|t| {
            TermSpec::of(t).ok_or_else(|| {
                ModelError::Invalid(format!(
                    "effect {} has no place in schema {}",
                    t.name().as_str(),
                    crate::SCHEMA
                ))
            })
        })
        .collect()
}

/// The extended section of a fitted model with reference throttle and voltage `refs`.
pub fn extended_of(m: &Model, refs: [f64; 2]) -> Result<Extended, ModelError> {
    let c = m.core;
    Ok(Extended {
        core: CoreSpec {
            fn_hz: c.fn_hz,
            zeta: c.zeta,
            gain: c.gain,
            offset: c.offset,
            lead: c.lead,
        },
        terms: to_specs(m)?,
        u_ref: refs[0],
        v_ref: refs[1],
    })
}

/// The `propid_diagnose` model an extended section describes.
pub fn model(e: &Extended) -> Result<Model, ModelError> {
    let c = e.core;
    let mut m = Model::new(Core {
        fn_hz: c.fn_hz,
        zeta: c.zeta,
        gain: c.gain,
        offset: c.offset,
        lead: c.lead,
    });
    for t in &e.terms {
        m = m.with_boxed(t.to_term()?);
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One spec of every effect.
    pub(crate) fn every() -> Vec<TermSpec> {
        vec![
            TermSpec::DeadTime {
                delay_samples: 3,
                sensor_samples: 1,
            },
            TermSpec::StaticNonlinearity { exponent: 1.4 },
            TermSpec::ExtraMode {
                fn_hz: 30.0,
                zeta: 0.2,
                gain: 0.1,
            },
            TermSpec::BaselineDrift { rate_per_s: 0.01 },
            TermSpec::PeriodicDisturbance {
                freq_hz: 50.0,
                sin_coef: 0.02,
                cos_coef: -0.01,
            },
            TermSpec::SupplySag {
                gain_per_volt: 0.05,
                scales: "drive_and_output".into(),
                output_share: 0.3,
            },
            TermSpec::Saturation {
                level: 9.5,
                clipped: "sensor".into(),
                sensor_samples: 12,
            },
            TermSpec::AsymmetricDynamics { log_ratio: 0.4 },
            TermSpec::StiffnessNonlinearity {
                k3_per_k1: 0.003,
                scale_sq: 2.0,
            },
        ]
    }

    #[test]
    fn every_effect_of_the_catalogue_goes_to_the_file_and_back_unchanged() {
        let specs = every();
        let names: Vec<&str> = propid_diagnose::effects::names()
            .map(|n| n.as_str())
            .collect();
        assert_eq!(names.len(), specs.len(), "a new effect needs its TermSpec");
        for s in specs {
            let t = s.to_term().unwrap();
            assert_eq!(TermSpec::of(t.as_ref()).as_ref(), Some(&s));
            let text = serde_json::to_string(&s).unwrap();
            assert!(text.contains(t.name().as_str()), "{text}");
            let back: TermSpec = serde_json::from_str(&text).unwrap();
            assert_eq!(back, s);
        }
    }

    #[test]
    fn an_unknown_word_is_refused() {
        let s = TermSpec::Saturation {
            level: 1.0,
            clipped: "both".into(),
            sensor_samples: 0,
        };
        assert!(s.to_term().is_err());
    }
}
