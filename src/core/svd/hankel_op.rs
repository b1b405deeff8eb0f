//! Hankel operator applied through FFT convolution (owned by the svd part; placeholder).
