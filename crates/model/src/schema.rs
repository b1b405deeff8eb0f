//! The schema this version of the model file writes and reads ([`SCHEMA`]), and why a file is
//! refused ([`ModelError`]).

/// The schema this version writes and reads.
pub const SCHEMA: &str = "propid-model/1";

/// Why a model file is refused.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// Not a JSON object.
    #[error("not a propid model file: {0}")]
    NotJson(String),
    /// Another schema, or none.
    #[error("schema {found:?}: this propid reads {SCHEMA:?} model files only")]
    Schema {
        /// The `schema` found (`"none"` without one).
        found: String,
    },
    /// The checksum does not match the content.
    #[error(
        "the checksum does not match the content (stored {stored}, computed {computed}): the \
         file was changed after propid wrote it"
    )]
    Tampered {
        /// The stored checksum.
        stored: String,
        /// The checksum of the content.
        computed: String,
    },
    /// The content does not hold together (a matrix of the wrong size, no model at all).
    #[error("invalid model: {0}")]
    Invalid(String),
}
