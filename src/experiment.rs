//! Host-side experiment plan (to be written).
