//! (to be written)

pub mod csv_file;
pub mod resample;
pub mod steps;
