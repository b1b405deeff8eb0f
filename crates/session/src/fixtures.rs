//! Test fixtures shared by the daemon's unit tests: a complete model report with short numbers.

use propid_numerics::ModelReport;
use serde_json::{json, Value};

/// A complete, stable 2nd-order model report (fn 12.5 Hz, ζ 0.5, DC gain 2, one pulse) with the
/// fields of `overrides` replaced.
pub fn report(overrides: Value) -> ModelReport {
    let mut base = json!({
        "order": 2, "dt_s": 0.001, "fn_hz": 12.5, "zeta": 0.5, "dc_gain": 2.0,
        "time_constants_s": [], "poles_s": [[-39.25, 68.0], [-39.25, -68.0]],
        "poles_z": [[0.96, 0.065], [0.96, -0.065]],
        "a": [[0.5, 0.25], [-0.25, 0.5]], "b": [[1.0], [0.0]], "c": [[1.0, 0.0]], "d": [[0.0]],
        "singular_values": [3.0, 1.0],
        "indicators": [{"msv": 3.0, "mac": 1.0, "emac": 0.5, "mpc": 1.0, "cmi": 0.5},
                       {"msv": 3.0, "mac": 1.0, "emac": 0.5, "mpc": 1.0, "cmi": 0.5}],
        "uncertainty": {"fn_hz": 0.25, "zeta": null, "dc_gain": 0.5},
        "pulses": 1, "pulses_skipped": 0, "missing_samples": 0, "noise_rms": 0.01,
        "mass_spring_damper": {"m": 0.25, "d": 0.125, "k": 0.5},
        "hankel_block_rows": 10, "hankel_block_cols": 10, "svd": "truncated"
    });
    if let (Some(b), Value::Object(o)) = (base.as_object_mut(), overrides) {
        b.extend(o);
    }
    serde_json::from_value(base).expect("a complete model report")
}
