//! (to be written)

pub mod effects;
pub mod plant;
