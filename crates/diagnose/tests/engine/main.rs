//! The discrepancy engine on records in memory: the simulated stand's cases (every effect of
//! the catalogue, clean plants), records with gaps and clips, the verdicts; and on files' bytes
//! read as `propid diagnose` reads them (`read.rs`): stand exports in their own units, effects
//! hidden in real logs and in a stand's export.

mod calibrated;
mod detection;
mod hidden_sag;
mod injected;
mod input_lead;
mod outliers;
mod read;
mod record;
mod rejected;
mod staircase;
mod stand_cases;
mod stand_lag;
mod units;
mod verdict;
