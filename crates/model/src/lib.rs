//! propid's model file (issue 30) without I/O: a model that outlives the command that made it.
//!
//! - [`file`]: the versioned schema ([`schema::SCHEMA`]), writing and reading its JSON text with
//!   an integrity check over the canonical content, and the checks a loaded model passes.
//! - [`terms`]: the extended model's terms as data, to and from `propid-diagnose`'s terms.
//! - [`simulate`]: free-run simulation of a loaded model on an input, the initial state
//!   estimated from the first outputs, and the per-output RMS and fit (`propid compare`).
//! - [`params`]: the numbers flight controllers and simulators take, from the stand's figures
//!   and static map (`propid params`).
//!
//! The schema is documented in docs/model_file.md, the parameters in docs/params.md.

pub mod file;
pub mod params;
pub mod schema;
pub mod simulate;
pub mod terms;

pub use file::ModelFile;
pub use schema::{ModelError, SCHEMA};
