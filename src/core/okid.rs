//! Observer/Kalman filter identification, OKID (owned by the okid part; placeholder).
