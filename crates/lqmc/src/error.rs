//! The error type of the `lqmc` crate.

use thiserror::Error;

/// Errors from `lqmc` constructors (lattices, tilings, estimators).
///
/// The hot paths (radical inverses, closest-point search, [`crate::LocalQmc::explore`]) never
/// return errors: they are validated once, at construction.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum LqmcError {
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
    /// Two objects that must agree on their number of dimensions do not.
    #[error("dimension mismatch: {what} has {found} dimensions, expected {expected}")]
    DimensionMismatch {
        /// What was checked.
        what: &'static str,
        /// Its number of dimensions.
        found: usize,
        /// The number required.
        expected: usize,
    },
    /// No embedded generator vector for this lattice size and dimension
    /// (see [`crate::TABLE_SIZES`] and [`crate::TABLE_MAX_DIMS`]).
    #[error("no embedded rank-1 lattice for N = {points}, s = {dims}")]
    NotInTable {
        /// The requested number of points.
        points: u32,
        /// The requested number of dimensions.
        dims: usize,
    },
}

impl LqmcError {
    pub(crate) fn invalid(name: &'static str, value: impl ToString, allowed: &'static str) -> Self {
        LqmcError::InvalidParameter {
            name,
            value: value.to_string(),
            allowed,
        }
    }
}
