//! SVD of block Hankel matrices. Placeholder until branch `core` lands (the core engineer owns
//! this file and the dense path / dispatch); the truncated FFT + Lanczos path lives in
//! [`truncated`] and [`hankel_op`].

pub mod hankel_op;
pub mod truncated;
