//! The host-side experiment plan (issue 3, item 4): a pure state machine, no I/O and no clock of
//! its own. It is handed the host's `now_us` and the frames the device sent; it says which
//! commands to send and tells the caller what happened (a level done, the end, a device reset,
//! a failed link).

mod config;

pub use config::{ExperimentConfig, ExperimentConfigError};
