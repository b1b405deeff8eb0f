//! The identification core (no I/O). Placeholder module list until branch `core` lands; the
//! core engineer owns this file.

pub mod svd;
