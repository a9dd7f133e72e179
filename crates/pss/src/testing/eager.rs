//! The eager proposal wrapper: materialises a lazy PSS candidate right after it is proposed.

use mcmc_core::{Proposal, Proposed};
use rand::Rng;

use crate::PssState;

/// Forces the candidate's lazy mutation right after `propose`: every stored coordinate of the
/// candidate is brought up to date ([`PssState::materialize`]) before the target reads it.
///
/// Two uses:
/// - proposal checks ([`mcmc_core::testing::assert_symmetric_proposal`],
///   [`mcmc_core::testing::assert_hastings_consistent`]) compare `log_q(x, y)` with what
///   `propose` reports, and `log_q` reads raw coordinates: on an unread lazy candidate they
///   are still `x`'s values;
/// - the reference of lazy-versus-eager tests: eager mutation perturbs every stored
///   coordinate at every proposal, which is what lazy mutation must equal in distribution.
///
/// Coordinates beyond the stored length are not created: a target that reads further still
/// grows the candidate lazily.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Eager<P>(pub P);

impl<P: Proposal<PssState>> Proposal<PssState> for Eager<P> {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        let proposed = self.0.propose(x, y, rng);
        y.materialize();
        proposed
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        self.0.log_q(from, to)
    }

    fn is_symmetric(&self) -> bool {
        self.0.is_symmetric()
    }

    fn num_components(&self) -> usize {
        self.0.num_components()
    }

    fn log_q_component(&self, j: usize, from: &PssState, to: &PssState) -> f64 {
        self.0.log_q_component(j, from, to)
    }

    fn log_hastings(&self, j: usize, x: &PssState, y: &PssState) -> f64 {
        self.0.log_hastings(j, x, y)
    }
}
