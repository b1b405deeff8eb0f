//! Range checks of the configuration's values: positive (`lo <= x <= hi`, a float also
//! finite, so NaN is refused), naming the key and the value on failure.

use super::ConfigError;

/// Checks an integer range; names the key and the value on failure.
pub fn int_in<T>(
    key: &'static str,
    v: T,
    lo: T,
    hi: T,
    expected: &'static str,
) -> Result<T, ConfigError>
where
    T: PartialOrd + std::fmt::Display + Copy,
{
    if lo <= v && v <= hi {
        Ok(v)
    } else {
        Err(ConfigError::OutOfRange {
            key,
            value: v.to_string(),
            expected,
        })
    }
}

/// Checks a float range positively (`finite && lo <= x <= hi`), so NaN is refused.
pub fn float_in(
    key: &'static str,
    v: f64,
    lo: f64,
    hi: f64,
    expected: &'static str,
) -> Result<f64, ConfigError> {
    if v.is_finite() && lo <= v && v <= hi {
        Ok(v)
    } else {
        Err(ConfigError::OutOfRange {
            key,
            value: v.to_string(),
            expected,
        })
    }
}
