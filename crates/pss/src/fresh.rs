//! Independent points of primary sample space for the render loop: fresh lazy states from keys.

use mcmc_core::render_loop::IndependentStates;

use crate::state::{PssState, MAX_STREAMS};
use crate::PssError;

/// The independent states of a primary-sample-space render loop: a fresh [`PssState`] whose
/// coordinates are uniforms drawn from the key when first read (a large step from nowhere).
/// Its bootstrap weight is `f(u)` (the default of [`IndependentStates::weight`]: points are
/// uniform on the unit hypercube, density 1), so the bootstrap mean estimates
/// `b = integral of f over [0, 1)^n` (Kelemen et al. 2002, eq. 5).
///
/// # Example
/// ```
/// use mcmc_core::render_loop::IndependentStates;
/// use pss::{FreshPss, PssState};
///
/// let fresh = FreshPss::new(3).unwrap();
/// let (mut a, mut b) = (fresh.empty(), fresh.empty());
/// fresh.independent(42, &mut a);
/// fresh.independent(42, &mut b);
/// assert_eq!(a.stream_values(1, 4), b.stream_values(1, 4)); // same key, same point
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FreshPss {
    streams: usize,
}

impl FreshPss {
    /// Fresh states with `streams` streams (1..=4).
    ///
    /// # Errors
    /// [`PssError::InvalidParameter`] if `streams` is out of range.
    pub fn new(streams: usize) -> Result<Self, PssError> {
        if !(1..=MAX_STREAMS).contains(&streams) {
            return Err(PssError::InvalidParameter {
                name: "streams",
                value: streams.to_string(),
                allowed: "1..=4",
            });
        }
        Ok(Self { streams })
    }

    /// Number of streams.
    #[must_use]
    pub fn streams(&self) -> usize {
        self.streams
    }
}

impl IndependentStates<PssState> for FreshPss {
    fn empty(&self) -> PssState {
        PssState::new(self.streams, 0)
    }

    fn independent(&self, key: u64, state: &mut PssState) {
        state.reset(self.streams, key);
    }
}
