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

/// One error path across the crates: a `pss` error is an `mcmc-core` error (a parameter out
/// of range), so code that builds PSS proposals and runs chains can use `?` on both.
impl From<PssError> for mcmc_core::McmcError {
    fn from(e: PssError) -> Self {
        match e {
            PssError::InvalidParameter {
                name,
                value,
                allowed,
            } => mcmc_core::McmcError::InvalidSetting {
                name,
                value,
                allowed,
            },
        }
    }
}
