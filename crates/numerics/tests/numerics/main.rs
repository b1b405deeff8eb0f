//! The numerics crate's integration tests, one binary: exact recovery, noise, indicators, errors, OKID and the SVDs.

mod core_errors;
mod core_exact;
mod core_indicators;
mod core_low_snr;
mod core_noise;
mod core_order_settles;
mod okid_identify;
mod okid_noise;
mod okid_recovery;
mod stabilization;
mod svd_accuracy;
mod svd_products;
