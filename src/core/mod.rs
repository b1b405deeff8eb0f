//! (to be written)

pub mod okid;
