//! SVG figures shared by more than one report (plotters, SVG backend): the stabilization
//! diagram of `identify --report` and `diagnose --report`; plain x–y charts (the experiment
//! kinds' run report of `run --report` and `replay --report`).

pub mod stabilization;
pub mod xy;
