//! The sizes a [`super::Workspace`] is built for ([`Limits`]).

/// Sizes a [`super::Workspace`] is built for. Inputs beyond them give
/// [`crate::IdentError::LimitsExceeded`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Limits {
    /// Longest record (samples) or Markov sequence (blocks).
    pub max_samples: usize,
    /// Most output channels `q` (at most 64).
    pub max_outputs: usize,
    /// Most inputs `p` (pulse experiments have 1).
    pub max_inputs: usize,
    /// Highest model order.
    pub max_order: usize,
    /// Most Hankel block rows `r`.
    pub max_block_rows: usize,
    /// Most Hankel block columns `c`.
    pub max_block_cols: usize,
    /// Most pulses in one record.
    pub max_pulses: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_samples: 8192,
            max_outputs: 3,
            max_inputs: 1,
            max_order: 12,
            max_block_rows: 128,
            max_block_cols: 128,
            max_pulses: 256,
        }
    }
}
