//! The error type of `mcmc-core`, returned at its boundaries (constructors and the chain driver).

use thiserror::Error;

/// Errors reported by `mcmc-core` constructors and by [`crate::Chain`].
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum McmcError {
    /// A target returned NaN or `+inf` as a log density. The candidate was rejected and the
    /// chain kept its state; the target has a bug (or a numerical problem) that must be fixed.
    #[error("target returned a non-finite log density ({value}) at stage {stage}; the candidate was rejected")]
    NonFiniteDensity {
        /// The offending value (NaN or +inf).
        value: f64,
        /// Kernel stage (1-based) whose candidate produced it; 0 for the initial state.
        stage: u8,
    },
    /// A proposal returned a NaN Hastings term.
    #[error("proposal returned a NaN Hastings term at stage {stage}; the candidate was rejected")]
    NonFiniteHastings {
        /// Kernel stage (1-based).
        stage: u8,
    },
    /// The initial state of a chain has zero density: MCMC cannot start there.
    #[error("the initial state has zero target density; start chains from a state with positive density")]
    ZeroDensityStart,
    /// A parameter is outside its allowed range.
    #[error("parameter `{name}` = {value} is outside its allowed range {allowed}")]
    InvalidParameter {
        /// Parameter name, as spelled in the params struct.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// A human-readable description of the allowed range.
        allowed: &'static str,
    },
    /// A setting is outside its allowed range (value not a number, e.g. a list or a name; also
    /// what other crates' parameter errors convert into).
    #[error("setting `{name}` = {value} is outside its allowed range {allowed}")]
    InvalidSetting {
        /// Setting name.
        name: &'static str,
        /// The rejected value, formatted.
        value: String,
        /// A human-readable description of the allowed range.
        allowed: &'static str,
    },
}

impl McmcError {
    /// Checks `lo <= value <= hi` (and finiteness), naming the parameter otherwise.
    pub fn check_range(
        name: &'static str,
        value: f64,
        lo: f64,
        hi: f64,
        allowed: &'static str,
    ) -> Result<(), McmcError> {
        if value.is_finite() && value >= lo && value <= hi {
            Ok(())
        } else {
            Err(McmcError::InvalidParameter {
                name,
                value,
                allowed,
            })
        }
    }
}
