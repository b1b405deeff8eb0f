//! The discrepancy engine on records in memory: the simulated stand's cases (every effect of
//! the catalogue, clean plants), records with gaps and clips, the verdicts.

mod calibrated;
mod detection;
mod record;
mod staircase;
mod stand_cases;
mod verdict;
