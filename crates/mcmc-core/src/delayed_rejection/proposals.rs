//! Simple stages for delayed rejection: a second stage that ignores the rejected candidate, and
//! a Gaussian walk on the unit torus with its exact wrapped density.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::proposal::{ConditionalProposal, Proposal, Proposed};
use crate::torus::{wrap, wrapped_normal_pdf};
use crate::McmcError;

/// A second stage that ignores the rejected candidate: `z ~ P(. | x)`, so
/// `Q2(z | x, y) = P(z | x)` (e.g. the reference implementation's timid Gaussian second stage
/// of the Tierney-Mira and Green-Mira variants, sigma = first-stage sigma / 10).
/// Symmetric when `P` is: then use
/// [`super::DelayedRejection::with_symmetric_second_stage`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndependentSecondStage<P>(pub P);

impl<S, P: Proposal<S>> ConditionalProposal<S> for IndependentSecondStage<P> {
    fn propose<R: Rng + ?Sized>(&self, x: &S, _y: &S, z: &mut S, rng: &mut R) -> Proposed {
        self.0.propose(x, z, rng)
    }

    fn log_q(&self, x: &S, _y: &S, z: &S) -> f64 {
        self.0.log_q(x, z)
    }
}

/// The Gaussian random walk on the unit torus: `y_i = wrap(x_i + sigma N(0, 1))`, with the
/// wrapped normal as its exact density (images `-3..=3`, exact to `1e-23` for
/// `sigma <= 1/4`). Symmetric. Only for states in `[0, 1)^n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrappedGaussianWalk {
    sigma: f64,
}

impl WrappedGaussianWalk {
    /// A walk with standard deviation `sigma` in `(0, 1/4]`.
    pub fn new(sigma: f64) -> Result<Self, McmcError> {
        McmcError::check_range("sigma", sigma, f64::MIN_POSITIVE, 0.25, "(0, 0.25]")?;
        Ok(Self { sigma })
    }

    /// The standard deviation per coordinate.
    #[must_use]
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
}

impl Proposal<Vec<f64>> for WrappedGaussianWalk {
    fn propose<R: Rng + ?Sized>(&self, x: &Vec<f64>, y: &mut Vec<f64>, rng: &mut R) -> Proposed {
        y.clear();
        y.extend(x.iter().map(|&v| {
            let n: f64 = StandardNormal.sample(rng);
            wrap(v + self.sigma * n)
        }));
        Proposed::symmetric()
    }

    fn log_q(&self, from: &Vec<f64>, to: &Vec<f64>) -> f64 {
        if from.len() != to.len() {
            return f64::NEG_INFINITY;
        }
        from.iter()
            .zip(to)
            .map(|(&a, &b)| wrapped_normal_pdf(wrap(b - a), 0.0, self.sigma).ln())
            .sum()
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constructors_validate() {
        assert!(WrappedGaussianWalk::new(0.3).is_err());
        assert!(WrappedGaussianWalk::new(0.0).is_err());
        assert_eq!(WrappedGaussianWalk::new(0.1).unwrap().sigma(), 0.1);
    }

    #[test]
    fn wrapped_walk_is_symmetric_across_the_seam() {
        let w = WrappedGaussianWalk::new(0.1).unwrap();
        let (a, b) = (vec![0.97, 0.5], vec![0.02, 0.45]);
        assert!((w.log_q(&a, &b) - w.log_q(&b, &a)).abs() < 1e-12);
        let i = IndependentSecondStage(w);
        assert_eq!(i.log_q(&a, &vec![0.3, 0.3], &b), w.log_q(&a, &b));
    }
}
