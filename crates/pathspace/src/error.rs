//! The crate's error type, used at its boundaries (constructors).

/// Errors of the `pathspace` crate.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum PathspaceError {
    /// A parameter is outside its allowed range.
    #[error("{name} = {value} is out of range (allowed: {allowed})")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// The allowed range.
        allowed: String,
    },
    /// A scene description is unusable (e.g. no emitter).
    #[error("invalid scene: {0}")]
    InvalidScene(String),
}

impl PathspaceError {
    /// `Ok` if `lo <= value <= hi` (and not NaN), else [`PathspaceError::InvalidParameter`].
    ///
    /// # Errors
    /// As described.
    pub fn check_range(name: &'static str, value: f64, lo: f64, hi: f64) -> Result<(), Self> {
        if value >= lo && value <= hi {
            Ok(())
        } else {
            Err(Self::InvalidParameter {
                name,
                value,
                allowed: format!("[{lo}, {hi}]"),
            })
        }
    }
}
