//! The error type of the `pss` crate.

use thiserror::Error;

/// Errors from `pss` constructors.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum PssError {
    /// A parameter is outside its allowed range.
    #[error("parameter `{name}` = {value} is outside its allowed range {allowed}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The rejected value, formatted.
        value: String,
        /// The allowed range.
        allowed: &'static str,
    },
}
