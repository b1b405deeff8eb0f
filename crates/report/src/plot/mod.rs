//! SVG figures shared by more than one report (plotters, SVG backend): the stabilization
//! diagram of `identify --report` and `diagnose --report`.

pub mod stabilization;
