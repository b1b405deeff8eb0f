//! (to be written)

pub mod resample;
pub mod steps;
