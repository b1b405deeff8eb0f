//! What `propid identify` prints: the file as identify reads it ([`load`]), the stand's
//! physics beside the model ([`Physics`]), the JSON object and the human summary
//! ([`summary`]) with its tables ([`stand`]).

pub mod load;
pub mod stand;
pub mod summary;

use propid_numerics::segment::Command;
use propid_numerics::stand::{channel_step_timing, ChannelTiming, OutputChannel};
use propid_numerics::stand_model::fit::{fit, Channel, FitInput};
use propid_numerics::stand_model::report::{Stand, StandRefused};
use propid_numerics::stand_model::Quantity;

/// The stand's physics (`"stand"`, [`propid_numerics::stand_model`]) and each step's timing
/// on every output channel, when the input is a stand's command; `None`, `[]` otherwise.
#[derive(Debug, Clone, Default)]
pub struct Physics {
    /// The stand model fitted to every channel of the stand the file has, or why not.
    pub stand: Option<Stand>,
    /// Per command step, its dead time and time constant on each channel.
    pub timing: Vec<std::collections::BTreeMap<&'static str, ChannelTiming>>,
}

impl Physics {
    pub fn of(loaded: &load::Loaded) -> Physics {
        if !(loaded.commanded && loaded.input_is_a_command) {
            return Physics::default();
        }
        let rules = loaded.segment_rules();
        let cmd = Command::with_missing(&loaded.input, &loaded.missing);
        let outputs: Vec<OutputChannel<'_>> = loaded
            .stand
            .iter()
            .map(|(key, unit, y)| OutputChannel { key, unit, y })
            .collect();
        let timing = channel_step_timing(cmd, loaded.dt_s, &rules, &outputs);
        let quantity = |key: &str| match key {
            "rpm" => Some(Quantity::Speed),
            "thrust" => Some(Quantity::Thrust),
            "torque" => Some(Quantity::Torque),
            "current" => Some(Quantity::Current),
            _ => None,
        };
        let channels: Vec<Channel<'_>> = loaded
            .stand
            .iter()
            .zip(&loaded.stand_interpolated)
            .filter_map(|((key, _, y), flags)| {
                Some(Channel {
                    key,
                    quantity: quantity(key)?,
                    y,
                    interpolated: flags,
                })
            })
            .collect();
        if rules.samples_are_steady() {
            let refused = StandRefused {
                refused: "a sample lasts longer than the response takes to settle: the record \
                          shows no dynamics"
                    .to_string(),
            };
            return Physics {
                stand: Some(Stand::Refused(refused)),
                timing,
            };
        }
        let input = FitInput {
            dt_s: loaded.dt_s,
            command: &loaded.input,
            voltage: loaded.voltage.as_deref(),
            channels: &channels,
            rules,
        };
        Physics {
            stand: Some(Stand::of(fit(&input))),
            timing,
        }
    }
}
