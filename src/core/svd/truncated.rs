//! Truncated SVD (in progress).
