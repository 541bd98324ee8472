//! Why a build's parameters are refused, naming the field: each method's
//! parameters check themselves against their own ranges (written once, next
//! to their defaults) with [`in_range`], and the CLI, recipes and the studio
//! read the same ranges.

use std::fmt::Display;
use std::ops::RangeInclusive;

/// A parameter out of its range, by name.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct ParamError {
    /// The parameter's name as its struct writes it (`kappa`, `min_quality`);
    /// the CLI shows it as its flag.
    pub field: &'static str,
    pub message: String,
}

impl ParamError {
    pub fn new(field: &'static str, message: impl Into<String>) -> ParamError {
        ParamError {
            field,
            message: message.into(),
        }
    }

    /// The field as a command-line flag: `min_quality` → `--min-quality`.
    pub fn flag(&self) -> String {
        format!("--{}", self.field.replace('_', "-"))
    }
}

/// `value` inside `range` (NaN never is), or the error naming `field`.
pub fn in_range<T: PartialOrd + Display>(
    field: &'static str,
    value: T,
    range: &RangeInclusive<T>,
) -> Result<(), ParamError> {
    if range.contains(&value) {
        return Ok(());
    }
    Err(ParamError::new(
        field,
        format!(
            "must be in {}..={}, got {value}",
            range.start(),
            range.end()
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_refuse_nan_and_name_the_field() {
        assert!(in_range("kappa", 3.0, &(1.0..=16.0)).is_ok());
        let e = in_range("min_quality", f32::NAN, &(0.0..=1.0)).unwrap_err();
        assert_eq!(e.to_string(), "min_quality: must be in 0..=1, got NaN");
        assert_eq!(e.flag(), "--min-quality");
        assert!(in_range("k", 2usize, &(3..=1000)).is_err());
    }
}
