//! Truncated Hankel SVD by FFT products and Lanczos (owned by the svd part; placeholder).
