//! Models per operating point (owned by the okid part; placeholder).
